"""Compact frames (frame version 2, sans-I/O): only the joints a seat's renderer and glove layer read, and the
music row as a palette, inside the same 32-byte header as version 1 (docs/audience.md, "Compact frame").

    offset size  field
     0     32    the header of version 1 (wire.HEADER) with version 2: magic, version, kind, n_joints, n_music,
                 epoch, seq, media_t, wall_t
    32     12*n_joints   the description's ``frames.joints`` (n_joints, 3) float32 metres, in that order; NaN = not
                         tracked
    ...    music (n_music > 0):
             1          k, the palette's size: 1..255, or 0 for a raw row
             4*k        the palette: the row's distinct values, float32, ascending
             n_music    each actuator's palette index (u8)
           or, for k = 0, 4*n_music bytes: the row as float32

Why: the renderer reads 7 of the 32 joints (:data:`hapmotion.skeleton.joints.RENDER_JOINTS`, whatever the method,
preset or parameters) and a seat's glove layer 4 more (:data:`hapmotion.show.hands.GLOVE_JOINTS`), so the other 21
are 252 bytes a frame no seat uses; and a music row holds a few distinct
intensities (a song's bands spread over zones: at most 3 distinct values per row on the recordings here), so a
palette of float32 values and one byte per actuator carries the row exactly in about a quarter of its float32 size.
Whole percents (one byte per actuator, no palette) would be 13 bytes smaller but not exact: the seat mixes the music
before the Player rounds, and whole-percent music changed a Player percent on 13-25 % of frames of real
recordings. The seat decodes both versions; a compact frame's joints and music are the very float32 numbers a
version-1 frame carries, so a seat renders the same rows from either.

Packed frames (frame version 3, a ``nats://`` sink's ``frames=compact&pack=N``): the compact rows of up to N
consecutive rendered frames in one message, so a 60 fps show goes out at 30 messages a second (``pack=2``) and every
seat still renders each 60 fps frame exactly::

    offset size  field
     0     32    the header with version 3 (media_t: the first frame's; seq numbers the messages)
    32     1     c, the frames in this message: 1..N (fewer only when the run ends mid-message)
    33     ...   the first frame's joints and music, as in a compact frame
    ...    8     the next frame's media_t (float64, after the one before), then its joints and music; c frames

Why: a server's cost is per message, whatever its size (docs/audience.md, "Measured"), so 30 messages a second
carry the audience of a 30 Hz stream; a 30 Hz stream interpolated by a cubic missed the 60 Hz render's side on fast
dance (:mod:`hapmotion.audience.interpolation`). Each frame carries its media time because a live show's frames are
not always one render interval apart.
"""

from __future__ import annotations

import math
import struct
from typing import Callable, Optional, Sequence

import numpy as np

from ..show.hands import GLOVE_JOINTS
from ..skeleton.joints import JOINT_INDEX, JOINTS, RENDER_JOINTS
from .wire import (HEADER, KIND_FRAME, MAGIC, MAX_MEDIA_T, MAX_POSITION_M, N_JOINTS, WireFrame, decode_frame,
                   encode_frame, read_f32, read_header)

COMPACT = 2
"""The compact frame's version byte."""
PACKED = 3
"""The packed frame's version byte: compact frames of consecutive rendered frames in one message."""
FRAME_VERSIONS = {"full": 1, "compact": COMPACT}
"""The ``frames=`` choices of a ``nats://`` sink and the frame version each sends (``pack=`` makes compact frames
packed)."""
MAX_PALETTE = 255
PALETTE = struct.Struct("<B")
COUNT = struct.Struct("<B")
MEDIA_T = struct.Struct("<d")

RENDERER_JOINTS: tuple[str, ...] = tuple(j for j in JOINTS if j in RENDER_JOINTS)
"""The joints a seat's renderer reads, in canonical order: the kernel's joints (``RENDER_JOINTS``), the same for
every method, preset and parameter (``Renderer`` takes exactly these rows of a frame), so no seat setting can need
a joint a compact frame of these lacks. A description naming fewer is refused by the seat (``seat_show``)."""
SEAT_JOINTS: tuple[str, ...] = tuple(j for j in JOINTS if j in RENDER_JOINTS or j in GLOVE_JOINTS)
"""The joints a compact frame carries, in canonical order: the renderer's and those the glove layer of a seat
wearing gloves reads beyond them (:data:`~hapmotion.show.hands.GLOVE_JOINTS`: elbows and hand tips, 48 bytes)."""


def compact_joints() -> tuple[str, ...]:
    """The joints a compact frame carries (:data:`SEAT_JOINTS`)."""
    return SEAT_JOINTS


def missing_joints(frame_joints: Sequence[str], gloves: bool = False) -> list[str]:
    """The joints a seat's renderer reads (and, with ``gloves``, its glove layer) that frames of ``frame_joints``
    do not carry (empty: it can render)."""
    need = SEAT_JOINTS if gloves else RENDERER_JOINTS
    return [j for j in need if j not in frame_joints]


# ---------------------------------------------------------------------------------------------------- music
def encode_music(row: np.ndarray) -> bytes:
    """A music row ``(N,)`` 0..100 as a palette of its float32 values and one index byte per actuator (a raw
    float32 row when it has more than 255 distinct values)."""
    row32 = np.ascontiguousarray(row, dtype="<f4")
    values, index = np.unique(row32, return_inverse=True)
    if len(values) > MAX_PALETTE:
        return PALETTE.pack(0) + row32.tobytes()
    return PALETTE.pack(len(values)) + values.astype("<f4").tobytes() + index.astype(np.uint8).tobytes()


def _decode_music(data: bytes, offset: int, n_music: int) -> tuple[np.ndarray, int]:
    """The music row ``(N,)`` float64 from ``offset`` and the offset after it; ValueError on a bad palette."""
    if offset >= len(data):
        raise ValueError("no music palette size")
    (k,) = PALETTE.unpack_from(data, offset)
    offset += 1
    if k == 0:
        end = offset + 4 * n_music
        if end > len(data):
            raise ValueError("music row shorter than its actuator count")
        return read_f32(data, offset, n_music), end
    end = offset + 4 * k + n_music
    if end > len(data):
        raise ValueError(f"music palette of {k} values and {n_music} indices does not fit in the frame")
    values = read_f32(data, offset, k)
    index = np.frombuffer(data, dtype=np.uint8, count=n_music, offset=offset + 4 * k)
    if int(index.max()) >= k:
        raise ValueError(f"music palette index {int(index.max())} beyond its {k} values")
    return values[index], end


def _decode_rows(data: bytes, offset: int, joint_rows: np.ndarray, n_j: int,
                 n_m: int) -> tuple[Optional[np.ndarray], Optional[np.ndarray], int]:
    """One frame's (skeleton ``(32, 3)`` or None, music ``(N,)`` or None, offset after them) from ``offset``."""
    start = offset
    offset = start + 12 * n_j
    if offset > len(data):
        raise ValueError(f"{len(data)} bytes, too short for {n_j} joints")
    skeleton = None
    if n_j:
        xyz = read_f32(data, start, 3 * n_j).reshape(n_j, 3)
        if np.isinf(xyz).any() or (np.abs(np.nan_to_num(xyz)) > MAX_POSITION_M).any():
            raise ValueError(f"joint positions infinite or beyond {MAX_POSITION_M:g} m")
        skeleton = np.full((N_JOINTS, 3), np.nan)
        skeleton[joint_rows] = xyz
    music = None
    if n_m:
        music, offset = _decode_music(data, offset, n_m)
        if not (np.isfinite(music).all() and music.min() >= 0.0 and music.max() <= 100.0):
            raise ValueError("music values outside 0..100")
    return skeleton, music, offset


# ---------------------------------------------------------------------------------------------------- frames
def encode_compact_frame(epoch: int, seq: int, media_t: float, wall_t: float, joints: Optional[np.ndarray],
                         music: Optional[np.ndarray]) -> bytes:
    """The bytes of one compact frame; ``joints`` ``(J, 3)`` metres (the description's ``frames.joints``, in
    order) or None (music only), ``music`` ``(N,)`` 0..100 or None."""
    n_j = 0 if joints is None else int(np.shape(joints)[0])
    n_m = 0 if music is None else int(np.shape(music)[0])
    parts = [HEADER.pack(MAGIC, COMPACT, KIND_FRAME, n_j, n_m, epoch & 0xFFFFFFFF, seq & 0xFFFFFFFF,
                         float(media_t), float(wall_t))]
    if joints is not None:
        parts.append(np.ascontiguousarray(joints, dtype="<f4").tobytes())
    if music is not None:
        parts.append(encode_music(music))
    return b"".join(parts)


def decode_compact_frame(data: bytes, joint_rows: np.ndarray, n_music: int) -> WireFrame:
    """Parse a compact frame whose joints are the canonical rows ``joint_rows`` ``(J,)``; the skeleton comes back
    as ``(32, 3)`` with NaN (not sent) in the other rows, as a seat's engine takes it. ValueError naming the
    field on anything that does not fit (callers count it as ``malformed``)."""
    epoch, seq, media_t, wall_t, n_j, n_m = read_header(data, COMPACT, len(joint_rows), n_music)
    skeleton, music, offset = _decode_rows(data, HEADER.size, joint_rows, n_j, n_m)
    if offset != len(data):
        raise ValueError(f"{len(data)} bytes, expected {offset} for {n_j} joints and {n_m} music values")
    return WireFrame(epoch, seq, media_t, wall_t, skeleton, music)


def frame_decoder(frame_version: int, frame_joints: Sequence[str], n_music: int) -> Callable[[bytes], WireFrame]:
    """The decoder of a show's frames: version 1 (every joint, float32 music) or compact frames of
    ``frame_joints``."""
    if frame_version == COMPACT:
        rows = np.array([JOINT_INDEX[j] for j in frame_joints], dtype=np.intp)
        return lambda data: decode_compact_frame(data, rows, n_music)
    return lambda data: decode_frame(data, n_music)


def frame_encoder(frame_version: int, frame_joints: Sequence[str]) -> Callable[..., bytes]:
    """``encode(epoch, seq, media_t, wall_t, skeleton (32, 3) or None, music or None)`` for a show's frames."""
    if frame_version != COMPACT:
        return encode_frame
    rows = np.array([JOINT_INDEX[j] for j in frame_joints], dtype=np.intp)

    def encode(epoch: int, seq: int, media_t: float, wall_t: float, skeleton: Optional[np.ndarray],
               music: Optional[np.ndarray]) -> bytes:
        return encode_compact_frame(epoch, seq, media_t, wall_t, None if skeleton is None else skeleton[rows],
                                    music)

    return encode


# ---------------------------------------------------------------------------------------------------- packed frames
def encode_packed_frame(epoch: int, seq: int, wall_t: float, times: Sequence[float],
                        joints: Sequence[Optional[np.ndarray]], music: Sequence[Optional[np.ndarray]]) -> bytes:
    """The bytes of one packed frame (version 3): consecutive rendered frames at media times ``times`` (1 to 255,
    ascending), each's ``joints`` ``(J, 3)`` metres or None and ``music`` ``(N,)`` 0..100 or None; every frame of
    a message has joints, or none has, and the same for music (the publisher sends a message early when that
    changes)."""
    n_j = 0 if joints[0] is None else int(np.shape(joints[0])[0])
    n_m = 0 if music[0] is None else int(np.shape(music[0])[0])
    parts = [HEADER.pack(MAGIC, PACKED, KIND_FRAME, n_j, n_m, epoch & 0xFFFFFFFF, seq & 0xFFFFFFFF,
                         float(times[0]), float(wall_t)), COUNT.pack(len(times))]
    for i, (t, xyz, row) in enumerate(zip(times, joints, music)):
        if i:
            parts.append(MEDIA_T.pack(float(t)))
        if n_j:
            parts.append(np.ascontiguousarray(xyz, dtype="<f4").tobytes())
        if n_m:
            parts.append(encode_music(row))
    return b"".join(parts)


def decode_packed_frame(data: bytes, joint_rows: np.ndarray, n_music: int, pack: int) -> list[WireFrame]:
    """The frames ``[WireFrame]`` (1 to ``pack``, the description's ``frames.pack``) of one packed frame, each
    skeleton ``(32, 3)`` with NaN in the rows not sent; ValueError naming the field on anything that does not fit
    (a count of 0 or beyond ``pack``, media times not ascending or finite, a short or long message)."""
    epoch, seq, media_t, wall_t, n_j, n_m = read_header(data, PACKED, len(joint_rows), n_music)
    if len(data) < HEADER.size + COUNT.size:
        raise ValueError(f"{len(data)} bytes, no frame count after the header")
    (count,) = COUNT.unpack_from(data, HEADER.size)
    if not 1 <= count <= pack:
        raise ValueError(f"{count} frames in a message, expected 1 to {pack} (the description's frames.pack)")
    offset, out, t = HEADER.size + COUNT.size, [], media_t
    for i in range(count):
        if i:
            if offset + MEDIA_T.size > len(data):
                raise ValueError(f"{len(data)} bytes, too short for frame {i + 1} of {count}")
            (next_t,) = MEDIA_T.unpack_from(data, offset)
            offset += MEDIA_T.size
            if not (math.isfinite(next_t) and abs(next_t) <= MAX_MEDIA_T and next_t > t):
                raise ValueError(f"media_t {next_t} of frame {i + 1}, expected finite seconds after {t}")
            t = next_t
        skeleton, music, offset = _decode_rows(data, offset, joint_rows, n_j, n_m)
        out.append(WireFrame(epoch, seq, t, wall_t, skeleton, music))
    if offset != len(data):
        raise ValueError(f"{len(data)} bytes, expected {offset} for {count} frames of {n_j} joints and {n_m} "
                         f"music values")
    return out


def message_decoder(frame_version: int, frame_joints: Sequence[str], n_music: int,
                    pack: int = 1) -> Callable[[bytes], list[WireFrame]]:
    """The decoder of a show's frame messages: the frames ``[WireFrame]`` each carries (one, or for packed frames
    up to ``pack``)."""
    if frame_version == PACKED:
        rows = np.array([JOINT_INDEX[j] for j in frame_joints], dtype=np.intp)
        return lambda data: decode_packed_frame(data, rows, n_music, pack)
    decode = frame_decoder(frame_version, frame_joints, n_music)
    return lambda data: [decode(data)]


def packed_encoder(frame_joints: Sequence[str]) -> Callable[..., bytes]:
    """``encode(epoch, seq, wall_t, times, skeletons [(32, 3) or None], music [(N,) or None])`` for packed
    frames of ``frame_joints``."""
    rows = np.array([JOINT_INDEX[j] for j in frame_joints], dtype=np.intp)

    def encode(epoch: int, seq: int, wall_t: float, times: Sequence[float],
               skeletons: Sequence[Optional[np.ndarray]], music: Sequence[Optional[np.ndarray]]) -> bytes:
        return encode_packed_frame(epoch, seq, wall_t, times, [None if s is None else s[rows] for s in skeletons],
                                   music)

    return encode

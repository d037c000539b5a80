"""A seat's frame path without a network, for the audience tests: the venue's frames of a real recording (and
song) encoded as the publisher encodes them, decoded, interpolated and rendered as a seat does (no tests here)."""

from __future__ import annotations

from typing import Optional

import numpy as np

from hapmotion.audience.compact import frame_encoder, message_decoder, packed_encoder
from hapmotion.audience.interpolation import Upsampler
from hapmotion.audience.listener import seat_show
from hapmotion.audience.publisher import describe_show
from hapmotion.audience.seat import Seat, SeatStage
from hapmotion.body.model import BodyModel
from hapmotion.show import Show, song_track
from hapmotion.show.stage import OutputStage


def venue_show(motion, song=None, *, frames: str = "full", rate: Optional[float] = None,
               method: str = "mst", mirror: bool = True, pack: Optional[int] = None):
    """(description, music rows ``(T, N)`` or None) of a venue replaying ``motion`` at its own rate with ``song``."""
    show = Show(method=method, audio=song, mirror=mirror)
    layout = show.load_layout()
    mode = "multimodal" if song is not None else "motion"
    stage = OutputStage.for_show(show, mode, layout=layout, fps=motion.fps)
    desc = describe_show("offline", show=show, stage=stage, layout=layout, body=BodyModel.from_motion(motion),
                         stall_ms=250.0, mirror=mirror, epoch=1, frames=frames, rate=rate,
                         pack=pack)
    music = None
    if song is not None:
        music = song_track(show, fps=motion.fps, layout=layout).intensities
        if music.shape[0] < motion.n_frames:
            music = np.vstack([music, np.zeros((motion.n_frames - music.shape[0], music.shape[1]))])
    return desc, music


def published(desc, motion, music) -> list[bytes]:
    """The frames the publisher sends for every rendered frame of ``motion`` (every ``fps / rate``-th one; packed:
    ``pack`` rendered frames a message, the last message fewer when the run ends mid-message)."""
    if desc.pack > 1:
        encode_packed, p = packed_encoder(desc.frame_joints), desc.pack
        return [encode_packed(desc.epoch, i // p, 1000.0 + i / motion.fps, [k / motion.fps for k in ks],
                              [motion.positions[k] for k in ks], [None if music is None else music[k] for k in ks])
                for i in range(0, motion.n_frames, p) for ks in [range(i, min(i + p, motion.n_frames))]]
    encode = frame_encoder(desc.frame_version, desc.frame_joints)
    every = int(round(desc.fps / desc.frame_rate))
    return [encode(desc.epoch, i // every, k / motion.fps, 1000.0 + k / motion.fps, motion.positions[k],
                   None if music is None else music[k])
            for i, k in enumerate(range(0, motion.n_frames)) if k % every == 0]


def seat_rows(desc, frames: list[bytes], seat: Seat = Seat()) -> tuple[np.ndarray, np.ndarray]:
    """(media times ``(F,)``, rows ``(F, N)``) a seat plays for ``frames``: decoded, interpolated to the render
    rate, rendered by the seat's renderer and output stage, zones applied, in the order the seat plays them."""
    parts = seat_show(desc, seat)
    zones = SeatStage(seat, parts.layout)
    decode = message_decoder(desc.frame_version, desc.frame_joints, len(desc.actuators), desc.pack)
    up = Upsampler(desc.fps, desc.frame_rate * desc.pack)
    times, rows = [], []
    played = [f for data in frames for c in decode(data) for f in up.feed(c)] + up.flush()
    for wf in played:
        if parts.music is not None:
            parts.music.put(wf.media_t, wf.music)
        incoming = parts.renderer.step(wf.skeleton) if parts.renderer is not None else None
        times.append(wf.media_t)
        rows.append(zones(parts.stage.step(incoming, wf.media_t, wf.skeleton)))
    return np.array(times), np.array(rows)

"""The one motion type every reader produces and every renderer consumes.

World convention for :attr:`Motion.positions`: metres, right-handed, **+Y up** (readers rotate camera frames such
as Azure Kinect's +Y-down frame into it). Horizontal axes are whatever the source used; the renderer never relies
on them because it works in the per-frame body frame (``hapmotion.body.frame``).
"""

from __future__ import annotations

import mmap
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np

from .errors import InputError
from .skeleton.joints import JOINT_INDEX, JOINTS, N_JOINTS, RENDER_JOINTS


@dataclass
class Motion:
    """A recorded or streamed skeleton on the canonical 32 Azure Kinect joints.

    Attributes
    ----------
    positions:
        ``(T, 32, 3)`` float64, metres, +Y up. Joints the source does not have and could not be derived are NaN in
        every frame (``present[j]`` is False); all present joints are finite in every frame (gaps are filled by
        :func:`fill_gaps`).
    fps:
        Frames per second (> 0).
    present:
        ``(32,)`` bool: the joint has data (read or derived).
    derived:
        ``(32,)`` bool: the joint was computed from others (e.g. SPINE_NAVEL for COCO-17), not read.
    confidence:
        ``(T, 32)`` float32 in 0..1: 1 = read with full confidence, 0.5 = derived or low-confidence, 0 = missing in
        the source and filled (held or interpolated). Absent joints are 0. When every frame has the same
        confidences (a file without any), a read-only view of one row.
    meta:
        Free-form facts for ``hapmotion info``: ``format``, ``skeleton``, ``path``, ``units``, ``source_joints``
        (canonical name -> source name), ``notes`` (list of strings: skipped T-pose frames, chosen body id, ...),
        ``filled_frames`` (count of joint-frames filled).
    """

    positions: np.ndarray
    fps: float
    present: np.ndarray
    derived: np.ndarray
    confidence: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    # ------------------------------------------------------------------ basic facts
    @property
    def n_frames(self) -> int:
        return int(self.positions.shape[0])

    @property
    def duration(self) -> float:
        """Seconds covered by the frames (``n_frames / fps``)."""
        return self.n_frames / self.fps

    @property
    def joint_names(self) -> tuple[str, ...]:
        return JOINTS

    def joint(self, name: str) -> np.ndarray:
        """``(T, 3)`` positions of one canonical joint (metres)."""
        return self.positions[:, JOINT_INDEX[name], :]

    @property
    def times(self) -> np.ndarray:
        """``(T,)`` seconds from the first frame."""
        return np.arange(self.n_frames, dtype=np.float64) / self.fps

    # ------------------------------------------------------------------ transforms
    def slice(self, start: int, stop: int | None = None) -> "Motion":
        """Frames ``start:stop`` as a new Motion (shares nothing with this one)."""
        return replace(
            self,
            positions=self.positions[start:stop].copy(),
            confidence=self.confidence[start:stop].copy(),
            meta=dict(self.meta),
        )

    def resample(self, fps: float) -> "Motion":
        """Linear resampling to a new frame rate; the first frame is kept, the duration is kept (floor).

        Returns ``self`` when the rate is unchanged.
        """
        if fps <= 0 or not np.isfinite(fps):
            raise ValueError(f"fps must be a positive number, got {fps}")
        if abs(fps - self.fps) < 1e-9:
            return self
        n_new = max(1, int(np.floor((self.n_frames - 1) * fps / self.fps + 1e-9)) + 1)
        t_new = np.arange(n_new) / fps
        t_old = self.times
        flat = self.positions.reshape(self.n_frames, -1)
        out = np.empty((n_new, flat.shape[1]))
        for k in range(flat.shape[1]):
            out[:, k] = np.interp(t_new, t_old, flat[:, k])
        conf = np.empty((n_new, N_JOINTS), dtype=np.float32)
        for j in range(N_JOINTS):
            conf[:, j] = np.interp(t_new, t_old, self.confidence[:, j])
        meta = dict(self.meta)
        meta.setdefault("notes", [])
        meta["notes"] = list(meta["notes"]) + [f"resampled from {self.fps:g} to {fps:g} fps"]
        return replace(self, positions=out.reshape(n_new, N_JOINTS, 3), fps=float(fps), confidence=conf, meta=meta)

    def render_joints_only(self, extra: Sequence[str] = (), let_go: bool = False) -> "Motion":
        """A copy holding only the joints the renderer reads (:data:`~hapmotion.skeleton.joints.RENDER_JOINTS`),
        for a caller that renders this motion and lets it go (``hapmotion render``): an hour at 120 fps then keeps
        72 MB of positions instead of 330 MB through rendering and the output stage.

        ``extra`` names more joints to keep. The copy's other joints are absent (``present`` and ``derived`` False,
        confidence 0) and read 0.0, not NaN: its arrays are joint-major (``positions`` is a ``(T, 32, 3)`` view of
        a ``(32, T, 3)`` array of zeros) and the memory of the joints never written is never allocated by the
        system. The render joints' values are this motion's, bit for bit, so the copy renders exactly as this
        motion does.

        ``let_go=True``: this motion is not used again (its positions then read 0.0 or anything). When its
        positions lie on their own memory map (:func:`new_positions`, as the BVH reader makes them), each block of
        frames goes back to the system once its joints are copied, so the copy never coexists with the whole
        motion: an hour at 120 fps peaks 72 MB lower. Elsewhere (Windows, another reader's array) it is the plain
        copy.
        """
        n = self.n_frames
        keep = np.zeros(N_JOINTS, dtype=bool)
        keep[[JOINT_INDEX[j] for j in (*RENDER_JOINTS, *extra)]] = True
        keep &= self.present
        positions = np.zeros((N_JOINTS, n, 3))  # calloc: pages of the joints left out are never touched
        confidence = np.zeros((N_JOINTS, n), dtype=np.float32)
        release = _page_release(self.positions) if let_go else None
        kept = np.flatnonzero(keep)
        for start in range(0, n, COPY_BLOCK):
            part = self.positions[start:start + COPY_BLOCK]
            for j in kept:
                positions[j, start:start + part.shape[0]] = part[:, j, :]
            if release is not None:
                release(start, start + part.shape[0])
        for j in kept:
            confidence[j] = self.confidence[:, j]
        return replace(self, positions=positions.transpose(1, 0, 2), present=keep, derived=self.derived & keep,
                       confidence=confidence.T, meta=dict(self.meta))

    def missing_render_joints(self) -> list[str]:
        """Names of the joints the renderer needs that this motion lacks."""
        return [j for j in RENDER_JOINTS if not self.present[JOINT_INDEX[j]]]


def new_motion(
    positions: np.ndarray,
    fps: float,
    *,
    source: str,
    valid: np.ndarray | None = None,
    derived: np.ndarray | None = None,
    confidence: np.ndarray | None = None,
    meta: dict[str, Any] | None = None,
    take: bool = False,
) -> Motion:
    """Build a validated :class:`Motion` from raw canonical positions; the readers' common exit.

    Parameters
    ----------
    positions:
        ``(T, 32, 3)`` metres, +Y up. Absent joints may hold anything (they are set to NaN).
    fps:
        Frame rate.
    source:
        File or stream name, for error messages.
    valid:
        ``(T, 32)`` bool, True where the value is a real observation. Non-finite values are always invalid.
        Default: all finite values are valid.
    derived:
        ``(32,)`` bool, joints computed by the reader.
    confidence:
        ``(T, 32)`` in 0..1 for the valid samples (default 1, or 0.5 for derived joints).
    take:
        ``positions`` (float64) is the reader's own array, filled in place and kept by the Motion instead of
        copied: an hour of 120 fps motion is 330 MB.

    A joint counts as present when it is valid in at least one frame. Invalid samples of present joints are filled
    (interpolated inside a gap, held at the ends) and counted in ``meta["filled_frames"]``.

    Raises :class:`InputError` for zero frames, a bad fps, a joint the renderer needs that is absent, or a
    frame whose render joints are all invalid throughout.
    """
    pos = np.asarray(positions, dtype=np.float64) if take else np.array(positions, dtype=np.float64, copy=True)
    if pos.ndim != 3 or pos.shape[1:] != (N_JOINTS, 3):
        raise InputError(source, None, f"expected positions of shape (T, {N_JOINTS}, 3), found {pos.shape}")
    n = pos.shape[0]
    if n == 0:
        raise InputError(source, None, "expected at least one frame, found 0")
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(source, "frame rate", f"expected a positive frame rate, found {fps}")
    # which joints are finite in some frame and in every frame, a block of frames at a time
    somewhere, everywhere = np.zeros(N_JOINTS, dtype=bool), np.ones(N_JOINTS, dtype=bool)
    for start in range(0, n, FINITE_BLOCK):
        block = _finite_frames(pos[start:start + FINITE_BLOCK])
        somewhere |= block.any(axis=0)
        everywhere &= block.all(axis=0)
    if valid is None and confidence is None and (everywhere | ~somewhere).all():
        # each joint is finite in every frame or in none (a BVH file): the (T, 32) masks below would say nothing
        # more, and are not made (14 MB for an hour at 120 fps)
        present, ok = somewhere, None
    else:
        finite = np.empty((n, N_JOINTS), dtype=bool)
        for start in range(0, n, FINITE_BLOCK):
            finite[start:start + FINITE_BLOCK] = _finite_frames(pos[start:start + FINITE_BLOCK])
        ok = finite if valid is None else (np.asarray(valid, dtype=bool) & finite)
        present = ok.any(axis=0)
    der = np.zeros(N_JOINTS, dtype=bool) if derived is None else np.asarray(derived, dtype=bool).copy()
    if confidence is None and (ok is None or ok[:, present].all()):
        # every frame has the same confidences (a BVH file): one row, repeated by a read-only view
        row = np.where(present, np.where(der, 0.5, 1.0), 0.0).astype(np.float32)
        conf = np.broadcast_to(row, (n, N_JOINTS))
    else:
        if confidence is None:
            conf = np.where(der[None, :], 0.5, 1.0).astype(np.float32) * np.ones((n, 1), dtype=np.float32)
        else:
            conf = np.clip(np.asarray(confidence, dtype=np.float32), 0.0, 1.0).copy()
        conf[~ok] = 0.0
        conf[:, ~present] = 0.0
    filled = fill_gaps(pos, ok, present) if ok is not None else 0
    pos[:, ~present, :] = np.nan
    der &= present
    meta = dict(meta or {})
    meta.setdefault("path", source)
    meta.setdefault("notes", [])
    meta["filled_frames"] = int(filled)
    meta["filled_by_joint"] = {} if ok is None else {
        JOINTS[j]: int((~ok[:, j]).sum()) for j in range(N_JOINTS) if present[j] and (~ok[:, j]).any()}
    motion = Motion(positions=pos, fps=float(fps), present=present, derived=der, confidence=conf, meta=meta)
    missing = motion.missing_render_joints()
    if missing:
        names = meta.get("source_joints_available")
        shown = ", ".join(str(n)[:30] for n in names[:12]) if names else ""
        more = f" and {len(names) - 12} more" if names and len(names) > 12 else ""
        hint = f" (the file has: {shown}{more})" if names else ""
        raise InputError(
            source,
            "joints " + ", ".join(missing),
            f"expected hands, shoulders, spine, pelvis and neck (read or derivable), found none for these{hint}",
        )
    return motion


FINITE_BLOCK = 8192
"""Frames :func:`new_motion` checks for finite values at a time (its temporaries: 2 MB)."""


def _finite_frames(block: np.ndarray) -> np.ndarray:
    """``(k, 32)`` bool: which joints of ``block`` (``(k, 32, 3)``) are finite in each frame."""
    # x * 0 is 0 for every finite x and NaN for NaN and inf: a joint is finite where the three sum to 0. Five
    # times faster than isfinite(...).all(axis=2) over the axis of 3, and no (k, 32, 3) temporary
    with np.errstate(invalid="ignore"):  # inf * 0 is the NaN looked for, not a warning for the reader's notes
        zero = block[:, :, 0] * 0.0
        zero += block[:, :, 1] * 0.0
        zero += block[:, :, 2] * 0.0
    return zero == 0.0

COPY_BLOCK = 16384
"""Frames :meth:`Motion.render_joints_only` copies at a time: with ``let_go``, the 12 MB of the whole motion's
frames it gives back after each block bound how far the copy runs ahead of the memory returned."""


CAN_RELEASE_PAGES = all(hasattr(mmap, name) for name in ("MADV_DONTNEED", "MAP_PRIVATE", "MAP_ANONYMOUS")) \
    and hasattr(mmap.mmap, "madvise")
"""Whether memory-map pages can be given back before the map is closed (Linux, macOS; not Windows)."""


def new_positions(n_frames: int, fill: float = np.nan) -> np.ndarray:
    """A ``(n_frames, 32, 3)`` float64 array filled with ``fill``, on a private anonymous memory map of its own (of
    the standard library's :mod:`mmap`) rather than the allocator's heap, so that
    :meth:`Motion.render_joints_only` with ``let_go`` can give its pages back to the system a block of frames at a
    time. A reader that fills a whole recording (the BVH reader) allocates with this. Where pages cannot be given
    back (no ``madvise``: Windows) it is an ordinary array."""
    nbytes = n_frames * N_JOINTS * 3 * 8
    if nbytes == 0 or not CAN_RELEASE_PAGES:
        return np.full((n_frames, N_JOINTS, 3), fill)
    # private: a shared map (mmap's default) would be shared memory, which MADV_DONTNEED does not free
    pages = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    positions = np.frombuffer(pages, dtype=np.float64).reshape(n_frames, N_JOINTS, 3)
    positions.fill(fill)
    return positions


def _page_release(positions: np.ndarray):
    """``release(start, stop)``: give the whole memory pages of ``positions[start:stop]`` back to the system
    (they then read 0.0 on Linux), or None when ``positions`` is not a C-ordered view of a memory map that can
    (not made by :func:`new_positions`, or no ``madvise``: Windows)."""
    base = positions
    while isinstance(base, (np.ndarray, memoryview)):
        base = base.base if isinstance(base, np.ndarray) else base.obj
    if not CAN_RELEASE_PAGES or not isinstance(base, mmap.mmap) or not positions.flags.c_contiguous:
        return None
    origin = np.frombuffer(base, dtype=np.uint8).__array_interface__["data"][0]
    offset = positions.__array_interface__["data"][0] - origin
    row, page = positions.strides[0], mmap.PAGESIZE

    def release(start: int, stop: int) -> None:
        lo = -(-(offset + start * row) // page) * page  # whole pages only: the frames either side stay intact
        hi = (offset + stop * row) // page * page
        if hi > lo:
            base.madvise(mmap.MADV_DONTNEED, lo, hi - lo)

    return release


def fill_gaps(pos: np.ndarray, ok: np.ndarray, present: np.ndarray) -> int:
    """Fill invalid samples of present joints in place: linear interpolation inside a gap, hold at the ends.

    ``pos`` is ``(T, J, 3)``, ``ok`` ``(T, J)`` bool, ``present`` ``(J,)`` bool. Returns the number of joint-frames
    filled.
    """
    n = pos.shape[0]
    t = np.arange(n)
    count = 0
    for j in np.flatnonzero(present):
        good = ok[:, j]
        if good.all():
            continue
        bad = ~good
        count += int(bad.sum())
        for k in range(3):
            # np.interp holds the end values outside the known range: exactly "hold at the ends".
            pos[bad, j, k] = np.interp(t[bad], t[good], pos[good, j, k])
    return count

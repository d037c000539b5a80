"""How ``render`` hands data to its kernel and back: the joints read straight from the motion's own array (any memory
layout, writable or read-only, through one compiled signature), the body sized from it in place, and the rows' range
checked by the kernel as it writes them. The bytes are those of the gathered path (tests/support/previous_render.py) on every real
recording, and a NaN or an out-of-range value still never reaches a track."""

from __future__ import annotations

import numpy as np
import pytest

import hapmotion
from hapmotion.body.frame import DEFAULT_AXES
from hapmotion.body.model import BodyModel
from hapmotion.body.sizing_compiled import SIZING_JOINTS, body_samples
from hapmotion.errors import UsageError
from hapmotion.motion import Motion
from hapmotion.renderer import packed, renderer as renderer_module
from hapmotion.renderer.kernel import render_frames, row_in_range
from hapmotion.renderer.params import get_preset
from hapmotion.renderer.renderer import MAX_RENDER_FPS, pack_params
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from hapmotion.track import HapticTrack
from support.data import MOTION
from support.previous_render import render_gathered
from support.previous_show import body_from_motion
from support.synthetic import motion_from_frames, waving

REAL = sorted(MOTION.glob("*.bvh")) + [MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl"]


def same(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def with_positions(motion: Motion, positions: np.ndarray) -> Motion:
    return Motion(positions=positions, fps=motion.fps, present=motion.present, derived=motion.derived,
                  confidence=motion.confidence, meta=dict(motion.meta))


def layouts(motion: Motion) -> dict[str, Motion]:
    """``motion`` with the same positions in every memory layout ``render`` may be given."""
    pos = motion.positions
    read_only = pos.copy()
    read_only.flags.writeable = False
    joint_major = np.ascontiguousarray(pos.transpose(1, 0, 2)).transpose(1, 0, 2)
    padded = np.zeros(pos.shape[:2] + (4,))
    padded[:, :, :3] = pos
    return {"frame-major": motion, "joint-major": with_positions(motion, joint_major),
            "Fortran": with_positions(motion, np.asfortranarray(pos)), "read-only": with_positions(motion, read_only),
            "strided": with_positions(motion, padded[:, :, :3]),
            "render joints only": motion.render_joints_only()}


@pytest.mark.parametrize("path", REAL, ids=lambda p: p.name)
def test_render_reads_the_motion_in_place_with_the_bytes_of_the_gathered_path(path):
    motion = hapmotion.load_motion(path)
    for method, preset in (("mst", "felt"), ("mst", "paper"), ("baseline", "paper")):
        want = render_gathered(motion, method, preset)
        for name, m in layouts(motion).items():
            got = hapmotion.render(m, method=method, preset=preset)
            assert same(got.intensities, want.intensities), (name, method, preset)
            for key in want.debug:
                assert same(got.debug[key], want.debug[key]), (name, method, preset, key)
            assert got.meta["body"] == want.meta["body"], name
    assert BodyModel.from_motion(motion) == body_from_motion(motion)


def test_every_layout_renders_as_stepping_frame_by_frame_and_in_chunks():
    frames = np.concatenate([waving(n=120, hand="HAND_LEFT", freq=2.0), waving(n=120, hand="HAND_RIGHT")])
    frames[40:43, JOINT_INDEX["NECK"]] = np.nan  # not received: held by the kernel
    motion = motion_from_frames(frames)
    motion.positions[40:43, JOINT_INDEX["NECK"]] = np.nan
    body = BodyModel.from_motion(motion)
    stepper = hapmotion.Renderer(fps=motion.fps, body=body)
    stepped = np.array([stepper.step(f) for f in motion.positions])
    for name, m in layouts(motion).items():
        whole = hapmotion.render(m, body=body)
        chunked = hapmotion.render(m, body=body, chunk=7)  # chunks end inside the held frames
        assert same(whole.intensities, stepped) and same(chunked.intensities, stepped), name
        assert BodyModel.from_motion(m) == body, name
    assert stepped.max() > 0  # the comparison has something to compare


def test_the_kernel_reports_whether_every_row_it_wrote_is_within_0_to_100():
    for row, ok in (([0.0, 50.0, 100.0], True), ([-0.0, 100.0], True), ([np.nan, 1.0], False),
                    ([1.0, np.inf], False), ([-1e-300], False), ([np.nextafter(100.0, 200.0)], False), ([], True)):
        assert row_in_range(np.array(row, dtype=np.float64)) is ok, row
    motion = motion_from_frames(waving(n=60))
    layout = hapmotion.load_layout()
    n, n_act = motion.n_frames, layout.n_actuators
    rows = np.array([JOINT_INDEX[j] for j in RENDER_JOINTS], dtype=np.intp)
    for pct, want in ((get_preset("paper").percent_per_level, True), (np.nan, False)):
        prm = pack_params(get_preset("paper"), "mst", motion.fps)
        prm[packed.P_PCT] = pct  # NaN percent per level: NaN motor drives (no parameter set can ask for this)
        out = np.zeros((n, n_act))
        got = render_frames(motion.positions, rows, prm, BodyModel.from_motion(motion).as_array(),
                            layout.chart_table(), np.arange(n_act), packed.new_state(n_act), out,
                            np.zeros((n, packed.N_DEBUG_F)), np.zeros((n, packed.N_DEBUG_I), dtype=np.int8))
        assert got is want and bool(np.isnan(out).any()) is not want


def test_a_nan_the_kernel_writes_never_reaches_a_track(monkeypatch):
    """If the kernel ever wrote a NaN, ``render`` would not take its rows as they are: the track's own check refuses
    them, as it refused any NaN before the kernel checked the range."""
    pack = renderer_module.pack_params

    def nan_levels(*args, **kwargs):
        prm = pack(*args, **kwargs)
        prm[packed.P_PCT] = np.nan
        return prm

    monkeypatch.setattr(renderer_module, "pack_params", nan_levels)
    with pytest.raises(ValueError, match="finite"):
        hapmotion.render(motion_from_frames(waving(n=60)), preset="paper")


def test_wild_coordinates_render_finite_rows_or_are_refused():
    """Finite but absurd positions (a forged file's 1e300 metres) never give a track a NaN or a value outside
    0..100."""
    for scale in (1e150, 1e300):
        frames = waving(n=60) * scale
        try:
            with np.errstate(invalid="ignore", over="ignore"):  # 1e300 m shoulders measure an infinite body
                track = hapmotion.render(motion_from_frames(frames))
        except ValueError as e:
            assert "finite" in str(e)
            continue
        rows = track.intensities
        assert np.isfinite(rows).all() and rows.min() >= 0.0 and rows.max() <= 100.0


def test_a_track_of_rows_in_range_is_kept_and_everything_else_still_checked():
    ids = hapmotion.load_layout().actuators
    rows = np.linspace(0.0, 100.0, 3 * len(ids)).reshape(3, len(ids))
    track = HapticTrack.of_rows_in_range(rows, 60, ids, meta={"a": 1})
    assert track.intensities is rows and track.fps == 60.0 and track.actuators == tuple(ids)
    assert track.meta == {"a": 1} and track.debug == {} and track.layout == "x40_shoulders"
    as_floats = HapticTrack.of_rows_in_range(np.full((2, len(ids)), 150, dtype=np.int64), 60.0, ids)
    assert same(as_floats.intensities, np.full((2, len(ids)), 100.0))  # not float64: converted and clipped
    with pytest.raises(ValueError, match=r"\(T, 52\)"):
        HapticTrack.of_rows_in_range(rows[:, :5], 60.0, ids)
    with pytest.raises(ValueError, match="fps"):
        HapticTrack.of_rows_in_range(rows, 0.0, ids)


@pytest.mark.parametrize("clip", ["01_01.bvh", "dataset-1_dance-short_normal_001.bvh"])
def test_without_debug_values_the_rows_are_the_same(clip):
    """``render(debug=False)`` (``hapmotion render`` to .tact) has the kernel overwrite one row of debug values:
    the same rows, in one chunk or several, and a show's rows through the stage too."""
    from hapmotion.show import render_show
    from hapmotion.show.settings import Show

    motion = hapmotion.load_motion(MOTION / clip)
    want = hapmotion.render(motion)
    for chunk in (100_000, 333):
        got = hapmotion.render(motion, debug=False, chunk=chunk)
        assert same(got.intensities, want.intensities) and got.debug == {} and got.meta == want.meta, chunk
    show = Show()
    assert same(render_show(show, motion, debug=False).intensities, render_show(show, motion).intensities)


def test_positions_of_any_number_type_or_byte_order_render_as_float64():
    # the compiled passes take native float64 only: float32, integer and big-endian positions are converted first,
    # so they render as the same values in float64 do
    motion = motion_from_frames(waving(90))
    for positions in (motion.positions.astype(np.float32), np.round(motion.positions * 1000).astype(np.int64),
                      motion.positions.astype(">f8")):
        want = hapmotion.render(with_positions(motion, positions.astype(np.float64)), preset="felt")
        got = hapmotion.render(with_positions(motion, positions), preset="felt")
        assert same(got.intensities, want.intensities), positions.dtype
        assert BodyModel.from_motion(with_positions(motion, positions)) == \
            BodyModel.from_motion(with_positions(motion, positions.astype(np.float64)))


def test_positions_without_the_canonical_rows_are_refused_not_read_past():
    # the kernel and the body sizing read rows 0..31 and 3 coordinates without bounds checks: a motion of another
    # shape must be refused before them, never read past its end
    motion = motion_from_frames(waving(30))
    for positions in (motion.positions[:, :5], motion.positions[:, :, :2], motion.positions[:, :, 0]):
        with pytest.raises(ValueError, match=r"must be \(T, 32, 3\)"):
            hapmotion.render(with_positions(motion, positions))
    with pytest.raises(ValueError, match="joints: no row"):
        BodyModel.from_positions(motion.positions[:, :5], JOINT_INDEX)
    with pytest.raises(ValueError, match=r"must be \(T, J, 3\)"):
        BodyModel.from_positions(motion.positions[:, :, :2], JOINT_INDEX)
    for chunk in (0, -5):  # a negative chunk rendered no frame at all: a silent track
        with pytest.raises(ValueError, match="chunk must be at least 1"):
            hapmotion.render(motion, chunk=chunk)


@pytest.mark.parametrize("preset", ["felt", "paper"])
def test_one_frame_of_an_absurd_joint_is_held_over_not_felt_to_the_end(preset):
    """A joint 1e155 m away (or more) for one frame is taken as not received: the renderer's squared speeds stay
    finite, and two seconds later the rows are those of the motion without the glitch to 0.01 % (the joint held for
    a frame, then back, passes through the filters and fades); they went silent for good."""
    frames = waving(n=600)
    want = hapmotion.render(motion_from_frames(frames), preset=preset).intensities
    for joint in ("HAND_LEFT", "HAND_RIGHT", "PELVIS"):
        for value in (1e155, -1e300, 2e4):
            glitched = frames.copy()
            glitched[120, JOINT_INDEX[joint]] = value
            track = hapmotion.render(with_positions(motion_from_frames(frames), glitched), preset=preset)
            assert np.abs(track.intensities[240:] - want[240:]).max() < 0.01, (joint, value)
    r = renderer_module.Renderer("mst", preset, fps=60.0)
    for t, frame in enumerate(frames[:200]):
        r.step(frame if t != 120 else np.full((32, 3), 1e300))
    assert np.isfinite(r._state).all()


def test_the_kernel_refuses_arrays_it_would_read_or_write_past():
    """numba checks no index, and the loop's views are borrowed: the kernel checks every array against the positions
    once per call, so that a caller's mistake is a ValueError, never a read or write past an array."""
    motion = motion_from_frames(waving(n=20))
    layout = hapmotion.load_layout()
    n, n_act = motion.n_frames, layout.n_actuators
    prm = pack_params(get_preset("felt"), "mst", motion.fps)

    def call(positions=motion.positions, rows=np.array([JOINT_INDEX[j] for j in RENDER_JOINTS], dtype=np.intp),
             state=None, out=None, dbg_f=None, dbg_i=None, mirror=None, params=prm):
        return render_frames(positions, rows, params, BodyModel.from_motion(motion).as_array(), layout.chart_table(),
                             np.arange(n_act) if mirror is None else mirror,
                             packed.new_state(n_act) if state is None else state,
                             np.zeros((n, n_act)) if out is None else out,
                             np.zeros((n, packed.N_DEBUG_F)) if dbg_f is None else dbg_f,
                             np.zeros((n, packed.N_DEBUG_I), dtype=np.int8) if dbg_i is None else dbg_i)

    assert call() is True
    assert call(dbg_f=np.zeros((1, packed.N_DEBUG_F)), dbg_i=np.zeros((1, packed.N_DEBUG_I), dtype=np.int8))
    wrong = {
        "rows past the joints": dict(positions=np.ascontiguousarray(motion.positions[:, :5])),
        "two coordinates": dict(positions=np.ascontiguousarray(motion.positions[:, :, :2])),
        "a negative row": dict(rows=np.array([-1, 0, 1, 2, 3, 4, 5], dtype=np.intp)),
        "too few rows": dict(rows=np.arange(3, dtype=np.intp)),
        "fewer output rows": dict(out=np.zeros((n - 1, n_act))),
        "no debug row": dict(dbg_f=np.zeros((0, packed.N_DEBUG_F)), dbg_i=np.zeros((0, packed.N_DEBUG_I), np.int8)),
        "narrow debug": dict(dbg_f=np.zeros((n, 2))),
        "a short state": dict(state=packed.new_state(n_act)[:-1].copy()),
        "a mirror map past the motors": dict(mirror=np.r_[np.arange(n_act - 1), n_act]),
        "short parameters": dict(params=prm[:3].copy()),
    }
    for name, kwargs in wrong.items():
        with pytest.raises(ValueError, match="does not fit"):  # `name` says which, in the failure's locals
            call(**kwargs)


def test_the_body_sizing_pass_refuses_arrays_it_would_read_or_write_past():
    positions = motion_from_frames(waving(n=20)).positions
    rows = np.array([JOINT_INDEX[j] for j in SIZING_JOINTS], dtype=np.intp)
    n = len(positions)
    body_samples(positions, rows, DEFAULT_AXES, np.empty(n), np.empty(n), np.empty(n))
    for args in ((positions[:, :5], rows, np.empty(n)), (positions[:, :, :2], rows, np.empty(n)),
                 (positions, rows[:3].copy(), np.empty(n)), (positions, rows - 1, np.empty(n)),
                 (positions, rows, np.empty(n - 1))):
        p, r, width = args
        with pytest.raises(ValueError, match="does not fit"):
            body_samples(np.ascontiguousarray(p), r, DEFAULT_AXES, width, np.empty(n), np.empty(n))


def test_a_frame_rate_past_the_loops_range_is_refused_not_rendered_as_nan():
    """At 1e300 fps a frame's motion times the rate, twice, overflowed: the rows were silent and the debug values
    NaN. Rates up to MAX_RENDER_FPS render finite values; past it, a one-line UsageError."""
    for fps in (MAX_RENDER_FPS, 2000.0):
        track = hapmotion.render(motion_from_frames(waving(n=60), fps=fps))
        assert all(np.isfinite(v).all() for v in track.debug.values()) and np.isfinite(track.intensities).all()
    for fps in (MAX_RENDER_FPS * 1.01, 1e300):
        fast = motion_from_frames(waving(n=60), fps=fps)
        with pytest.raises(UsageError, match="fps must be a positive number up to 1e"):
            hapmotion.render(fast)

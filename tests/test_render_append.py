"""The paper's "append" read as accumulating weights (``weight_window_s``, on in ``paper``), the moving-hand gate
outside the speed term (``active_speed_mps``) and two hands that carry weight kept one triangle (``two_active``):
worked by hand, and the steadier ``energy`` configuration of docs/algorithm.md on a real recording."""

from __future__ import annotations

import numpy as np
import pytest
from support.data import MOTION
from support.synthetic import motion_from_frames, pose, waving

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.renderer.packed import CHOICE_BOTH, CHOICE_LEFT, CHOICE_NONE, CHOICE_RIGHT, new_state
from hapmotion.renderer.params import PAPER_VARIANTS, PRESETS
from hapmotion.renderer.steps.choice import appended_weights, choose_weighted
from hapmotion.skeleton.joints import JOINT_INDEX

STEADY_ENERGY = PRESETS["energy"]
"""``energy``, whose steps make its MST steadier than its baseline (docs/algorithm.md)."""


def run_appends(frames, n):
    """Feed ``(above_left, above_right, excess_left, excess_right, far_left)`` rows through
    :func:`appended_weights`; each frame's ``(held, w_excess)``."""
    state = new_state(52)
    out = []
    for al, ar, el, er, far_left in frames:
        held, w = np.zeros(2, dtype=np.bool_), np.zeros(2)
        appended_weights(state, np.array([al, ar]), np.array([el, er]), n, far_left, held, w)
        out.append((tuple(bool(h) for h in held), tuple(float(x) for x in w)))
    return out


def test_weights_accumulate_over_the_window_and_leave_it():
    """The left hand is above on frames 0 and 1 (excess 0.5, 0.25), then not: with a three-frame window its extra
    weight is 0.5, 0.75, 0.25, then 0; it stays active until the last appended value has left the window."""
    rows = [(True, False, 0.5, 0.0, True), (True, False, 0.25, 0.0, True)] + [(False, False, 0.0, 0.0, True)] * 3
    got = run_appends(rows, 3)
    assert [g[0][0] for g in got] == [True, True, True, True, False]
    assert [g[1][0] for g in got] == pytest.approx([0.5, 0.75, 0.75, 0.25, 0.0])
    assert all(g[0][1] is False and g[1][1] == 0.0 for g in got)
    one = run_appends(rows, 1)  # the per-frame reading: this frame's value alone
    assert [g[0][0] for g in one] == [True, True, False, False, False]
    assert [g[1][0] for g in one] == [0.5, 0.25, 0.0, 0.0, 0.0]


def test_two_active_hands_append_only_to_the_farther_one():
    """Both above: the weight goes to the hand farther from the dynamic point; the other stays active but gains
    nothing (Section 4.2.2: "we distribute the weight value ... to the joint which records a higher distance")."""
    got = run_appends([(True, True, 0.4, 0.9, True), (True, True, 0.4, 0.9, False)], 3)
    assert got[0][0] == (True, True) and got[0][1] == pytest.approx((0.4, 0.0))
    assert got[1][0] == (True, True) and got[1][1] == pytest.approx((0.4, 0.9))


def test_two_active_joints_only_from_the_current_frame_unless_held():
    above, held = np.array([True, False]), np.array([True, True])
    assert choose_weighted(np.array([True, True]), held, np.zeros(2), 0.3, 0.5, CHOICE_NONE, True, False) == CHOICE_BOTH
    # both carry weight, only the left is above now: the left (paper); both, with two_active = "held"
    assert choose_weighted(above, held, np.array([0.1, 2.0]), 0.3, 0.5, CHOICE_NONE, True, False) == CHOICE_LEFT
    assert choose_weighted(above, held, np.array([0.1, 2.0]), 0.3, 0.5, CHOICE_NONE, True, True) == CHOICE_BOTH
    # neither above now: the one carrying more weight
    none = np.array([False, False])
    assert choose_weighted(none, held, np.array([0.1, 2.0]), 0.3, 0.5, CHOICE_NONE, True, False) == CHOICE_RIGHT
    # only one carries weight: that one; none: the idle rule (farther hand, or the last choice)
    assert choose_weighted(none, np.array([False, True]), np.zeros(2), 0.9, 0.5, CHOICE_LEFT, True,
                           False) == CHOICE_RIGHT
    assert choose_weighted(none, none, np.zeros(2), 0.9, 0.5, CHOICE_RIGHT, True, False) == CHOICE_LEFT
    assert choose_weighted(none, none, np.zeros(2), 0.9, 0.5, CHOICE_RIGHT, False, False) == CHOICE_RIGHT


def jerk_frames(n=40, at=20):
    """Both hands still at the sides, then the left hand jumps 4 cm outwards at frame ``at`` (one acceleration
    spike, then still again): ``(n, 32, 3)``."""
    frames = np.repeat(pose(HAND_LEFT=(0.6, 1.4, 0.2), HAND_RIGHT=(-0.4, 1.3, 0.2))[None], n, axis=0)
    frames[at:, JOINT_INDEX["HAND_LEFT"], 0] += 0.04
    return frames


def test_paper_keeps_a_jerked_hand_weighted_for_three_frames_at_60_hz():
    """The step puts the left hand above its threshold on frames 20 and 21 (its second difference spikes twice);
    with the paper's three-frame window its appended weight (capped at 1 + 2) lasts until frame 23, the last frame
    whose window holds frame 21, and the dynamic point stays pulled towards it; per frame (the earlier reading)
    the weight is back to 1 on frame 22."""
    frames = jerk_frames()
    motion = motion_from_frames(frames, fps=60.0)
    literal = PRESETS["paper"].replace(**PAPER_VARIANTS["literal"])  # Eq. 1's point, without the hold and glide
    acc = hapmotion.render(motion, params=literal).debug["dynamic_point"]
    per_frame = hapmotion.render(motion, params=literal.replace(**PAPER_VARIANTS["frame-weights"]))
    hl, sr, jt = (frames[25, JOINT_INDEX[k]] for k in ("HAND_LEFT", "SHOULDER_RIGHT", "SPINE_NAVEL"))
    for t in (20, 21, 22, 23):
        np.testing.assert_allclose(acc[t], (3 * hl + sr + jt) / 5, atol=1e-9)
    np.testing.assert_allclose(acc[24], (hl + sr + jt) / 3, atol=1e-9)
    np.testing.assert_allclose(per_frame.debug["dynamic_point"][21], (3 * hl + sr + jt) / 5, atol=1e-9)
    np.testing.assert_allclose(per_frame.debug["dynamic_point"][22], (hl + sr + jt) / 3, atol=1e-9)


def test_energy_never_takes_a_still_hand_as_active():
    """A still right hand with 0.3 mm capture noise at 120 Hz exceeds the acceleration floor (about 10 m/s^2 of
    noise) but not the moving-hand gate (about 0.1 m/s); the waving left hand is the only active joint in ``energy``, while without the gate the right one is
    chosen on some frames."""
    rng = np.random.default_rng(4)
    t = np.arange(480) / 120.0
    frames = np.repeat(pose()[None], t.size, axis=0)
    frames[:, JOINT_INDEX["HAND_LEFT"]] = np.stack([0.45 + 0.2 * np.sin(2 * np.pi * t), 1.5 + 0 * t, 0.2 + 0 * t], 1)
    frames[:, JOINT_INDEX["HAND_RIGHT"]] += rng.normal(0, 0.0003, (t.size, 3))
    motion = motion_from_frames(frames, fps=120.0)
    gated = hapmotion.render(motion, params=STEADY_ENERGY).debug["active"]
    open_ = hapmotion.render(motion, params=STEADY_ENERGY.replace(active_speed_mps=0.0)).debug["active"]
    assert gated[:, 1].sum() == 0 and gated[60:, 0].all()
    assert open_[:, 1].sum() > 0


def test_steady_energy_mst_is_steadier_than_its_baseline_on_a_salsa_recording():
    """CMU 60_12 (salsa, both hands moving): with the steadier ``energy`` configuration the felt locus (intensity-weighted centroid of the
    motors) of MST moves slower and jitters less than the baseline's, and the rendered hand changes under once a
    second (the ``energy`` preset: about 11 changes a second)."""
    motion = hapmotion.load_motion(MOTION / "60_12_scaled.bvh")
    pos = hapmotion.load_layout().positions()

    def locus(track):
        x = track.intensities
        ok = x.sum(axis=1) > 0
        c = (x @ pos) / np.maximum(x.sum(axis=1), 1e-12)[:, None]
        step = np.linalg.norm(np.diff(c, axis=0), axis=1) * motion.fps
        both = ok[1:] & ok[:-1]
        n = max(1, int(round(0.2 * motion.fps)))
        avg = np.stack([np.convolve(c[:, k], np.ones(n) / n, mode="same") for k in range(3)], axis=1)
        jit = np.linalg.norm(c - avg, axis=1)[ok][n:-n]
        return float(np.median(step[both])), float(np.sqrt(np.mean(jit ** 2)))

    def switches(track):
        a = track.debug["active"]
        return np.count_nonzero(np.diff(a[:, 0] + 2 * a[:, 1].astype(int))) / (motion.n_frames / motion.fps)

    mst = hapmotion.render(motion, params=STEADY_ENERGY)
    base = hapmotion.render(motion, method="baseline", params=STEADY_ENERGY)
    (sm, jm), (sb, jb) = locus(mst), locus(base)
    assert sm < sb and jm < jb
    assert switches(mst) < 1.0


@pytest.mark.parametrize("params", [PRESETS["paper"], STEADY_ENERGY], ids=["paper", "steady-energy"])
@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_batch_equals_step_with_appended_weights(params, method):
    motion = motion_from_frames(waving(n=300, hand="HAND_RIGHT", freq=2.3))
    track = hapmotion.render(motion, method=method, params=params)
    r = hapmotion.Renderer(method, params=params, fps=motion.fps, body=BodyModel.from_motion(motion))
    rows = np.array([r.step(f) for f in motion.positions])
    assert np.array_equal(rows, track.intensities) and track.intensities.max() > 0

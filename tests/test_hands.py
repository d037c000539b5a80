"""The performer's hands on gloves: synthetic clap, wave and point skeletons whose answers follow from the rules of
hapmotion.show.hands by hand; real recordings; the stage, files, live and the fake Players (SDK1 and SDK2)."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest
from support.data import MOTION
from support.live_fakes import V2_ALL_SIZES, FakePlayerSdk1, FakePlayerSdk2, self_signed_cert

import hapmotion
from hapmotion.layout import load_layout
from hapmotion.motion import new_motion
from hapmotion.motion_files import save_motion_table
from hapmotion.rig import parse_rig, rig_track
from hapmotion.show import Show, render_show
from hapmotion.show.offline import render_input
from hapmotion.show.hands import HandGestures, HandLayer, HandRules, hand_rows
from hapmotion.skeleton.joints import JOINT_INDEX as J

FPS = 60.0
LAYOUT = load_layout()
GLOVES = LAYOUT.with_rig(parse_rig("x40+tactosy-shoulders+gloves"))
PALM, INDEX = 5, 1


def _body(n: int) -> np.ndarray:
    """``(n, 32, 3)`` a standing performer facing +Z (left at +X), arms hanging; NaN for the joints not set."""
    pos = np.full((n, 32, 3), np.nan)
    for name, p in {"PELVIS": (0, 1.0, 0), "SPINE_NAVEL": (0, 1.1, 0), "SPINE_CHEST": (0, 1.3, 0),
                    "NECK": (0, 1.5, 0), "HEAD": (0, 1.65, 0), "SHOULDER_LEFT": (0.2, 1.45, 0),
                    "SHOULDER_RIGHT": (-0.2, 1.45, 0), "ELBOW_LEFT": (0.22, 1.17, 0), "ELBOW_RIGHT": (-0.22, 1.17, 0),
                    "HAND_LEFT": (0.23, 0.9, 0), "HAND_RIGHT": (-0.23, 0.9, 0), "HIP_LEFT": (0.1, 1.0, 0),
                    "HIP_RIGHT": (-0.1, 1.0, 0)}.items():
        pos[:, J[name]] = p
    return pos


def _clap(speed_each: float = 0.75) -> np.ndarray:
    """Hands at chest height, 0.6 m apart, each moving in at ``speed_each`` m/s until they are 0.08 m apart, then
    still: they close at 2 ``speed_each`` m/s."""
    n = 120
    pos = _body(n)
    x = np.full(n, 0.3)
    for i in range(1, n):
        x[i] = max(0.04, x[i - 1] - speed_each / FPS)
    for side, s in (("LEFT", 1.0), ("RIGHT", -1.0)):
        pos[:, J[f"ELBOW_{side}"]] = (s * 0.25, 1.15, 0.15)
        pos[:, J[f"HAND_{side}"]] = np.stack([s * x, np.full(n, 1.3), np.full(n, 0.35)], axis=1)
    return pos


def _run(pos: np.ndarray) -> tuple[np.ndarray, HandGestures]:
    g = HandGestures(FPS)
    out = np.zeros((len(pos), 2, 6))
    flags = []
    for i, frame in enumerate(pos):
        out[i] = g.step(frame)
        flags.append((g.clapped, g.waving.copy(), g.pointed.copy()))
    g.flags = flags
    return out, g


def test_a_clap_is_one_short_pulse_on_both_palms_at_the_closing_speed():
    out, g = _run(_clap(0.75))
    claps = [i for i, f in enumerate(g.flags) if f[0]]
    assert len(claps) == 1
    i = claps[0]
    # closing at 1.5 m/s: 100 * 1.5 / clap_full (1.6) on both palms, nothing on the fingertips
    assert out[i, :, PALM] == pytest.approx([100 * 1.5 / 1.6] * 2, abs=0.1)
    assert out[:, :, :PALM].max() == 0
    # short: gone within clap_pulse_s (0.12 s, 7.2 frames at 60 fps), and never before the hands met
    assert out[i + 8:].max() == 0 and out[:i].max() == 0
    assert not any(f[1].any() or f[2].any() for f in g.flags)


def test_hands_meeting_slowly_are_no_clap():
    out, g = _run(_clap(0.2))  # closing at 0.4 m/s, under clap_speed (0.8)
    assert not any(f[0] for f in g.flags) and out.max() == 0


def _wave(n: int = 240, hz: float = 2.0, amplitude: float = 0.15) -> np.ndarray:
    """The right hand raised above its elbow, swinging side to side (along the shoulder line) at ``hz``; the left
    hand hanging."""
    pos = _body(n)
    t = np.arange(n) / FPS
    pos[:, J["ELBOW_RIGHT"]] = (-0.35, 1.45, 0.05)
    pos[:, J["HAND_RIGHT"]] = np.stack([-0.4 + amplitude * np.sin(2 * np.pi * hz * t), np.full(n, 1.7),
                                        np.full(n, 0.1)], axis=1)
    return pos


def test_a_wave_is_felt_on_the_waving_hand_in_its_rhythm():
    pos = _wave()
    out, g = _run(pos)
    left, right = out[:, 0], out[:, 1]
    assert left.max() == 0
    waving = np.array([f[1][1] for f in g.flags])
    # waving once it has turned three times: the velocity (a cosine) turns at 0.125, 0.375 and 0.625 s (every half
    # of the 0.5 s swing), plus the velocity filter's lag (a few frames)
    first = int(np.argmax(waving))
    assert 0.625 <= first / FPS <= 0.7 and waving[first:].all()
    # the whole glove at 100 min(1, speed / wave_full): the swing's peak speed is 0.15 * 2 pi * 2 = 1.9 m/s
    assert (right[first:] == right[first:, :1]).all() and right.max() == 100
    # in its rhythm: the level dips at each turn (twice per swing) and swells between them
    level = right[first:, 0]
    dips = np.flatnonzero((level[1:-1] < level[:-2]) & (level[1:-1] <= level[2:]) & (level[1:-1] < 60))
    seconds = (len(level) - 2) / FPS
    assert abs(len(dips) - 2 * 2.0 * seconds) <= 2


def test_the_wave_goes_to_the_mirrored_glove_when_the_show_is_mirrored():
    hands, _ = _run(_wave())
    plain, mirrored = hand_rows(hands, mirror=False), hand_rows(hands, mirror=True)
    assert plain[:, :6].max() == 0 and plain[:, 6:].max() == 100  # performer's right hand: the right glove
    assert mirrored[:, 6:].max() == 0 and mirrored[:, :6].max() == 100  # mirrored: the left glove


def _point(hold_s: float = 1.0) -> np.ndarray:
    """The right arm goes from bent (elbow down, forearm forward: reach 0.71 of the arm) to straight forward at
    shoulder height in 0.25 s (the hand travels 0.396 m: 1.58 m/s), then holds for ``hold_s`` (or comes straight
    back)."""
    move, hold = 15, int(round(hold_s * FPS))
    n = 30 + move + hold + 30
    pos = _body(n)
    shoulder = np.array([-0.2, 1.45, 0.0])
    elbow0, hand0 = shoulder + (0, -0.28, 0), shoulder + (0, -0.28, 0.27)
    elbow1, hand1 = shoulder + (0, 0, 0.28), shoulder + (0, 0, 0.55)
    f = np.concatenate([np.zeros(30), np.arange(1, move + 1) / move, np.ones(hold),
                        np.linspace(1, 0, 30)])[:n]
    pos[:, J["ELBOW_RIGHT"]] = elbow0 + f[:, None] * (elbow1 - elbow0)
    pos[:, J["HAND_RIGHT"]] = hand0 + f[:, None] * (hand1 - hand0)
    return pos


def test_a_point_is_a_fingertip_pulse_on_the_pointing_hand():
    out, g = _run(_point())
    points = [i for i, f in enumerate(g.flags) if f[2][1]]
    assert len(points) == 1 and not any(f[2][0] for f in g.flags)
    i = points[0]
    level = 100 * (0.28 * 2 ** 0.5 / 0.25) / 2.0  # arrival speed 1.58 m/s over point_full (2 m/s)
    assert out[i, 1, INDEX] == pytest.approx(level, abs=0.5)
    assert out[i, 1, [0, 2, 3, 4]] == pytest.approx([level / 2] * 4, abs=0.3)
    assert out[i, 1, PALM] == 0 and out[:, 0].max() == 0
    # after it stopped (30 + 15 frames) the hand was held point_hold_s (0.15 s = 9 frames) once its filtered speed
    # fell under hold_speed (a few frames)
    assert 45 + 9 <= i <= 45 + 9 + 6
    assert out[i + int(0.3 * FPS) + 1:].max() == 0  # a pulse, gone after point_pulse_s


def test_a_jab_that_comes_straight_back_is_no_point():
    out, g = _run(_point(hold_s=0.05))
    assert not any(f[2].any() for f in g.flags) and out.max() == 0


def test_hand_joints_that_are_missing_leave_the_gloves_at_rest():
    pos = _clap()
    pos[:, J["HAND_LEFT"]] = np.nan
    out, g = _run(pos)
    assert out.max() == 0


def test_the_layer_runs_the_same_numbers_in_one_go_and_frame_by_frame():
    pos = np.concatenate([_clap(), _wave(), _point()])
    layer = HandLayer(FPS, mirror=True)
    whole = layer.rows(pos)
    layer.reset()
    stepped = np.array([layer.step(f, i / FPS) for i, f in enumerate(pos)])
    assert np.array_equal(whole, stepped) and whole.max() == 100


# ------------------------------------------------------------------------------------------ on real recordings
def _rows(path, rig="x40+tactosy-shoulders+gloves"):
    motion = hapmotion.load_motion(path)
    layout = LAYOUT.with_rig(parse_rig(rig))
    return render_show(Show(layout=layout), motion), layout


def test_both_hands_waving_are_felt_on_both_gloves():
    track, layout = _rows(MOTION / "dataset-2_wave-both-hands_normal_001.bvh")
    gloves = track.intensities[:, len(LAYOUT.actuators):]
    assert track.actuators == layout.played_actuators and gloves.shape[1] == 12
    # the recording waves both hands above the shoulders for most of its 6.7 s
    assert (gloves[:, :6].max(axis=1) > 0).mean() > 0.6 and (gloves[:, 6:].max(axis=1) > 0).mean() > 0.6


def test_the_render_commands_kept_joints_give_the_gloves_the_same_rows():
    """``hapmotion render`` keeps only the joints a show reads (render_input): on a glove rig that includes the
    glove layer's, so the track is the whole motion's, bit for bit, and no joint it let go reads as a place."""
    motion = hapmotion.load_motion(MOTION / "dataset-2_wave-both-hands_normal_001.bvh")
    show = Show(layout=LAYOUT.with_rig(parse_rig("x40+tactosy-shoulders+gloves")))
    whole = render_show(show, motion)
    kept = render_show(show, render_input(show, motion))
    assert np.array_equal(kept.intensities, whole.intensities)
    assert whole.intensities[:, len(LAYOUT.actuators):].max() > 0


def test_gloves_leave_the_body_chart_as_it_was_and_rigs_without_gloves_unchanged():
    """The glove layer only adds columns: the body chart's rows are the plain render's, bit for bit, unless the
    row's power goes over the show's limit; a rig without gloves renders exactly as before."""
    path = MOTION / "dataset-1_byebye_happy_001.bvh"
    plain = render_show(Show(), hapmotion.load_motion(path))
    track, _ = _rows(path)
    assert np.array_equal(track.intensities[:, :len(LAYOUT.actuators)], plain.intensities)
    assert track.intensities[:, len(LAYOUT.actuators):].max() > 0
    pro, _ = _rows(path, "pro")
    assert np.array_equal(pro.intensities, plain.intensities) and pro.actuators == plain.actuators


def test_a_glove_rig_track_writes_the_gloves_and_plays_back_to_the_same_rows():
    track, layout = _rows(MOTION / "dataset-2_wave-both-hands_normal_001.bvh", "pro+gloves")
    motors = rig_track(track, layout)
    col = {a: i for i, a in enumerate(motors.actuators)}
    glove = motors.intensities[:, [col[f"GloveL_{k}"] for k in range(6)]]
    # gloves' places are the gloves' motors: the projection copies them
    assert np.array_equal(glove, track.intensities[:, len(LAYOUT.actuators):len(LAYOUT.actuators) + 6])


# ------------------------------------------------------------------------------------------ live on fake Players
def _clap_bvh_frames() -> np.ndarray:
    return np.concatenate([_clap(), _wave()])


def _live(player, url, tmp_path):
    from hapmotion.live import live

    clip = tmp_path / "hands.npz"
    save_motion_table(new_motion(_clap_bvh_frames(), FPS, source="hands"), clip)
    show = Show(layout=GLOVES)

    async def run():
        await player.start()
        try:
            await live(show, f"replay:{clip}", [url()], speed=2.0, handle_signals=False)
        finally:
            await player.stop()

    asyncio.run(run())


def test_live_a_clap_and_a_wave_reach_the_sdk1_players_glove_dots(tmp_path):
    player = FakePlayerSdk1(sizes=V2_ALL_SIZES)
    _live(player, player.url, tmp_path)
    assert player.errors == [] and player.turn_off_all
    gloves = {pos: [v for _, p, v, _ in player.frames if p == pos] for pos in ("GloveL", "GloveR")}
    # the clap on both palms (dot 5); the performer's right-hand wave on the mirrored, left, glove
    assert max(v[5] for v in gloves["GloveL"]) > 50 and max(v[5] for v in gloves["GloveR"]) > 50
    assert max(max(v[:5]) for v in gloves["GloveL"]) > 50 and max(max(v[:5]) for v in gloves["GloveR"]) == 0


def test_live_the_gloves_reach_the_sdk2_players_positions_8_and_9(tmp_path):
    player = FakePlayerSdk2(self_signed_cert(tmp_path), sizes={0: 40, 1: 6, 2: 6, 8: 6, 9: 6})
    _live(player, lambda: player.url(workspace_id="show", api_key="k"), tmp_path)
    assert player.errors == [] and player.stop_all
    left = [v for _, pos, v, _ in player.dots if pos == 8]
    right = [v for _, pos, v, _ in player.dots if pos == 9]
    assert max(v[5] for v in right) > 50 and max(max(v[:5]) for v in left) > 50 and max(max(v[:5]) for v in right) == 0


def test_rules_are_documented_numbers():
    r = HandRules()
    assert 0 < r.contact_m < 0.3 and r.clap_speed < r.clap_full and r.hold_speed < r.point_speed


def test_render_for_gloves_writes_the_gloves_tact_and_play_sends_it_back(tmp_path):
    """``render --rig pro+gloves`` of a waving recording: the gloves' ``.tact`` files hold the wave; the rig's own
    track played on the same rig reaches the Player's glove dots with the same numbers (to its rounding)."""
    from click.testing import CliRunner

    from hapmotion.cli import cli
    from hapmotion.live.playback import play

    wave = MOTION / "dataset-2_wave-both-hands_normal_001.bvh"
    for out in ("pg.tact", "pg.csv"):
        result = CliRunner().invoke(cli, ["render", str(wave), "--rig", "pro+gloves", "-o", str(tmp_path / out)])
        assert result.exit_code == 0, result.output
    for side in ("L", "R"):
        glove = hapmotion.load_track(tmp_path / f"pg.Glove{side}.tact")
        assert glove.intensities.max() > 50 and (glove.intensities.max(axis=1) > 0).mean() > 0.5
    track = hapmotion.load_track(tmp_path / "pg.csv")
    player = FakePlayerSdk1(sizes=V2_ALL_SIZES)

    async def run():
        await player.start()
        try:
            await play(track, [player.url()], show=Show(layout=LAYOUT.with_rig(parse_rig("pro+gloves"))),
                       handle_signals=False)
        finally:
            await player.stop()

    asyncio.run(run())
    assert player.errors == []
    col = {a: i for i, a in enumerate(track.actuators)}
    sent = max(max(v) for _, p, v, _ in player.frames if p == "GloveL")
    assert abs(sent - np.rint(track.intensities[:, [col[f"GloveL_{k}"] for k in range(6)]].max())) <= 1


# ------------------------------------------------------------------------------------------ the output stage
def _stage(**show):
    from hapmotion.show import OutputStage

    return OutputStage.for_show(Show(layout=GLOVES, mirror=False, **show), "motion", layout=GLOVES, fps=FPS)


def test_the_stage_puts_the_gloves_under_the_wearers_comfort_and_the_power_limit():
    from hapmotion.show import Comfort

    pos = _clap(0.75)
    body_rows = np.zeros((len(pos), len(LAYOUT.actuators)))
    plain = _stage().rows(body_rows, None, pos)
    n = len(LAYOUT.actuators)
    assert plain.shape == (len(pos), n + 12) and plain[:, n + PALM].max() == pytest.approx(100 * 1.5 / 1.6, abs=0.1)
    capped = _stage(comfort=Comfort(max_level=40.0)).rows(body_rows, None, pos)
    assert capped[:, n:].max() == pytest.approx(40.0)  # the wearer's maximum level covers the gloves
    # a full body chart and full gloves: the whole row is scaled to the show's one power limit (0.75 of 64 motors)
    full = _stage().rows(np.full_like(body_rows, 100.0), None, pos)
    power = ((full / 100.0) ** 2).sum(axis=1)
    assert power.max() <= 0.75 * (n + 12) + 1e-9 and full[:, n + PALM].max() > 0
    # frame by frame, as live and a seat drive it: the same rows
    stage = _stage()
    stepped = np.array([stage.step(r, i / FPS, f) for i, (r, f) in enumerate(zip(body_rows, pos))])
    assert np.array_equal(stepped, plain)


def test_a_glove_pattern_plays_on_gloves_as_it_is():
    from hapmotion.track import HapticTrack

    ids = parse_rig("gloves").actuators
    rows = np.zeros((10, 12))
    rows[:, 1] = 80.0  # the left index tip
    pattern = HapticTrack(rows, 30.0, ids, layout="gloves")
    on_rig = rig_track(pattern, GLOVES)
    col = {a: i for i, a in enumerate(on_rig.actuators)}
    assert on_rig.intensities[:, col["GloveL_1"]].max() == 80.0
    assert on_rig.intensities[:, [col[a] for a in on_rig.actuators if a != "GloveL_1"]].max() == 0


def test_a_hand_tip_where_the_input_has_one_decides_the_reach():
    """With ``HANDTIP_*`` (Azure Kinect JSON, live canonical senders) the reach runs to the fingers' end: a hand
    pointing on along the arm is a point; the same arm with the hand bent back at the wrist (the tip 9 cm back
    towards the shoulder, reach (0.55 - 0.09) / (0.55 + 0.09) = 0.72) is not."""
    pos = _point()
    arm = pos[:, J["HAND_RIGHT"]] - pos[:, J["ELBOW_RIGHT"]]
    unit = arm / np.linalg.norm(arm, axis=1)[:, None]
    pos[:, J["HANDTIP_RIGHT"]] = pos[:, J["HAND_RIGHT"]] + 0.09 * unit
    _, g = _run(pos)
    assert sum(f[2][1] for f in g.flags) == 1
    pos[:, J["HANDTIP_RIGHT"]] = pos[:, J["HAND_RIGHT"]] - 0.09 * unit
    out, g = _run(pos)
    assert not any(f[2].any() for f in g.flags) and out.max() == 0


def test_live_frames_at_an_uneven_rate_are_timed_by_their_show_time():
    """A sender that skips every other frame, or sends in bursts: the frames' show times give the speeds, so the
    clap is found once, at the same closing speed (1.5 m/s: 100 * 1.5 / 1.6 on both palms)."""
    pos = _clap(0.75)
    keep = np.flatnonzero(np.arange(len(pos)) % 3 != 1)  # two frames of three
    g = HandGestures(FPS)
    out = np.array([g.step(pos[i], i / FPS) for i in keep])
    claps = np.flatnonzero(out[:, 0, PALM] > 0)
    assert out[:, :, PALM].max() == pytest.approx(100 * 1.5 / 1.6, abs=0.5)
    assert len(claps) and (np.diff(claps) == 1).all() and out[:, :, :PALM].max() == 0


def _raised_still(jitter_m: float, n: int = 300, seed: int = 1) -> np.ndarray:
    """The right hand of :func:`_wave` held still at its centre, with a webcam tracker's jitter: Gaussian noise of
    ``jitter_m`` (m, per axis, per frame) on the hand."""
    pos = _wave(n, amplitude=0.0)
    pos[:, J["HAND_RIGHT"]] += np.random.default_rng(seed).normal(0.0, jitter_m, (n, 3))
    return pos


@pytest.mark.parametrize("jitter_m", [0.002, 0.005, 0.01, 0.02])
def test_tracker_jitter_on_a_raised_still_hand_is_no_wave(jitter_m):
    # the jitter reverses the smoothed velocity at well over wave_min_speed every few frames; those reversals are
    # a few jitters apart, under 5 times the jitter the layer estimates, so they are no turns (50 s per seed)
    for seed in range(3):
        out, g = _run(_raised_still(jitter_m, n=3000, seed=seed))
        assert not any(f[1].any() for f in g.flags) and out.max() == 0
        # the estimate follows the jitter, a little above it (it rises faster than it falls)
        assert jitter_m <= g._jitter2[1] ** 0.5 <= 1.6 * jitter_m


def test_a_small_wave_is_still_a_wave_and_a_jittery_wave_too():
    # a 16 cm swing (amplitude 8 cm), the benchmarks' smallest synthetic wave, with 10 mm of jitter on top
    pos = _wave(amplitude=0.08)
    pos[:, J["HAND_RIGHT"]] += np.random.default_rng(2).normal(0.0, 0.01, (len(pos), 3))
    out, g = _run(pos)
    waving = np.array([f[1][1] for f in g.flags])
    assert waving[len(pos) // 2:].mean() > 0.9 and out[:, 1].max() > 50


@pytest.mark.parametrize("gap", [5e-324, 0.0, -1.0 / 60, 1e-300])
def test_a_tiny_zero_or_backward_time_step_never_silences_the_gloves(gap):
    pos = _wave()
    t = np.arange(len(pos)) / FPS
    t[100:] += gap - 1.0 / FPS  # frame 100 comes `gap` s after frame 99, the rest follow at the usual rate
    g = HandGestures(FPS)
    out = np.array([g.step(f, float(s)) for f, s in zip(pos, t)])
    assert np.isfinite(out).all() and np.isfinite(g._vel).all()
    clean = HandGestures(FPS).run(pos, np.arange(len(pos)) / FPS)
    # still waving a second after the odd step, as without it
    assert out[160:, 1].min() > 0 and clean[160:, 1].min() > 0


def test_non_finite_or_impossible_hand_moves_leave_no_lasting_state():
    pos = _wave()
    pos[100, J["HAND_RIGHT"]] = (1e308, 1.7, 0.1)  # finite, but the step from the last frame is not
    pos[101, J["HAND_RIGHT"]] = (-1e308, 1.7, 0.1)
    pos[130, J["HAND_RIGHT"]] = (1e3, 1.7, 0.1)  # a 1 km jump: a glitch, not a movement
    g = HandGestures(FPS)
    out = g.run(pos)
    assert np.isfinite(out).all() and np.isfinite(g._vel).all()
    assert out[200:, 1].min() > 0  # the wave is felt again
    g._vel[1] = np.nan  # whatever got in, the next frame starts afresh
    assert np.isfinite(g.step(pos[-1])).all() and np.isfinite(g._vel).all()

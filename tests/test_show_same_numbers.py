"""The block-wise and in-place number paths give the bytes the whole-array ones gave (tests/support/previous_show.py
keeps those), on real recordings and music and on synthetic edge cases: body size, mix and power limit, the audio
pattern, resampling, a file's confidences, the render joints alone, and the stage writing into rows it was given."""

from __future__ import annotations

import numpy as np
import pytest

import hapmotion
from hapmotion.audio import analyze_file
from hapmotion.audio.mix import ROW_BLOCK, limit_power, mix
from hapmotion.audio.pattern import audio_intensities
from hapmotion.body.model import BodyModel
from hapmotion.motion import new_motion
from hapmotion.show import render_show
from hapmotion.show.offline import render_input
from hapmotion.show.settings import Show
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from hapmotion.track import HapticTrack
from support import previous_show as before
from support.data import AUDIO, MOTION
from support.synthetic import motion_from_frames, waving

REAL = sorted(MOTION.glob("*.bvh")) + [MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl"]


def same(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.fixture(scope="module")
def motions():
    return {p.stem: hapmotion.load_motion(p) for p in REAL}


@pytest.fixture(scope="module")
def music_rows():
    """The real song's rows at 60 fps on the default layout, tiled past several mix blocks."""
    an = analyze_file(AUDIO / "vibe_ace.ogg", fps=60.0)
    rows, _ = audio_intensities(an, hapmotion.load_layout())
    return np.tile(rows, (-(-3 * ROW_BLOCK // rows.shape[0]), 1))


def test_body_size_is_the_whole_array_one_on_every_real_recording(motions):
    for name, m in motions.items():
        assert BodyModel.from_motion(m) == before.body_from_motion(m), name


def test_body_size_with_degenerate_frames_and_a_broken_skeleton():
    frames = waving(n=200)
    frames[10:20, JOINT_INDEX["SHOULDER_RIGHT"]] = frames[10:20, JOINT_INDEX["SHOULDER_LEFT"]]  # no right axis
    frames[30:40, JOINT_INDEX["NECK"]] = frames[30:40, JOINT_INDEX["PELVIS"]]
    m = motion_from_frames(frames)
    assert BodyModel.from_motion(m) == before.body_from_motion(m)
    flat = waving(n=50)
    flat[:, :, 1] = 0.0  # every joint at one height: the default proportions
    m = motion_from_frames(flat)
    assert BodyModel.from_motion(m) == before.body_from_motion(m)


@pytest.mark.parametrize("rule", ["duck", "paper", "energy"])
def test_mix_in_blocks_is_the_whole_array_mix_on_real_motion_and_music(motions, music_rows, rule):
    layout = hapmotion.load_layout()
    motion = hapmotion.render(motions["dataset-1_dance-short_normal_001"]).intensities
    motion = np.tile(motion, (-(-music_rows.shape[0] // motion.shape[0]), 1))[:music_rows.shape[0]]
    motion[5, 3] = np.nan  # non-finite values count as 0 in both
    for limit in (None, 0.75 * 52, 3.0):
        want = before.mix(motion, music_rows, (2, 3), limit, rule=rule, positions=layout.positions())
        assert same(mix(motion, music_rows, (2, 3), limit, rule=rule, positions=layout.positions()), want)
        into = np.array(motion)
        got = mix(into, music_rows, (2, 3), limit, rule=rule, positions=layout.positions(), out=into)
        assert got is into and same(got, want)
        row = before.mix(motion[100], music_rows[100], (2, 3), limit, rule=rule, positions=layout.positions())
        assert same(mix(motion[100], music_rows[100], (2, 3), limit, rule=rule, positions=layout.positions()), row)


def test_power_limit_in_place_is_the_whole_array_one(music_rows):
    rows = music_rows * 1.3  # some rows over the limit
    for limit in (None, 39.0, 1.0):
        want = before.limit_power(rows, limit)
        assert same(limit_power(rows, limit), want)
        own = rows.copy()
        assert limit_power(own, limit, copy=False) is own and same(own, want)
    assert same(limit_power(rows[7], 1.0), before.limit_power(rows[7], 1.0))


@pytest.mark.parametrize("song", ["vibe_ace.ogg", "lets_go_fishin.ogg"])
def test_audio_pattern_in_blocks_is_the_whole_array_one_on_real_music(song):
    an = analyze_file(AUDIO / song, fps=60.0)
    for layout in (hapmotion.load_layout(), hapmotion.load_layout().actuators[:12]):
        rows, kick = audio_intensities(an, layout)
        want_rows, want_kick = before.audio_intensities(an, layout)
        assert same(rows, want_rows) and same(kick, want_kick)


@pytest.mark.parametrize("fps_in,fps", [(120.0, 50.0), (30.0, 50.0), (60.0, 50.0), (50.0, 7.0), (29.97, 50.0)])
def test_resampling_in_blocks_is_the_whole_array_one(motions, fps_in, fps):
    rows = hapmotion.render(motions["01_01"]).intensities
    rows = np.tile(rows, (5, 1))  # past several blocks
    track = HapticTrack(rows, fps_in, hapmotion.load_layout().actuators)
    assert same(track.resample(fps).intensities, before.resample_rows(rows, fps_in, fps))


def test_a_track_keeps_clean_rows_and_clips_others_as_before():
    ids = hapmotion.load_layout().actuators
    clean = np.linspace(0.0, 100.0, 4 * len(ids)).reshape(4, len(ids))
    assert HapticTrack(clean, 60.0, ids).intensities is clean
    wild = clean * 2 - 50
    wild[0, 0] = -0.0
    got = HapticTrack(wild, 60.0, ids).intensities
    assert got is not wild and same(got, np.clip(wild, 0.0, 100.0))
    for bad in (np.nan, np.inf, -np.inf):
        rows = clean.copy()
        rows[2, 5] = bad
        with pytest.raises(ValueError, match="finite"):
            HapticTrack(rows, 60.0, ids)
    assert HapticTrack(np.zeros((0, len(ids))), 60.0, ids).n_frames == 0


def test_a_bvh_files_confidences_are_the_full_table_as_one_row(motions):
    for name, m in motions.items():
        if not (MOTION / f"{name}.bvh").exists():
            continue
        every = np.broadcast_to(m.present, m.confidence.shape)  # a BVH file has every present joint in every frame
        assert not m.confidence.flags.writeable, name
        assert same(np.ascontiguousarray(m.confidence), before.confidence_table(m.derived, every, m.present)), name


def test_finite_joints_and_confidences_with_gaps_and_infinities():
    frames = waving(n=40)
    frames[3, JOINT_INDEX["HAND_LEFT"], 1] = np.nan
    frames[7, JOINT_INDEX["HAND_RIGHT"], 0] = np.inf
    frames[9, JOINT_INDEX["NECK"], 2] = -np.inf
    frames[:, JOINT_INDEX["FOOT_LEFT"]] = np.nan  # absent throughout
    frames[11, JOINT_INDEX["ELBOW_LEFT"]] = 1e308  # finite, however large
    m = new_motion(frames.copy(), 30.0, source="synthetic")
    finite = np.isfinite(frames).all(axis=2)
    present = finite.any(axis=0)
    assert same(m.present, present)
    assert m.meta["filled_frames"] == int((~finite[:, present]).sum()) == 3
    assert same(m.confidence, before.confidence_table(m.derived, finite, present))
    assert not any("warning" in n for n in m.meta["notes"])  # inf * 0 is looked for, not warned about
    whole = new_motion(waving(n=40), 30.0, source="synthetic")
    assert whole.confidence.shape == (40, 32) and not whole.confidence.flags.writeable


def test_the_render_joints_alone_render_the_same_show(motions):
    for name in ("01_01", "dataset-1_punch_normal_001", "gBR_sBM_cAll_d04_mBR0_ch03"):
        m = motions[name]
        for show in (Show(), Show(fps=50.0), Show(audio=AUDIO / "vibe_ace.ogg")):
            alone = render_input(show, m)
            keep = np.zeros(32, dtype=bool)
            keep[[JOINT_INDEX[j] for j in RENDER_JOINTS]] = True
            assert same(alone.present, keep & m.present) and alone.positions.shape[1:] == (32, 3)
            assert alone.positions.base.shape == (32, alone.n_frames, 3)  # joint-major: the rest never touched
            a, b = render_show(show, alone), render_show(show, m)
            assert same(a.intensities, b.intensities), (name, show.fps, show.audio)
            assert a.meta == b.meta and a.debug.keys() == b.debug.keys()
            assert all(same(a.debug[k], b.debug[k]) for k in a.debug)


def test_the_stage_writes_into_rows_it_is_given_without_changing_a_callers_track(motions):
    show = Show(audio=AUDIO / "vibe_ace.ogg")
    motion_track = hapmotion.render(motions["dataset-1_byebye_happy_001"])
    kept = motion_track.intensities.copy()
    for mode in ("multimodal", "audio", "motion"):
        shown = render_show(show.replace(mode=mode), motion_track=motion_track)
        assert same(motion_track.intensities, kept), mode  # a caller's track is read, never written
        again = render_show(show.replace(mode=mode), motions["dataset-1_byebye_happy_001"])
        assert same(again.intensities, shown.intensities), mode


@pytest.mark.parametrize("clip,song", [("01_01.bvh", None), ("dataset-1_dance-short_normal_001.bvh", "vibe_ace.ogg"),
                                       (None, "lets_go_fishin.ogg")])
def test_render_command_writes_the_tact_files_of_the_whole_motion(tmp_path, clip, song):
    """``hapmotion render`` keeps only the render joints and drops the debug before writing: the same files."""
    from hapmotion.cli import main as cli
    from hapmotion.rig import rig_track
    from hapmotion.track_files import save_track

    args = ([str(MOTION / clip)] if clip else []) + (["--audio", str(AUDIO / song)] if song else [])
    (tmp_path / "cli").mkdir()
    (tmp_path / "api").mkdir()
    assert cli(["render", *args, "-o", str(tmp_path / "cli" / "show.tact")]) in (None, 0)
    show = Show(audio=AUDIO / song if song else None)
    track = render_show(show, hapmotion.load_motion(MOTION / clip) if clip else None)
    save_track(rig_track(track, show.load_layout(), slots=True), tmp_path / "api" / "show.tact")
    names = sorted(p.name for p in (tmp_path / "api").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "cli").iterdir()) and len(names) == 3
    for name in names:
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "api" / name).read_bytes(), name

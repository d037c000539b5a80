"""Scorecard, tables, the evaluate report on every bundled recording, and the CLI command."""

import csv
import math

import numpy as np
import pytest
from click.testing import CliRunner

from hapmotion.layout import load_layout
from hapmotion.metrics import sweep
from hapmotion.metrics.evaluation import evaluate
from hapmotion.metrics.motor import DEFAULT_MOTOR, MotorModel, simulate
from hapmotion.metrics.scorecard import AUDIO_COLUMNS, COLUMNS, csv_key, score_audio, score_track
from hapmotion.metrics.tables import csv_text, markdown_table
from hapmotion.renderer import render
from hapmotion.show import Show, render_motion
from hapmotion.track import HapticTrack
from support.data import SHARED_DATA

CLIPS = sorted(p for p in (SHARED_DATA / "motion").iterdir() if p.suffix in (".bvh", ".pkl", ".json", ".csv", ".npz"))
LAYOUT = load_layout()


def constant_track(level: float = 50.0, n: int = 300) -> HapticTrack:
    x = np.zeros((n, LAYOUT.n_actuators))
    x[:, 5] = level
    return HapticTrack(x, 60.0, LAYOUT.actuators)


# ------------------------------------------------------------------ scorecard
def test_constant_track_scores():
    s = score_track(constant_track(50.0))
    assert s["jerk"] == 0.0 and s["toggles_s"] == 0.0 and s["saturation"] == 0.0 and s["dead_zone"] == 0.0
    assert s["hf_power"] is None  # nothing varies
    assert s["speed_rho"] is None and s["felt_moving"] is None and s["locus_cm"] is None  # no motion, no debug
    low = score_track(constant_track(5.0))
    assert low["dead_zone"] == 1.0 and low["skin_rms"] == 0.0  # below the ERM start threshold: nothing felt
    assert score_track(constant_track(100.0))["saturation"] == 1.0


def test_locus_is_the_same_mirrored_or_not():
    case = sweep.sweep_case("diagonal")
    a = render(case.motion, method="baseline", preset="paper", mirror=True, body=case.body)
    b = render(case.motion, method="baseline", preset="paper", mirror=False, body=case.body)
    assert not np.array_equal(a.intensities, b.intensities)
    sa, sb = score_track(a, case.motion), score_track(b, case.motion)
    for key in ("locus_cm", "locus_amp_cm", "locus_skin_cm", "constancy_db"):
        assert sa[key] == pytest.approx(sb[key], rel=1e-9)
    # and the mirrored locus is small: mirroring handled (unmirrored it would be tens of cm off)
    assert sa["locus_cm"] < 2.0


def test_audio_scores_on_a_hand_made_mix():
    x = np.zeros((600, LAYOUT.n_actuators))
    onsets = np.array([1.0, 2.0, 3.0, 4.0])
    for t in onsets[:3]:
        k = int(round(t * 60))
        x[k:k + 2] = 100.0  # a 33 ms full-drive kick on every actuator
    s = score_audio(HapticTrack(x, 60.0, LAYOUT.actuators), onsets)
    assert s["onset_p"] == 1.0 and s["onset_r"] == pytest.approx(0.75)
    assert s["onset_f"] == pytest.approx(2 * 0.75 / 1.75)
    assert s["mix_saturation"] == pytest.approx(6 / 600)


def test_audio_kicks_are_counted_as_the_motors_render_them():
    """A 15 % kick starts motors with a 10 % start threshold, but not motors that need 20 %."""
    x = np.zeros((600, LAYOUT.n_actuators))
    onsets = np.array([1.0, 2.0, 3.0])
    for t in onsets:
        k = int(round(t * 60))
        x[k:k + 3] = 15.0
    track = HapticTrack(x, 60.0, LAYOUT.actuators)
    assert score_audio(track, onsets)["onset_r"] == 1.0
    stiff = score_audio(track, onsets, motor=MotorModel(dead_zone=0.2))
    assert stiff["onset_r"] == 0.0 and stiff["onset_p"] is None  # no kick at all: precision undefined


def test_tables_show_undefined_as_dash_and_empty():
    rows = [{"clip": "c", "method": "mst", "preset": "paper", **{c.key: None for c in COLUMNS}}]
    rows[0]["locus_cm"] = 1.234
    rows[0]["hf_power"] = 0.125
    md = markdown_table(rows, COLUMNS)
    assert "| 1.23 |" in md and "| 12.5 |" in md and "–" in md and "nan" not in md.lower()
    text = csv_text(rows, COLUMNS)
    rec = list(csv.DictReader(text.splitlines()))[0]
    assert float(rec["locus_cm"]) == 1.234 and float(rec["hf_power_pct"]) == 12.5 and rec["speed_rho"] == ""


def test_a_negative_zero_is_shown_as_zero():
    """A stillness ratio a hair under 0 (a level below the moving one's baseline) is shown as 0, never -0, in the
    table, the bench table and the verdict; a real negative stays negative."""
    from hapmotion.metrics.tables import bench_markdown, number
    from hapmotion.metrics.verdict import run_sentence

    rows = [{"clip": "c", "method": "mst", "preset": "felt", **{c.key: None for c in COLUMNS}}]
    rows[0].update(still_ratio=-0.0004, speed_rho=-0.001, reach_rho=-0.3)
    md = markdown_table(rows, COLUMNS)
    assert "-0" not in md.replace("-0.30", "") and "| 0 |" in md and "| 0.00 |" in md and "| -0.30 |" in md, md
    assert number(-0.004, ".2f") == "0.00" and number(-0.006, ".2f") == "-0.01" and number(0.0, ".0f") == "0"
    assert "-0" not in bench_markdown([{"case": "c", "preset": "felt", "phantom": "energy", "range_db": -0.001,
                                        "jerk": -0.0}])

    class Run:  # what run_sentence reads of a run
        method, preset = "mst", "felt"
        scores = {"felt_moving": 1.0, "peak_moving": 86.0, "speed_rho": -0.001, "still_ratio": -0.0004,
                  "lateral": 0.85}
    text = run_sentence(Run())
    assert "(0 % of the moving level)" in text and "(rank correlation 0.00)" in text and "-0" not in text, text


# ------------------------------------------------------------------ the report on every bundled recording
SOMETIMES = {"still_ratio": "still", "lateral": "hand"}
"""Columns defined only where the recording has frames of their kind (stillness, a hand moving alone)."""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    return evaluate(CLIPS, ("mst", "baseline"), ("paper", "energy"), out_dir=out), out


@pytest.mark.slow
def test_report_covers_every_clip_without_nan(report):
    rep, out = report
    assert len(CLIPS) == 7
    assert len(rep.runs) == len(CLIPS) * 4
    with open(out / "metrics.csv") as f:
        recs = list(csv.DictReader(f))
    assert len(recs) == len(CLIPS) * 4
    for rec in recs:
        facts = rep.clips[rec["recording"]].facts
        for c in COLUMNS:
            key = csv_key(c.key)
            if c.key in SOMETIMES:
                # defined exactly where the recording holds enough frames of that kind
                frames = facts.still if c.key == "still_ratio" else facts.hand >= 0
                need = 1 if c.key == "still_ratio" else int(np.ceil(0.5 * facts.fps - 1e-9))
                assert (rec[key] != "") == (np.count_nonzero(frames) >= need), (rec["recording"], key)
                if rec[key] == "":
                    continue
            assert rec[key] != "", (rec["recording"], rec["method"], rec["preset"], key)
            assert math.isfinite(float(rec[key]))
    md = (out / "metrics.md").read_text()
    assert "nan" not in md.lower() and md.count("\n| ") >= len(CLIPS) * 4
    for name in ["summary.png", "bench.png", "bench.csv"] + [f"{p.stem}.png" for p in CLIPS]:
        assert (out / name).stat().st_size > 1000, name
    assert not list(out.glob("*.part"))


def mirrored_locus_cm(track: HapticTrack, motion, facts) -> float:
    """The locus error of ``track`` scored as if its mirroring were the other one (cm)."""
    wrong = HapticTrack(track.intensities, track.fps, track.actuators, layout=track.layout,
                        meta={**track.meta, "mirror": not track.meta["mirror"]}, debug=track.debug)
    return score_track(wrong, motion, facts=facts)["locus_cm"]


@pytest.mark.slow
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: p.stem)
def test_mirrored_locus_is_worse(clip):
    """The locus metric's sanity on renders whose side is clear: the default preset keeps the active hand's side
    (its felt locus lies off the midline while a hand leads), so scoring a render as if mirrored puts the centroid on
    the wrong side, more than twice as far from the renderer's target (2.3-9.0x on these recordings)."""
    from hapmotion.metrics.scorecard import motion_facts
    from hapmotion.motion_files import load_motion

    motion = load_motion(clip)
    facts = motion_facts(motion)
    for method in ("mst", "baseline"):
        track = render(motion, method=method)
        assert mirrored_locus_cm(track, motion, facts) > 2 * score_track(track, motion, facts=facts)["locus_cm"], \
            method


@pytest.mark.slow
def test_report_values_are_sane(report):
    rep, _ = report
    by = {(r.clip, r.method, r.preset): r for r in rep.runs}
    lag_checked = 0
    for run in rep.runs:
        s, t, clip = run.scores, run.track, rep.clips[run.clip]
        # the lag is measured, not assumed: delaying the track by 6 frames delays the reach lag by 6 frames (where
        # the reach drives the vibration: a strong correlation peaking within 0.3 s, not a far peak of a periodic
        # movement, whose neighbour a shift can overtake)
        k = 6
        late = np.zeros_like(t.intensities)
        late[k:] = t.intensities[:-k]
        shifted = score_track(HapticTrack(late, t.fps, t.actuators, layout=t.layout, meta=t.meta, debug=t.debug),
                              clip.motion, facts=clip.facts)
        # ... nor a flat one: on the one-hand wave the raised arm's reach is a slow plateau, so r(reach, felt total)
        # is flat over a third of a second (energy's MST: 0.66-0.69 from -10 to 0 frames) and with the moving-hand
        # gate a 6-frame shift moves no peak (energy's MST, paper's baseline)
        flat = run.clip == "dataset-1_byebye_happy_001"
        if s["reach_rho"] >= 0.5 and abs(s["reach_lag_ms"]) <= 300 and not flat:
            lag_checked += 1
            assert shifted["reach_lag_ms"] == pytest.approx(s["reach_lag_ms"] + 1000 * k / t.fps,
                                                             abs=1000 / t.fps + 1e-6)  # within one frame
        # the locus is read in the performer's frame: scoring the mirrored track as if it were not mirrored puts
        # the centroid on the wrong side, more than twice as far from the target. Not for energy's MST: it keeps two
        # hands that both carry weight one triangle, so two arms swinging alike are felt on the midline, where
        # mirroring moves nothing (CMU 01_01 1.3x, the two-hand wave 1.8x); test_mirrored_locus_is_worse checks the
        # metric on every recording with the default preset, whose side is clear
        if (run.method, run.preset) != ("mst", "energy"):
            assert mirrored_locus_cm(t, clip.motion, clip.facts) > 2 * s["locus_cm"], (run.clip, run.method)
        # power above the motors' bandwidth: the two-sided spectrum's share at |f| above it, pooled over actuators
        x = t.intensities / 100.0
        power = (np.abs(np.fft.fft(x - x.mean(axis=0), axis=0)) ** 2).sum(axis=1)
        freq = np.abs(np.fft.fftfreq(x.shape[0], 1.0 / t.fps))
        assert s["hf_power"] == pytest.approx(power[freq > DEFAULT_MOTOR.bandwidth_hz].sum() / power.sum(), rel=1e-9)
        # commands under the motors' start are exactly those the motor model leaves at rest
        _, running = simulate(t.intensities, t.fps)
        sent = t.intensities >= 0.5
        assert s["dead_zone"] == pytest.approx(np.count_nonzero(sent & ~running) / np.count_nonzero(sent))
    assert lag_checked >= 3
    # the energy preset's dead-zone lift (10 %) equals the motor model's start threshold (10 %): no command it sends
    # stalls, while a share of the paper preset's do (it has no lift: 18-77 % of its MST commands on these recordings)
    for clip in {r.clip for r in rep.runs}:
        for method in ("mst", "baseline"):
            energy, paper = by[(clip, method, "energy")].scores, by[(clip, method, "paper")].scores
            assert energy["dead_zone"] == 0.0
            assert paper["dead_zone"] > 0.1


@pytest.mark.slow
def test_verdict_says_what_the_table_says(report):
    from hapmotion.metrics.tables import number

    rep, out = report
    md = (out / "metrics.md").read_text()
    verdicts = md.split("## Key metrics")[0]
    for run in rep.runs:
        assert f"**{run.clip}**" in verdicts
        s = run.scores
        assert (f"With {run.method}/{run.preset}, it is " in verdicts)
        assert f"in {100 * s['felt_moving']:.0f} % of those frames, strongest motor {s['peak_moving']:.0f} of 100" \
            in verdicts
        assert f"(rank correlation {number(s['speed_rho'], '.2f')})" in verdicts


def test_one_hand_punches_land_on_the_mirrored_side():
    """Real recording: mainly left-hand jabs. Mirrored (the default) the wearer feels them on the right, unmirrored
    on the left; either way the lateral accuracy reads the track's own mirroring, and reading it with the wrong one
    finds the energy on the wrong side."""
    from hapmotion.metrics.scorecard import motion_facts
    from hapmotion.motion_files import load_motion

    motion = load_motion(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    facts = motion_facts(motion)
    assert np.count_nonzero(facts.hand == 0) > 5 * np.count_nonzero(facts.hand == 1)  # the left hand punches
    for method in ("mst", "baseline"):
        for mirror in (True, False):
            track = render_motion(Show(method=method, preset="energy", mirror=mirror), motion)
            assert score_track(track, motion, facts=facts)["lateral"] >= 0.9, (method, mirror)
            track.meta["mirror"] = not mirror
            assert score_track(track, motion, facts=facts)["lateral"] <= 0.1, (method, mirror)


@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: p.stem)
def test_energy_split_keeps_energy_constant_on_real_recordings(clip):
    """Known answer on real data: with the energy split alone, energy is a function of the level only (0 dB)."""
    from hapmotion.motion_files import load_motion
    from hapmotion.renderer import PRESETS

    motion = load_motion(clip)
    for method in ("mst", "baseline"):
        paper = score_track(render(motion, method=method, preset="paper"), motion)
        split = score_track(render(motion, method=method, params=PRESETS["paper"].replace(phantom="energy")), motion)
        assert split["constancy_db"] == pytest.approx(0.0, abs=1e-6)
        assert paper["constancy_db"] > 0.3  # the linear split's energy varies with the position (0.6-4.8 dB)


# ------------------------------------------------------------------ CLI
def test_cli_writes_the_report(tmp_path):
    from hapmotion.cli.evaluate import command

    clip = str(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    res = CliRunner().invoke(command, [clip, "--methods", "mst", "--presets", "paper,energy", "--no-figures",
                                       "--no-bench", "-o", str(tmp_path / "r")])
    assert res.exit_code == 0, res.output
    assert "scored 2 runs" in res.output
    assert (tmp_path / "r" / "metrics.csv").exists() and not (tmp_path / "r" / "summary.png").exists()


def test_cli_param_override_labels_the_preset(tmp_path):
    from hapmotion.cli.evaluate import command

    clip = str(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    res = CliRunner().invoke(command, [clip, "--methods", "baseline", "--presets", "energy", "--param",
                                       "release_alpha=0.3", "--no-figures", "--no-bench", "-o", str(tmp_path)])
    assert res.exit_code == 0, res.output
    assert "energy*" in (tmp_path / "metrics.md").read_text()


@pytest.mark.parametrize("args, message", [
    (["--methods", "mst,nope"], "unknown method"),
    (["--presets", "paper,loud"], "unknown preset"),
    (["--param", "release_alpha"], "NAME=VALUE"),
])
def test_cli_bad_options_are_one_line_errors(tmp_path, capsys, args, message):
    from hapmotion.cli import main

    clip = str(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    code = main(["evaluate", clip, *args, "-o", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert message in err and "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "r").exists()


def test_cli_with_audio_adds_onset_columns(tmp_path):
    from hapmotion.cli.evaluate import command

    clip = str(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    song = str(SHARED_DATA / "audio" / "vibe_ace.ogg")
    res = CliRunner().invoke(command, [clip, "--methods", "mst", "--presets", "paper", "--audio", song,
                                       "--no-figures", "--no-bench", "-o", str(tmp_path)])
    assert res.exit_code == 0, res.output
    rec = list(csv.DictReader(open(tmp_path / "metrics.csv")))[0]
    for c in AUDIO_COLUMNS:
        assert rec[csv_key(c.key)] != "", c.key
    # the mix's kicks, as the motors render them, land on the music's onsets; the music does not swamp the
    # one-hand side of the jabs, and the mix follows the music
    assert float(rec["onset_p"]) >= 0.9 and float(rec["onset_r"]) >= 0.9
    assert float(rec["mix_follows_audio"]) > 0.3


@pytest.mark.slow
def test_cli_default_presets_with_figures_and_bench(tmp_path):
    """With no --presets every preset is scored, figures and (asked for) the bench included (a preset whose sweep goes silent in
    part has no energy range: the bench figure says so instead of failing)."""
    from hapmotion.cli.evaluate import command
    from hapmotion.renderer.params import PRESETS

    clip = str(SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh")
    res = CliRunner().invoke(command, [clip, "--methods", "mst", "--bench", "-o", str(tmp_path / "r")])
    assert res.exit_code == 0, res.output
    assert f"scored {len(PRESETS)} runs" in res.output
    assert (tmp_path / "r" / "bench.png").stat().st_size > 10_000
    assert "Synthetic sweep bench" in (tmp_path / "r" / "metrics.md").read_text()


def test_evaluate_takes_the_mix_options_and_the_default_mix_keeps_the_beat():
    """The default (felt, duck with the kicks through) keeps the song's onsets felt under a punching performer;
    the same evaluation with the music's share at 0 (ratio 0:1) has no kick left, so the options reach the mix."""
    clip = SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh"
    song = SHARED_DATA / "audio" / "vibe_ace.ogg"
    kept = evaluate([clip], ("mst",), ("felt",), audio=song, figures=False, bench=False)
    assert kept.runs[0].scores["onset_r"] >= 0.7
    gone = evaluate([clip], ("mst",), ("felt",), audio=song, figures=False, bench=False, mix_ratio=(0.0, 1.0))
    assert gone.runs[0].scores["onset_r"] < 0.2
    paper_rule = evaluate([clip], ("mst",), ("felt",), audio=song, figures=False, bench=False, mix_rule="paper")
    assert paper_rule.runs[0].scores["mix_follows_audio"] != kept.runs[0].scores["mix_follows_audio"]

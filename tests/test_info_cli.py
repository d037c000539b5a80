"""``hapmotion info`` through the real ``hapmotion`` entry point (``hapmotion.cli.main``: a HapMotionError is one
line on stderr, exit code 2), and the shared reader options through a probe command in a small test group."""

from __future__ import annotations

import json
import sys

import click
import pytest
from click.testing import CliRunner

from hapmotion.cli.info import command
from hapmotion.cli.motion_options import MOTION_OPTION_NAMES, motion_options, read_motion
from hapmotion.errors import HapMotionError, UsageError

from support.data import MOTION


class Group(click.Group):
    """Like the hapmotion group: a HapMotionError becomes one line on stderr and its exit code."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except HapMotionError as err:
            click.echo(f"hapmotion: error: {err}", err=True)
            sys.exit(err.exit_code)


@click.group(cls=Group)
def cli():
    pass


cli.add_command(command)


@click.command("probe")
@click.argument("input")
@motion_options
@click.option("--flag", is_flag=True)
def probe(input, motion_opts, flag):
    """A second command reusing the decorator, as render/live/view will."""
    click.echo(json.dumps({"input": input, "opts": motion_opts, "flag": flag}))


cli.add_command(probe)


def run(*args):
    """``info`` runs through the real entry point; ``probe`` (test-only) through the small group above."""
    runner = CliRunner()
    if args and args[0] == "probe":
        return runner.invoke(cli, list(map(str, args)))
    from types import SimpleNamespace

    from hapmotion.cli import main as real_main

    with runner.isolation() as (out, err, both):
        code = real_main(list(map(str, args)))
        sys.stdout.flush()
        sys.stderr.flush()
        return SimpleNamespace(exit_code=code, output=both.getvalue().decode(), stdout=out.getvalue().decode(),
                               stderr=err.getvalue().decode())


def test_info_table():
    r = run("info", MOTION / "01_01.bvh")
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    labels = [ln.split("  ")[0] for ln in lines]
    assert labels[:3] == ["format", "skeleton", "path"]
    value_col = lines[0].index("BVH")
    assert all(len(ln) > value_col and ln[value_col - 1] == " " for ln in lines)  # one aligned value column
    text = r.output
    assert lines[3].split() == ["frames", "2751"] and lines[4].split() == ["fps", "120"]
    assert "CMU units (x0.0564444 -> m" in text and "skipped the leading T-pose frame 0" in text
    assert "HAND_LEFT <- LeftHand" in text and "NECK <- Neck1" in text


def test_info_json_and_options():
    r = run("info", MOTION / "dataset-1_punch_normal_001.bvh", "--json", "--skip-frames", "24", "--fps-in", "60",
            "--units", "CM")
    assert r.exit_code == 0, r.output
    s = json.loads(r.output)
    assert s["frames"] == 200 and s["fps"] == 60.0 and s["frames_skipped"] == 24
    assert s["joints_found"]["HAND_LEFT"] == "Hand_L" and s["joints_derived"] == {}
    assert s["units"] == "cm (x0.01 -> m) (option)"


def test_info_kinect_body_option(tmp_path):
    from support.motion_files import kinect_document  # the fixture generator of the Kinect tests

    import hapmotion

    clip = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh").slice(0, 30)
    path = tmp_path / "k.json"
    path.write_text(json.dumps(kinect_document(clip)))
    r = run("info", path, "--body-id", "3", "--json")
    assert r.exit_code == 0, r.output
    assert "body 3 (option body_id); body ids found: 7, 3" in json.loads(r.output)["notes"]


@pytest.mark.parametrize("args, message", [
    (["info", "missing.bvh"], "missing.bvh: file not found"),
    (["info", MOTION / "SOURCES.md"], "expected one of the extensions .bvh"),
    (["info", MOTION / "01_01.bvh", "--body-id", "2"], "--body-id does not apply to BVH files (.bvh); it applies to "
     ".json"),
    (["info", MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", "--up", "z"], "--up does not apply to AIST++"),
    (["info", MOTION / "01_01.bvh", "--units", "cm", "--scale", "0.1"], "give either units or scale"),
    (["info", MOTION / "01_01.bvh", "--fps-in", "nan"], "--fps-in must be a frame rate between 0.5 and 2000 fps, "
     "found nan"),
    (["info", MOTION / "01_01.bvh", "--fps-in", "1e-300"], "--fps-in must be a frame rate between 0.5 and 2000 fps"),
    (["info", MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", "--fps-in", "inf"], "--fps-in must be a frame rate"),
])
def test_errors_are_one_line_exit_2(args, message):
    r = run(*args)
    assert r.exit_code == 2
    assert r.stderr.count("\n") == 1 and message in r.stderr and "Traceback" not in r.output + r.stderr


def test_bad_file_error_names_the_line(tmp_path):
    lines = (MOTION / "01_01.bvh").read_text().split("\n")
    lines[300] += " 1.5"
    bad = tmp_path / "bad.bvh"
    bad.write_text("\n".join(lines))
    r = run("info", bad)
    assert r.exit_code == 2
    assert r.stderr.strip() == f"error: {bad}: line 301: expected 96 channel values, found 97"


def test_decorator_gathers_options_for_other_commands():
    r = run("probe", "x.bvh", "--fps-in", "30", "--up", "z", "--flag")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["flag"] is True and out["input"] == "x.bvh"
    assert out["opts"] == {"units": None, "scale": None, "skip_frames": None, "body_id": None, "fps_in": 30.0,
                           "up": "z", "joint_map": None, "limits": None}
    assert tuple(out["opts"]) == MOTION_OPTION_NAMES
    helps = run("probe", "--help").output
    for opt in ("--units", "--scale", "--skip-frames", "--body-id", "--fps-in", "--up", "--joint-map", "--limit",
                "--flag"):
        assert opt in helps
    assert json.loads(run("probe", "x.bvh", "--limit", "frames=9", "--limit", "depth=3").output)["opts"]["limits"] == \
        ["frames=9", "depth=3"]
    r = run("probe", "x.bvh", "--skip-frames", "-1")
    assert r.exit_code == 2 and "--skip-frames" in r.output


def test_read_motion_maps_fps_in():
    m = read_motion(str(MOTION / "dataset-1_punch_normal_001.bvh"), fps_in=10.0, skip_frames=None)
    assert m.fps == 10.0
    with pytest.raises(UsageError):
        read_motion(str(MOTION / "dataset-1_punch_normal_001.bvh"), body_id=1)


def test_info_says_which_up_axis_and_why(tmp_path):
    from support.motion_files import bvh_to_z_up

    path = tmp_path / "zup.bvh"
    path.write_text(bvh_to_z_up((MOTION / "dataset-1_punch_normal_001.bvh").read_text()))
    r = run("info", path)
    assert r.exit_code == 0, r.output
    row = next(ln for ln in r.output.splitlines() if ln.startswith("up axis"))
    assert "+Z (detected: head above the pelvis along +Z in 100% of frames, a foot the lowest joint in" in row
    r = run("info", path, "--up", "z", "--json")
    assert json.loads(r.output)["up_axis"] == "+Z (option)"


def test_joint_map_and_limit_options(tmp_path):
    from support.motion_files import SCHEMES, synthetic_bvh

    path = tmp_path / "odd.bvh"
    path.write_text(synthetic_bvh(SCHEMES["CMU"], rename={"LeftHand": "lmanus", "RightHand": "rmanus"}))
    r = run("info", path)
    assert r.exit_code == 2 and "--joint-map" in r.stderr and r.stderr.count("\n") == 1
    jm = tmp_path / "map.toml"
    jm.write_text('lmanus = "HAND_LEFT"\nrmanus = "HAND_RIGHT"\n')
    r = run("info", path, "--joint-map", jm, "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["joints_found"]["HAND_LEFT"] == "lmanus"
    r = run("info", path, "--joint-map", jm, "--limit", "frames=10")
    assert r.exit_code == 2 and "expected at most 10 frames (limit frames; raise it with --limit frames=N), found 60" \
        in r.stderr
    assert run("info", path, "--joint-map", jm, "--limit", "frames=60").exit_code == 0
    r = run("info", path, "--limit", "frame=60")
    assert r.exit_code == 2 and "--limit expects NAME=NUMBER" in r.stderr


def test_weak_up_axis_warning_reaches_stderr(tmp_path):
    """Every command reading motion prints the reader's warnings (here through ``info``): one line each."""
    from support.motion_files import SCHEMES, synthetic_bvh

    text = synthetic_bvh(SCHEMES["CMU"], frames=60)
    head, motion = text.split("MOTION\n")
    rows = motion.strip().split("\n")
    body = [" ".join(r.split()[:4] + ["-90.0"] + r.split()[5:]) if k < 30 else r for k, r in enumerate(rows[2:])]
    path = tmp_path / "lying.bvh"
    path.write_text(head + "MOTION\n" + "\n".join(rows[:2] + body) + "\n")
    r = run("info", path)
    assert r.exit_code == 0
    assert r.stderr.startswith(f"warning: {path}: weak evidence for the up axis (") and r.stderr.count("\n") == 1
    assert "--up" in r.stderr

"""The show options every rendering command shares (preset, mix rule, cues, gain and comfort limits) reach the
track the same way in files and live."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest

import hapmotion
from hapmotion.cli import main
from hapmotion.show.comfort import Comfort
from hapmotion.show import OutputStage, Show, render_show
from support.bounded import run_within
from support.data import AUDIO, MOTION, TACT

PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"
SONG = AUDIO / "vibe_ace.ogg"


def run(args, capsys):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def punch():
    return hapmotion.load_motion(PUNCH)


def test_render_defaults_to_the_felt_preset(tmp_path, capsys, punch):
    out = tmp_path / "d.npz"
    assert run(["render", PUNCH, "-o", out], capsys)[0] == 0
    np.testing.assert_allclose(hapmotion.load_track(out).intensities, render_show(Show(), punch).intensities)
    assert render_show(Show(), punch).meta["preset"] == "felt"


def test_gain_and_max_level_from_the_command_line(tmp_path, capsys, punch):
    full = render_show(Show(), punch).intensities
    out = tmp_path / "soft.npz"
    code, _, err = run(["render", PUNCH, "--gain", "0.5", "--max-level", "30", "-o", out], capsys)
    assert code == 0, err
    soft = hapmotion.load_track(out).intensities
    np.testing.assert_allclose(soft, np.minimum(full * 0.5, 30.0), atol=1e-9)
    assert soft.max() == pytest.approx(30.0) and full.max() > 60.0
    code, _, err = run(["render", PUNCH, "--gain", "9", "-o", tmp_path / "x.npz"], capsys)
    assert code == 2 and "--gain" in err and not (tmp_path / "x.npz").exists()


def test_mix_rule_option_picks_the_rule(tmp_path, capsys, punch):
    out = tmp_path / "paper_mix.npz"
    code, _, err = run(["render", PUNCH, "--audio", SONG, "--mix-rule", "paper", "-o", out], capsys)
    assert code == 0, err
    want = render_show(Show(audio=SONG, mix_rule="paper"), punch)
    np.testing.assert_allclose(hapmotion.load_track(out).intensities, want.intensities)
    assert want.meta["mix_rule"] == "paper"
    ducked = render_show(Show(audio=SONG), punch)
    assert ducked.meta["mix_rule"] == "duck" and not np.allclose(ducked.intensities, want.intensities)


def test_cues_are_layered_into_the_rendered_show(tmp_path, capsys, punch):
    heart = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
    cues = tmp_path / "show.cues"
    cues.write_text(f"1.0 {heart} gain=0.8\n")
    out = tmp_path / "cued.npz"
    code, _, err = run(["render", PUNCH, "--cues", cues, "-o", out], capsys)
    assert code == 0, err
    plain = render_show(Show(), punch).intensities
    cued = hapmotion.load_track(out).intensities
    first = int(round(1.0 * punch.fps))
    np.testing.assert_allclose(cued[:first], plain[:first])                   # nothing before the cue
    assert (cued[first:] >= plain[first:] - 1e-9).all() and (cued[first:] - plain[first:]).sum() > 100
    code, _, err = run(["render", PUNCH, "--cues", tmp_path / "none.cues", "-o", tmp_path / "y.npz"], capsys)
    assert code == 2 and "none.cues" in err


def test_live_applies_the_same_comfort_as_files():
    """The live engine's last stage is the show's limiter: stepping a stream gives the rows the offline comfort
    stage writes for the same frames (gain, level and the stateful duty limit)."""
    from hapmotion.show.comfort import limit_rows
    from hapmotion.live import LiveEngine
    from hapmotion.live.frames import SkeletonFrame
    from hapmotion.live.sources import Source
    from support.live_fakes import Tap
    from support.synthetic import waving

    frames = waving(n=90)
    comfort = Comfort(gain=1.5, max_level=70.0, max_duty=0.3, window_s=0.5)

    class Script(Source):
        name = "script"

        async def run(self):
            # stamped at 60 frames/s, as a tracker stamps them: the engine renders at the sender's own rate, and
            # a machine too busy to keep the sleeps even must not change that rate
            for k, pos in enumerate(frames):
                self.engine.submit(SkeletonFrame(np.array(pos, dtype=float), k, k / 60, time.perf_counter()))
                await asyncio.sleep(1 / 60)

    tap = Tap()
    renderer = hapmotion.Renderer(fps=60.0)
    stage = OutputStage.for_show(Show(comfort=comfort), "motion", layout=renderer.layout, fps=60.0)
    engine = LiveEngine(renderer, [tap], stage=stage, n_actuators=len(renderer.layout.actuators), fps=60.0,
                        handle_signals=False)
    stats = run_within(engine.run(Script()), 20)
    assert stats.rendered == len(frames)
    plain, _ = hapmotion.Renderer(fps=60.0).run(frames)
    want, _ = limit_rows(plain, comfort, 60.0)
    np.testing.assert_allclose(tap.rendered(), want, atol=1e-9)
    assert want.max() <= 70.0 + 1e-9 and not np.allclose(want, np.minimum(plain * 1.5, 70.0))   # the duty limit acts

"""The show's options refuse what cannot be meant, in one line naming the option."""

from __future__ import annotations

import pytest

from hapmotion.cli import main
from support.data import MOTION

CLIP = str(MOTION / "60_12_scaled.bvh")


@pytest.mark.parametrize("extra, message", [
    (["--mix", "1:2"], "--mix sets how the music plays: give --audio SONG too"),
    (["--audio-offset", "3"], "--audio-offset sets how the music plays"),
    (["--mix-rule", "paper"], "--mix-rule sets how the music plays"),
    (["--no-mirror", "--param", "mirror=true"], "--param mirror=... and --mirror/--no-mirror disagree"),
    (["--preset", "Felt"], "--preset: unknown preset 'Felt' (did you mean felt?)"),
    (["--gain", "nan"], "--gain must be a number in 0..5"),
])
def test_render_refuses_options_that_would_be_ignored_or_contradict(tmp_path, capsys, extra, message):
    out = tmp_path / "x.csv"
    code = main(["render", CLIP, "-o", str(out), *extra])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_demo_checks_its_options_before_making_its_folder(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--preset", "Felt", "-o", str(out)]) == 2
    assert "did you mean felt" in capsys.readouterr().err and not out.exists()

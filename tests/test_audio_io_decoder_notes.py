"""A damaged MP3 ends in one error line: libmpg123's own notes ("Note: Illegal Audio-MPEG-Header ...", "error:
dequantization failed!"), which it prints straight to the process's stderr, never reach the console."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from hapmotion.audio.io import mp3_supported

SRC = Path(__file__).resolve().parents[1] / "src"


@pytest.fixture(scope="module")
def damaged_mp3(tmp_path_factory):
    """A 3 s sine encoded as MP3, then 200 bytes overwritten at fixed places inside the frames."""
    folder = tmp_path_factory.mktemp("mp3")
    sr = 44100
    t = np.arange(3 * sr) / sr
    good = folder / "good.mp3"
    sf.write(good, 0.3 * np.sin(2 * np.pi * 440 * t), sr, format="MP3")
    raw = bytearray(good.read_bytes())
    rng = np.random.default_rng(0)
    for i in rng.integers(1000, len(raw), size=200):
        raw[i] = int(rng.integers(0, 256))
    bad = folder / "bad.mp3"
    bad.write_bytes(bytes(raw))
    return good, bad


def analyse_in_subprocess(path):
    code = ("import sys\nfrom hapmotion.audio import analyze_file\nfrom hapmotion.errors import InputError\n"
            "try:\n    analyze_file(sys.argv[1]); print('ok')\nexcept InputError as e:\n    print(e)\n")
    env = dict(os.environ, PYTHONPATH=str(SRC))
    return subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, env=env,
                          timeout=120)


needs_mp3 = pytest.mark.skipif(not mp3_supported(), reason="libsndfile without MP3")


@needs_mp3
def test_damaged_mp3_is_one_clean_error(damaged_mp3):
    good, bad = damaged_mp3
    r = analyse_in_subprocess(bad)
    assert r.stderr == "", r.stderr  # nothing from libmpg123
    assert r.stdout.startswith(f"{bad}: near ") and "decode error: dequantization failed!" in r.stdout
    assert r.stdout.count("\n") == 1
    r = analyse_in_subprocess(good)
    assert r.stdout == "ok\n" and r.stderr == ""


@needs_mp3
def test_stderr_works_again_after_an_mp3(damaged_mp3, capfd):
    """The capture is undone after each read: what the program prints afterwards reaches stderr."""
    from hapmotion.audio.io import mono_blocks, probe

    good, _ = damaged_mp3
    n = sum(len(b) for b in mono_blocks(probe(good)))
    assert n > 2 * 44100
    os.write(2, b"after\n")
    assert capfd.readouterr().err == "after\n"


def test_float_wav_with_absurd_values_is_refused(tmp_path):
    """Damaged float WAV data (3e38) would overflow the analysis' energy sums with a RuntimeWarning per block."""
    x = np.zeros((22050, 1), dtype=np.float32)
    x[5000] = 3e38
    path = tmp_path / "loud.wav"
    sf.write(path, x, 22050, subtype="FLOAT")
    r = analyse_in_subprocess(path)
    assert r.stderr == "" and r.stdout == (f"{path}: sample 5000 (0.227 s): expected sample values within +-10000 "
                                           "(full scale is 1), found 3e+38\n")

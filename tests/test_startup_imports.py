"""Every command's start-up stays light: ``hapmotion --help`` and building the command line load neither numba nor
scipy (together about 0.9 s and 130 MB of a process), which are imported where they are used."""

from __future__ import annotations

import subprocess
import sys

from tests.support.data import MOTION

PROBE = """
import sys
from hapmotion.cli import main
code = main(sys.argv[1:])
heavy = sorted({name.split('.')[0] for name in sys.modules} & {'numba', 'scipy', 'soundfile', 'websockets', 'nats'})
print(code, ' '.join(heavy) or '-')
"""


def _heavy_after(*args: str) -> tuple[str, str]:
    out = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True, check=True)
    code, heavy = out.stdout.strip().splitlines()[-1].split(" ", 1)
    return code, heavy


def test_help_loads_no_heavy_library():
    assert _heavy_after("--help") == ("0", "-")


def test_every_command_help_loads_no_heavy_library():
    """``live --help`` and ``play --help`` are left out: their help lists the source and sink kinds from the live
    package's table, which they load when the help is shown (cli/kinds_help.py)."""
    for command in ("render", "info", "check", "listen", "view", "plot", "evaluate", "demo", "venue-setup"):
        assert _heavy_after(command, "--help") == ("0", "-"), command


def test_info_on_a_bvh_loads_no_scipy_signal():
    """``info`` reads the motion (numba's forward kinematics) but never the audio analysis (scipy.signal)."""
    probe = PROBE + "print('scipy.signal' in sys.modules, 'hapmotion.audio.analysis' in sys.modules)\n"
    out = subprocess.run([sys.executable, "-c", probe, "info", str(MOTION / "dataset-1_punch_normal_001.bvh")],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "False False"

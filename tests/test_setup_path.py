"""The README's set-up, run as a newcomer would in a fresh clone: its set-up lines (``make demo``, then the line
that puts ``.venv/bin`` on PATH), then the ``hapmotion`` command of the Use section, in a shell whose PATH knows
nothing of this test's environment.

The clone gets a real virtual environment made by ``python -m venv``, and ``make demo`` runs the real
``scripts/setup-env`` in it (pip installs the clone's own hapmotion, editable, with its ``hapmotion`` command).
Only the pinned dependencies are not downloaded again: a ``.pth`` line lends the clone's venv the site-packages of
the interpreter running the tests (built by the same ``scripts/setup-env`` from the same pins), so pip finds them
installed. pip still fetches the build backend (setuptools) for the editable install from the package index.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def code_block(k: int) -> list[str]:
    """The commands of the README's code block ``k`` (0: the set-up), without their comments."""
    block = re.findall(r"```\w*\n(.*?)```", README, re.S)[k]
    return [line.split("#", 1)[0].strip() for line in block.splitlines() if line.split("#", 1)[0].strip()]


def test_the_readme_opens_with_the_set_up_and_the_line_that_puts_hapmotion_on_path():
    assert code_block(0) == ["make demo", "make test"]          # exactly the two set-up commands
    assert code_block(1) == [". .venv/bin/activate"]
    first_screen = README[:README.index("## Use")]
    assert "docs/player.md" in first_screen and ".venv\\Scripts\\activate" in first_screen


@pytest.mark.skipif(shutil.which("make") is None or shutil.which("git") is None, reason="needs make and git")
@pytest.mark.timeout(900)
def test_from_a_fresh_clone_the_set_up_lines_give_a_working_hapmotion_command(tmp_path):
    if subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True).returncode != 0:
        pytest.skip("not a git checkout")
    clone = tmp_path / "hapmotion"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True, timeout=300)
    (clone.parent / "shared").mkdir()  # a clone lives beside ../shared in CI; the set-up must not need it
    # the clone's own venv, as scripts/setup-env makes it, lent this interpreter's installed dependencies
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(clone / ".venv")], check=True, timeout=300)
    venv_python = clone / ".venv" / "bin" / "python"
    site = subprocess.run([str(venv_python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    # named to sort after the editable install's own .pth, so the clone's src comes first on sys.path
    lent = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (Path(site) / "zz_lent_dependencies.pth").write_text("\n".join(sorted(lent)) + "\n")

    env = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": os.environ.get("HOME", str(tmp_path)),
           "LANG": "C.UTF-8", "MPLBACKEND": "Agg"}
    for key in ("PIP_INDEX_URL", "PIP_CACHE_DIR", "NUMBA_CACHE_DIR", "http_proxy", "https_proxy", "HTTPS_PROXY",
                "HTTP_PROXY", "no_proxy", "NO_PROXY"):
        if key in os.environ:
            env[key] = os.environ[key]

    def shell(script: str, timeout: float = 600) -> subprocess.CompletedProcess:
        return subprocess.run(["bash", "-c", script], cwd=clone, env=env, capture_output=True, text=True,
                              timeout=timeout)

    before = shell("command -v hapmotion || echo none")
    assert before.stdout.strip() == "none"          # nothing of this test's environment leaks into the shell

    lines = [code_block(0)[0], *code_block(1)]  # make test would run this suite again
    assert lines[0] == "make demo"
    demo = shell(lines[0])
    assert demo.returncode == 0, demo.stdout + demo.stderr
    assert (clone / "out" / "demo.tact").stat().st_size > 1000 and (clone / "out" / "demo.html").is_file()
    assert "'. .venv/bin/activate' puts the hapmotion command on PATH in this shell" in demo.stdout

    # the README's lines, then the Use section's commands as written, on the bundled files
    use = shell(" && ".join(lines[1:]) + " && command -v hapmotion && hapmotion --version"
                " && hapmotion info src/hapmotion/examples/heartbeat.tact"
                " && hapmotion render src/hapmotion/examples/heartbeat.tact -o out/heartbeat.csv"
                " && python -c 'import hapmotion; print(hapmotion.__file__)'")
    assert use.returncode == 0, use.stdout + use.stderr
    out = use.stdout.splitlines()
    assert out[0] == str(clone / ".venv" / "bin" / "hapmotion")
    assert out[1].startswith("hapmotion, version")
    assert out[-1] == str(clone / "src" / "hapmotion" / "__init__.py")   # the clone's own code, not this one's
    assert (clone / "out" / "heartbeat.csv").is_file()

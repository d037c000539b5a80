"""Every terminating signal ends a command like Ctrl-C: clean-up runs, no hidden ``.part`` file stays behind."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap

import pytest

from support.data import MOTION

PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"

# ``hapmotion render`` whose CSV writer stops half-way through writing its temporary file
SLOW_WRITER = textwrap.dedent("""
    import sys, time
    import hapmotion.track_files as tf
    from hapmotion.filesafety import atomic_path
    from hapmotion.cli import main

    def half_written(track, path):
        with atomic_path(path) as tmp:
            tmp.write_text("time_s,VestFront_0\\n0.0,")
            print("writing", flush=True)
            time.sleep(60)

    tf.WRITERS[".csv"] = half_written
    sys.exit(main(["render", sys.argv[1], "-o", sys.argv[2]]))
""")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGINT])
def test_signal_during_render_leaves_no_partial_file(tmp_path, sig):
    out = tmp_path / "show.csv"
    proc = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(PUNCH), str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")]  # the temporary file exists now
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=20)
    finally:
        proc.kill()
    assert proc.returncode == (130 if sig == signal.SIGINT else 128 + sig)
    assert err.strip() == ("aborted" if sig == signal.SIGINT else f"stopped by {sig.name}")
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_while_the_command_line_loads_is_a_clean_stop():
    """A SIGINT in the moment the commands are imported (made certain here: the import of the command line raises
    it) ends like one while running: one line, exit 130, no traceback."""
    import subprocess
    import sys

    code = ("import builtins, sys\n"
            "real_import = builtins.__import__\n"
            "def interrupted(name, globals=None, locals=None, fromlist=(), level=0):\n"
            "    if name == 'cli' and level == 1:\n"
            "        raise KeyboardInterrupt\n"
            "    return real_import(name, globals, locals, fromlist, level)\n"
            "builtins.__import__ = interrupted\n"
            "from hapmotion.console import main\n"
            "sys.exit(main())\n")
    out = subprocess.run([sys.executable, "-c", code, "--help"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 130 and out.stderr.strip() == "aborted", out.stderr

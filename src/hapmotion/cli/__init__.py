"""The ``hapmotion`` command line: a click group; each command lives in its own module.

User mistakes (:class:`~hapmotion.errors.HapMotionError`, missing or unreadable files) end with one line on
stderr and exit code 2; no traceback. Ctrl-C exits with 130; SIGTERM, SIGHUP and SIGQUIT (a closed terminal or
ssh session) end the same way, with 128 + the signal number, after the same clean-up (no half-written ``.part``
file is left behind). An unexpected internal error prints one line too, with the full traceback only when
``HAPMOTION_DEBUG=1``.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import traceback
from typing import Iterator

import click

from .. import __version__
from ..errors import HapMotionError


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, prog_name="hapmotion")
def cli() -> None:
    """Turn a performer's motion (and the music) into vibration for a bHaptics TactSuit X40 and two
    Tactosy sleeves worn on the shoulders, following the HapMotion paper (motion salient triangle).

    \b
    Typical use:
      hapmotion info dance.bvh                      what is in a recording
      hapmotion render dance.bvh -o dance.tact      the haptic track (.tact .csv .json .npz)
      hapmotion render dance.bvh --audio song.ogg -o show.csv   motion + music, the music making room
      hapmotion live --source replay:dance.bvh --sink player   a show to the bHaptics Player, in real time
      hapmotion play pattern.tact --sink player     a saved track or Designer pattern on the vest
      hapmotion check                               the Player's devices and a labelled test pattern
      hapmotion demo                                the bundled dance with bundled music
    """


def _register() -> None:
    from . import check, demo, evaluate, info, listen, live, play, plot, render, venue_setup, view

    for module in (render, info, demo, live, listen, play, check, view, plot, evaluate):
        cli.add_command(module.command, module.__name__.rsplit(".", 1)[1])
    cli.add_command(venue_setup.command, "venue-setup")


_register()


TERMINATING_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP", "SIGQUIT") if hasattr(signal, name))
"""Signals that end a command like Ctrl-C (SIGINT already raises KeyboardInterrupt)."""


class Terminated(BaseException):
    """Raised in the main thread by a terminating signal, so every ``finally`` and clean-up runs as for Ctrl-C."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


@contextlib.contextmanager
def signals_raise() -> Iterator[None]:
    """While the command runs, :data:`TERMINATING_SIGNALS` raise :class:`Terminated` (live mode installs its own
    handlers on top, which turn every sink off first), except those the process was started with ignored. The
    previous handlers come back afterwards."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: object) -> None:
        raise Terminated(signum)

    # A signal the command was started with ignored stays ignored (``nohup`` ignores SIGHUP so that the command
    # outlives its terminal).
    previous = {s: signal.signal(s, handler) for s in TERMINATING_SIGNALS if signal.getsignal(s) is not signal.SIG_IGN}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hapmotion`` script."""
    try:
        # without standalone mode click returns ctx.exit(n)'s code instead of exiting
        with signals_raise():
            rv = cli.main(args=argv, prog_name="hapmotion", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("aborted", err=True)
        return 130
    except click.UsageError as err:  # a wrong option: one line, like every other user mistake
        where = f"hapmotion {err.ctx.command_path.split(' ', 1)[1]}" if err.ctx and " " in err.ctx.command_path else "hapmotion"
        click.echo(f"error: {err.format_message()} (see '{where} --help')", err=True)
        return err.exit_code
    except click.ClickException as err:
        err.show()
        return err.exit_code
    except click.exceptions.Exit as err:
        return err.exit_code
    except HapMotionError as err:
        click.echo(f"error: {err}", err=True)
        return err.exit_code
    except (FileNotFoundError, IsADirectoryError, PermissionError) as err:
        click.echo(f"error: {err.filename}: {err.strerror}", err=True)
        return 2
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        return 130
    except Terminated as stop:
        click.echo(f"stopped by {signal.Signals(stop.signum).name}", err=True)
        return 128 + stop.signum
    except Exception as err:  # a bug, not a user mistake: one line unless asked for details
        if os.environ.get("HAPMOTION_DEBUG") == "1":
            traceback.print_exc()
        else:
            click.echo(f"internal error: {type(err).__name__}: {err} (set HAPMOTION_DEBUG=1 for the traceback)", err=True)
        return 1
    return rv if isinstance(rv, int) else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""What the streaming commands (``live``, ``play``, ``listen``, ``check``) print around a session: their log lines
on stderr headed by the command's name, and the summary plus ``--stats-json`` at the end."""

from __future__ import annotations

import json
import logging
import sys
from typing import Optional

import click


class _StderrHandler(logging.StreamHandler):
    """Writes to whatever ``sys.stderr`` is at the time of the message (tests and embedders swap it)."""

    @property  # type: ignore[override]
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


_HANDLER = _StderrHandler()


def setup_logging(command: str, quiet: bool) -> None:
    """Session messages go to the current stderr as ``COMMAND: ...`` lines (INFO and up, or WARNING with -q)."""
    logger = logging.getLogger("hapmotion.live")
    _HANDLER.setFormatter(logging.Formatter(f"{command}: %(message)s"))
    if _HANDLER not in logger.handlers:
        logger.addHandler(_HANDLER)
        logger.propagate = False
    logger.setLevel(logging.WARNING if quiet else logging.INFO)
    # python-osc warns on the root logger for every unreadable bundle element; sessions count those themselves
    # ("logged once per kind"), so a flood of bad packets must not flood the terminal.
    logging.getLogger().addFilter(_not_pythonosc)


def _not_pythonosc(record: logging.LogRecord) -> bool:
    return "pythonosc" not in record.pathname


def silent_devices(sinks) -> list:
    """The device sinks (the bHaptics Player links, SDK1 and SDK2) that never delivered a single frame: the Player
    was never reached, or it never confirmed reading what was written."""
    # Imported here, not at the top: the live package loads the whole show (the audio analysis, scipy), which
    # every command's start-up (``--help``, ``info``) would otherwise pay for; only a finished session needs it.
    from ..live.sinks.ws_client import WebSocketClientSink

    return [s for s in sinks if isinstance(s, WebSocketClientSink) and s.stats.sent == 0]


def finish_session(engine, stats_json: Optional[str], command: str) -> list[str]:
    """Print the summary (headed by ``command``), write ``--stats-json`` atomically; return the outputs that could
    not be written, and the device sinks that never delivered a frame (the commands then exit with 1). Raises
    nothing: a session error in flight stays the one reported."""
    if engine is None:
        return []
    from ..filesafety import atomic_path

    log = logging.getLogger("hapmotion.live")
    stats = engine.stats
    try:
        for line in stats.summary_lines(command, getattr(engine.source, "speed", 1.0)):
            click.echo(line, err=True)
    except OSError:  # the terminal is gone (SIGHUP after an ssh session closed): the summary has nowhere to go
        pass
    lost = [f"{s.name}: {s.error}" for s in engine.sinks if getattr(s, "error", None)]
    for sink in silent_devices(engine.sinks):
        # a script must be able to tell that nothing reached the vest; a Player that dropped out mid-show after
        # taking frames is not this case (the show went on, and the summary counts what was not delivered)
        unconfirmed = sink.stats.undelivered
        why = f"{unconfirmed} written but never confirmed; " if unconfirmed else ""
        message = (f"{sink.name}: no frame reached the device ({why}is the bHaptics Player running and reachable? "
                   "see docs/player.md)")
        log.error("%s", message)
        lost.append(message)
    if stats_json:
        try:
            with atomic_path(stats_json) as tmp:
                tmp.write_text(json.dumps(stats.as_dict(), indent=1), encoding="utf-8")
        except Exception as exc:
            log.error("--stats-json %s not written: %s", stats_json, exc)
            lost.append(f"--stats-json: {exc}")
    return lost

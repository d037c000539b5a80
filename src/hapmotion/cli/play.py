"""``hapmotion play``: a saved track or a bHaptics pattern played in real time to a vest (docs/playback.md)."""

from __future__ import annotations

from typing import Optional

import click

from .kinds_help import KindsHelpCommand
from .motion_options import cli_limits, limit_option
from ..show.settings import Show
from .show_options import cue_port_option, rig_line, session_options, show_options, undriven_line

HELP = """Play TRACK in real time to the same sinks as 'hapmotion live'.

TRACK is any track or pattern 'hapmotion.load_track' reads: a rendered track (.csv .json .npz .tact) or a
bHaptics Designer pattern (.tact, played on the Player's 20 ms tick). Its columns go to the motors with the same
ids in the session layout (X40 + two shoulder sleeves by default); devices the layout lacks are left out and
noted once.

\b
SINK (one or more), as for 'hapmotion live' (nats:// publishes a live show: 'hapmotion live' only):
{SINK KINDS}
\b
Safety: the end of the track, Ctrl-C, SIGTERM, SIGHUP and errors all send turn-off to every sink before
exiting.
\b
Examples:
  hapmotion play Heartbeat.tact --sink player
  hapmotion play show.csv --sink player --sink ws-broadcast --loop --speed 0.5
"""


@click.command("play", help=HELP, cls=KindsHelpCommand)
@click.argument("track", type=click.Path(dir_okay=False))
@click.option("--sink", "sinks", metavar="SINK", multiple=True, required=True,
              help="Where rows go; repeat for several sinks at once.")
@click.option("--loop", is_flag=True, help="Start the track again at its end (until Ctrl-C).")
@click.option("--speed", type=float, default=1.0, show_default=True,
              help="Playback speed factor (2 = twice as fast), above 0 and at most 10.")
@session_options
@cue_port_option
@click.option("-q", "--quiet", is_flag=True, help="Only warnings and the summary.")
@limit_option
@show_options("layout", "cues")
def command(track: str, sinks: tuple[str, ...], loop: bool, speed: float, show_stats: bool,
            stats_json: Optional[str], workspace_id: Optional[str], api_key: Optional[str],
            cue_port: Optional[str], quiet: bool, limits: tuple[str, ...], show: Show) -> None:
    from ..live.playback import run_play
    from .session_report import finish_session, setup_logging

    setup_logging("play", quiet)
    input_limits = cli_limits(limits)
    if stats_json:
        from ..filesafety import check_writable

        check_writable(stats_json, "--stats-json")
    started = []

    def ready(engine) -> None:
        started.append(engine)
        names = ", ".join(s.describe() for s in engine.sinks)
        click.echo(f"play: {track} ({engine.source.n} rows at {engine.source.fps:g}/s"
                   f"{', looped' if loop else ''}) on {rig_line(show.layout)} to {names}; Ctrl-C stops", err=True)
        undriven = undriven_line(show.layout)
        if undriven:
            click.echo(f"play: {undriven}", err=True)
        trigger = getattr(engine.cues, "trigger", None)
        if trigger is not None:
            click.echo(f"play: cues fired on {trigger.describe()} NAME [gain] ({trigger.exposure()}); "
                       f"names: {', '.join(engine.cues.names)}", err=True)

    try:
        run_play(track, list(sinks), show=show, speed=speed, loop=loop, workspace_id=workspace_id,
                 api_key=api_key, on_ready=ready, stats_interval=1.0 if show_stats else None,
                 on_stats=lambda text: click.echo(f"play: {text}", err=True), cue_port=cue_port,
                 limits=input_limits)
    finally:
        lost = finish_session(started[0] if started else None, stats_json, "play")
    if lost:
        raise click.exceptions.Exit(1)

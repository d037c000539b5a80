"""``hapmotion live``: performer motion in, vest vibration out, in real time (docs/live.md)."""

from __future__ import annotations

from typing import Optional

import click

from ..show import Show
from .audience_options import publisher_security_options
from .kinds_help import KindsHelpCommand
from .motion_options import CLI_SPELLING, motion_options, read_motion
from .show_options import cue_port_option, rig_line, session_options, show_options, split_values, undriven_line
from .token_option import token_options
from .session_report import finish_session, setup_logging

HELP = """Render a live skeleton stream frame by frame and drive haptic devices, recorders and viewers.

\b
SOURCE (one):
{SOURCE KINDS}
  OSC messages: /hapmotion/skeleton [seq t] x0 y0 z0 .. x31 y31 z31 (32 joints, metres, +Y up), or
  /hapmotion/joint/HAND_LEFT [seq t] x y z + /hapmotion/frame [seq t]; WebSocket JSON text frames:
  {"seq": 7, "t": 0.116, "joints": {"HAND_LEFT": [x, y, z], ...}}; replay: the reader options --units, --up,
  --skip-frames, ... as for render; --speed, --loop (docs/live.md, docs/vmc.md)
\b
Who may send: sources listen on loopback unless SOURCE names another interface (osc://0.0.0.0:9000). Browser
pages are refused unless --allow-origin lists them; --token makes WebSocket senders present a shared secret
(header "Authorization: Bearer TOKEN" or ws://HOST:PORT/?token=TOKEN); --allow-sender limits sender addresses.
At most --max-senders senders at once, each with its own message budget. The startup line says what is exposed.
\b
SINK (one or more):
{SINK KINDS}
\b
Safety: a source silent for --stall-ms fades every actuator to zero; Ctrl-C, SIGTERM, the end of a replay or an
error sends turn-off to every sink before exiting. A summary (frames in/out/dropped/late, p50/p99 latency) is
printed at exit.
\b
Cues: --cues show.cues layers authored patterns (bHaptics .tact or tracks) onto the rows at their show times;
with --cue-port 9002 a lighting desk or Unity fires named cues: /hapmotion/cue NAME [gain] (OSC over UDP).
\b
Examples:
  hapmotion live --source osc://0.0.0.0:9000 --allow-sender 192.168.1.20 --sink player --sink ws-broadcast
  hapmotion live --source replay:dance.bvh --loop --audio song.ogg --sink player --sink record:show.tact
"""


@click.command("live", help=HELP, cls=KindsHelpCommand)
@publisher_security_options
@click.option("--source", "source", metavar="SOURCE", help="Where the skeleton comes from (see above).")
@click.option("--sink", "sinks", metavar="SINK", multiple=True, required=True,
              help="Where frames go; repeat for several sinks at once.")
@click.option("--speed", type=float, default=1.0, show_default=True, help="Replay speed factor.")
@click.option("--loop", is_flag=True, help="Replay (or audio-only playback) starts again at the end.")
@click.option("--stall-ms", type=float, default=250.0, show_default=True,
              help="A silent source has faded every actuator to zero after this many milliseconds.")
@session_options
@click.option("--allow-origin", "allow_origins", metavar="ORIGIN[,ORIGIN]", multiple=True,
              help="ws:// source: web page origins (https://show.example) allowed to connect; browser pages are "
                   "refused otherwise. Programs (no Origin header) are not affected.")
@token_options
@click.option("--allow-sender", "allow_senders", metavar="IP[,IP]", multiple=True,
              help="Network sources: only these sender addresses (or networks, 10.0.0.0/24) may send.")
@click.option("--max-senders", type=click.IntRange(min=1), default=8, show_default=True,
              help="Network sources: senders served at once (WebSocket connections, OSC sender addresses).")
@cue_port_option
@click.option("-q", "--quiet", is_flag=True, help="Only warnings and the summary.")
@motion_options
@show_options("method", "preset", "mirror", "param", "layout", "fps", "audio", "audio_offset", "mode", "mix",
              "mix_rule", "cues")
def command(source: Optional[str], sinks: tuple[str, ...], speed: float, loop: bool, stall_ms: float,
            show_stats: bool, stats_json: Optional[str], workspace_id: Optional[str], api_key: Optional[str],
            allow_origins: tuple[str, ...], token: Optional[str], allow_senders: tuple[str, ...], max_senders: int,
            cue_port: Optional[str], quiet: bool, show: Show, motion_opts: dict) -> None:
    from .. import audience  # noqa: F401 (registers the nats:// sink kind)
    from ..live import run_live

    setup_logging("live", quiet)

    started = []

    def ready(engine) -> None:
        started.append(engine)
        names = ", ".join(s.describe() for s in engine.sinks)
        exposure = engine.source.exposure()
        click.echo(f"live: listening on {engine.source.describe()}" + (f" ({exposure})" if exposure else "")
                   + f"; on {rig_line(show.layout)}; sinks: {names}; Ctrl-C stops", err=True)
        undriven = undriven_line(show.layout)
        if undriven:
            click.echo(f"live: {undriven}", err=True)
        trigger = getattr(engine.cues, "trigger", None)
        if trigger is not None:
            click.echo(f"live: cues fired on {trigger.describe()} NAME [gain] ({trigger.exposure()}); "
                       f"names: {', '.join(engine.cues.names)}", err=True)

    # User mistakes (HapMotionError) and Ctrl-C before the session is up are reported by hapmotion.cli.main as one
    # line (exit 2 / 130); once the session runs, SIGINT/SIGTERM are a clean stop (exit 0).
    if stats_json:
        from ..filesafety import check_writable

        check_writable(stats_json, "--stats-json")
    src = _source(source, fps=show.fps, speed=speed, loop=loop, motion_opts=motion_opts,
                  allow_origins=split_values(allow_origins), token=token, allow_senders=allow_senders,
                  max_senders=max_senders)
    try:
        run_live(show, src, list(sinks), speed=speed, loop=loop, stall_ms=stall_ms,
                 stats_interval=1.0 if show_stats else None, workspace_id=workspace_id, api_key=api_key,
                 on_ready=ready, on_stats=lambda text: click.echo(f"live: {text}", err=True), cue_port=cue_port)
    finally:
        # The summary is printed however the session ended (turn-off has been sent by then). Nothing here raises:
        # a session error in flight stays the one reported.
        lost = finish_session(started[0] if started else None, stats_json, "live")
    if lost:  # the show ran but an output it was asked for is missing (already logged)
        raise click.exceptions.Exit(1)


def _source(text: Optional[str], *, fps: Optional[float], speed: float, loop: bool, motion_opts: dict,
            allow_origins: tuple[str, ...], token: Optional[str], allow_senders: tuple[str, ...],
            max_senders: int):
    """The source object for ``--source`` with every option that applies to it; UsageError naming an option given
    to a source it does not apply to. None without ``--source`` (``--mode audio``)."""
    from ..errors import UsageError
    from ..live.access import SenderAllowList
    from ..live.sources import ReplaySource, network_source
    from ..live.urls import parse_source

    reader_given = [CLI_SPELLING.get(k if k != "fps_in" else "fps", k) for k, v in motion_opts.items()
                    if v is not None]
    access_given = [name for name, v in (("--allow-origin", allow_origins), ("--token", token),
                                         ("--allow-sender", allow_senders)) if v]
    if text is None:
        if reader_given or access_given:
            raise UsageError(f"{(reader_given + access_given)[0]} applies to a --source")
        return None
    ep = parse_source(text)
    if ep.kind == "replay":
        if access_given:
            raise UsageError(f"{access_given[0]} applies to network sources (osc://, ws://), not to replay:")
        return ReplaySource(read_motion(ep.path, **motion_opts), fps=fps, speed=speed, loop=loop, path=ep.path)
    if reader_given:
        raise UsageError(f"{reader_given[0]} is a reader option: it applies to replay:FILE sources")
    return network_source(ep, allow_origins=allow_origins, token=token,
                          allow_senders=SenderAllowList.parse(allow_senders), max_senders=max_senders)

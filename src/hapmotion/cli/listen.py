"""``hapmotion listen``: one audience seat renders a show published on NATS, with its own settings
(docs/audience.md)."""

from __future__ import annotations

from typing import Optional

import click

from ..show.comfort import Comfort
from .audience_options import seat_security_options, seat_sync_options
from .show_options import (check_preset, comfort_options, cues_option, layout_option, method_option, mirror_option,
                           mode_option, param_option, parse_param_overrides, preset_option, read_cues, rig_line,
                           rig_of, rig_option, split_values)

HELP = """Render a show published with `hapmotion live ... --sink nats://HOST:PORT/SHOW` on this seat's vest.

\b
SHOW_URL: nats://HOST:PORT/SHOW or tls://HOST:PORT/SHOW (default port 4222).
The seat reads the show's description (renderer, music mix, frame rate, the performer's body) from the server,
renders the performer's skeleton with the same Renderer, mixes the music's channel, then applies its own
settings. Each frame plays --delay after its media time arrived live, so the vest matches a video/audio stream
running that far behind the venue; with --sync audio the seat finds that delay itself, by matching the music this
computer plays (its output's loopback, by default) against the venue's reference, and follows it when the stream
re-buffers or drifts (--delay is then a fine offset on top). The audio never leaves this computer.
\b
SINK (one or more): the sinks of `hapmotion live` (player, player-v3, osc://, ws-broadcast, record:PATH).
\b
Trust: only what the venue signed plays (--venue-pubkey FILE); --unsigned is a rehearsal without keys. NATS
credentials and TLS come from files and the environment (--nats-nkey, --nats-creds, --nats-ca, ...), never from the
command line or the URL.
\b
Safety: a silent show (lost connection, publisher stopped) fades every actuator to zero within the show's stall
time; Ctrl-C or SIGTERM turns every motor off before exiting.
\b
Examples:
  hapmotion listen tls://venue.example:4222/concert --venue-pubkey venue.pub --nats-nkey seat.nk --sink player
  hapmotion listen nats://127.0.0.1:4222/concert --unsigned --sink player --no-mirror --gain 0.7 --delay 180
  hapmotion listen tls://venue.example:4222/concert --venue-pubkey venue.pub --nats-nkey seat.nk --sink player --sync audio
"""


@click.command("listen", help=HELP)
@seat_security_options
@seat_sync_options
@click.argument("show_url", metavar="SHOW_URL")
@click.option("--sink", "sinks", metavar="SINK", multiple=True, required=True,
              help="Where the seat's frames go; repeat for several sinks at once.")
@click.option("--delay", "delay_ms", type=float, default=0.0, show_default=True,
              help="Milliseconds this seat's video/audio stream runs behind the venue (0..60000).")
@mirror_option
@method_option(default=None, help_suffix=" [default: the show's]")
@preset_option(default=None, help_suffix=" [default: the show's]")
@mode_option
@param_option
@layout_option
@rig_option
@click.option("--zone-off", "zones_off", metavar="ZONE[,ZONE]", multiple=True,
              help="Devices (VestBack, ForearmL, ...) or actuators (VestFront_5) that stay off.")
@click.option("--stats", "show_stats", is_flag=True, help="Print frame counts and latency every second.")
@click.option("-q", "--quiet", is_flag=True, help="Only warnings and the summary.")
@cues_option
@comfort_options
def command(show_url: str, sinks: tuple[str, ...], delay_ms: float, mirror: Optional[bool], method: Optional[str],
            preset: Optional[str], mode: Optional[str], params: tuple[str, ...], layout_file: Optional[str],
            rig: Optional[str], zones_off: tuple[str, ...], show_stats: bool, quiet: bool, cues: Optional[str],
            comfort: Comfort, security, sync) -> None:
    from ..audience import Seat, run_listen
    from ..audience.listener import parse_show_url
    from .session_report import finish_session, setup_logging

    setup_logging("listen", quiet)
    parse_show_url(show_url)  # a usage error before anything connects
    check_preset(preset)      # (the seat applies it only when the show's description comes)
    layout = layout_file
    if rig is not None:  # the seat's own wearables; the energy split unless the seat asks for the paper preset
        from ..layout import load_layout

        layout = load_layout(layout_file)
        layout = layout.with_rig(rig_of(rig, layout, energy=preset != "paper"))
    seat = Seat(method=method, preset=preset, mirror=mirror, mode=mode, overrides=parse_param_overrides(params),
                layout=layout, zones_off=split_values(zones_off), comfort=comfort, delay_s=delay_ms / 1000.0)
    sessions: list = []

    def ready(engine) -> None:
        names = ", ".join(s.describe() for s in engine.sinks)
        trust = engine.source.trust.describe()
        timing = (f"delay {delay_ms:g} ms" if sync is None else
                  f"--sync audio from {engine.source.sync.audio.describe()}, fine offset {delay_ms:g} ms")
        click.echo(f"listen: {show_url} ({timing}, {trust}); on {rig_line(layout)}; sinks: {names}; Ctrl-C stops",
                   err=True)

    try:
        run_listen(show_url, list(sinks), seat=seat, security=security, on_ready=ready, sessions=sessions, sync=sync,
                   cues=read_cues(cues),
                   stats_interval=1.0 if show_stats else None,
                   on_stats=lambda text: click.echo(f"listen: {text}", err=True))
    finally:
        lost = finish_session(sessions[-1][0] if sessions else None, None, "listen")
        if sync is not None and sessions and sessions[-1][1].sync is not None:
            state = sessions[-1][1].sync.state
            click.echo(f"listen: sync {state.state}; {state.locks} lock(s), {state.jumps} jump(s) followed", err=True)
    if lost:
        raise click.exceptions.Exit(1)

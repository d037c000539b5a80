"""``hapmotion check``: connect to the bHaptics Player, report its devices, play a labelled test pattern
(docs/playback.md)."""

from __future__ import annotations

from typing import Optional

import click

from ..show.settings import Show
from .show_options import show_options

HELP = """Check the haptic set-up before a show: connect to the bHaptics Player, report the devices it says are
connected, then play a short labelled test pattern so the wearer can confirm where each motor is.

\b
For each device of the layout (vest front, vest back, left and right shoulder sleeve): all its motors, then the
wearer's left and right column (edge), then the top and bottom row (front and back edge on a shoulder). With --rig,
each device of each wearable instead (gloves: thumb, little finger, wrist). Each step's label is printed as it
plays; the check ends with turn-off. The report names the rig the connected devices make.
\b
Examples:
  hapmotion check --sink player
  hapmotion check --sink player-v3 --workspace-id APP --api-key KEY --step-ms 800
  hapmotion check --rig pro+gloves --sink player
"""


@click.command("check", help=HELP)
@click.option("--sink", "sinks", metavar="SINK", multiple=True, default=("player",), show_default=True,
              help="The Player (player, player-v3; any live SINK also gets the pattern); repeatable.")
@click.option("--step-ms", type=click.IntRange(min=100, max=5000), default=500, show_default=True,
              help="How long each step plays.")
@click.option("--gap-ms", type=click.IntRange(min=0, max=5000), default=250, show_default=True,
              help="Silence between steps.")
@click.option("--intensity", type=click.FloatRange(min=1.0, max=100.0), default=60.0, show_default=True,
              help="Intensity of the test pattern, 0..100.")
@click.option("--no-pattern", is_flag=True, help="Only report the Player's devices.")
@click.option("--workspace-id", envvar="BHAPTICS_WORKSPACE_ID", default=None,
              help="bHaptics SDK2 workspace (app) id for player-v3 [env BHAPTICS_WORKSPACE_ID].")
@click.option("--api-key", envvar="BHAPTICS_API_KEY", default=None,
              help="bHaptics SDK2 API key for player-v3 [env BHAPTICS_API_KEY].")
@show_options("layout", comfort=False)
def command(sinks: tuple[str, ...], step_ms: int, gap_ms: int, intensity: float, no_pattern: bool,
            workspace_id: Optional[str], api_key: Optional[str], show: Show) -> None:
    # imported here, not at the top, like the live modules: asyncio alone is 30 ms of every command's start-up
    import asyncio

    from ..bhaptics.device_map import DeviceMap
    from ..live.player_check import CHECK_FPS, pattern_steps, pattern_track, probe_player, rig_pattern_steps
    from ..live.playback import run_play
    from ..live.kinds import build_sink
    from ..live.urls import parse_sink
    from .session_report import setup_logging

    setup_logging("check", quiet=True)  # the check prints its own lines; the session's warnings still show
    layout = show.load_layout()
    rig = layout.rig
    if rig is not None:  # the rig's own motors, every device of every wearable, with no body chart in between
        layout = rig.motor_layout()
        show = show.replace(layout=layout)
    dmap = DeviceMap.from_layout(layout) if rig is None else DeviceMap.for_rig(rig)
    objs = [build_sink(parse_sink(s), dmap=dmap, layout_name=layout.name, fps=CHECK_FPS, workspace_id=workspace_id,
                       api_key=api_key, meta={"mode": "check"}) for s in sinks]
    reports = [r for r in (asyncio.run(probe_player(s, layout)) for s in objs) if r is not None]
    for report in reports:
        for line in report.lines():
            click.echo(f"check: {line}")
    unreachable = [r for r in reports if not r.reachable]
    if unreachable and len(unreachable) == len(objs):
        raise click.exceptions.Exit(1)  # nothing to play to
    if no_pattern:
        return
    steps = pattern_steps(layout) if rig is None else rig_pattern_steps(rig)
    track, marks = pattern_track(layout, steps, step_s=step_ms / 1000.0, gap_s=gap_ms / 1000.0,
                                 intensity=intensity)
    click.echo(f"check: test pattern, {len(steps)} steps of {step_ms} ms (Ctrl-C stops):")
    count = iter(range(1, len(steps) + 1))
    run_play(track, objs, show=show, on_mark=lambda label: click.echo(f"check: {next(count):2d}. {label}"),
             marks=marks)
    click.echo("check: done, every motor turned off")
    if unreachable:
        raise click.exceptions.Exit(1)

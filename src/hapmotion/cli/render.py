"""``hapmotion render``: a recording (and/or a song) to a haptic track file."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Optional

import click

from ..errors import UsageError
from ..layout import load_layout
from ..rig import motor_columns, own_rig, rig_places, rig_track
from ..show.settings import Show
from ..track_files.sniff import is_track_file
from .motion_options import CLI_SPELLING, motion_options, read_motion, read_track
from .show_options import show_options, undriven_line


def progress_bar(total: int, label: str):
    """A tqdm bar on stderr, shown only for long jobs on a terminal; returns (update callable, close callable)."""
    from tqdm import tqdm

    show = total >= 200_000 and sys.stderr.isatty()
    bar = tqdm(total=total, desc=label, unit="frame", disable=not show, file=sys.stderr, leave=False)
    return bar.update, bar.close


@click.command()
@click.argument("motion_file", required=False, type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help="Track file to write: .tact (bHaptics Designer; sleeves go to OUT.ForearmL/R.tact), .csv, .json, .npz.")
@motion_options
@show_options()
def command(motion_file: Optional[str], output: str, show: Show, motion_opts: dict) -> None:
    """Render MOTION_FILE (BVH, Azure Kinect JSON, AIST++ .pkl, CSV/NPZ joints) into a haptic track.

    A track or pattern in place of MOTION_FILE (a bHaptics Designer .tact, or a track hapmotion wrote) is converted
    to the format of -o, at its own rate or at --fps (resampled, every peak kept); no other option applies to it.

    With --audio the music is rendered too and mixed with the motion (audio:motion = 2:3; the default mix rule
    makes room for the motion, --mix-rule paper is the HapMotion paper's weighted sum); with --audio and no
    MOTION_FILE the track is the music alone. --cues layers authored patterns on top; --gain and the comfort limits
    come last.
    """
    if motion_file is None and show.audio is None:
        raise UsageError("give a MOTION_FILE to render, or --audio SONG for the music alone")
    if motion_file is not None and is_track_file(motion_file):
        convert_track(motion_file, output, show, motion_opts or {})
        return
    # imported here, not at the top: rendering pulls in the music analysis (scipy), which `hapmotion --help` and
    # every other command's start-up would otherwise pay for
    from ..show import render_show
    from ..show.offline import render_input
    from ..track_files import save_track

    mode = show.resolved_mode(motion_file is not None)
    out_path = Path(output)
    motion = None
    if motion_file is not None:  # in audio mode too: the music then plays on the motion's timeline
        # only what the render reads is kept: an hour at 120 fps lets 330 MB of positions go before rendering,
        # a block of frames at a time as the render joints are copied (the read motion is used by nothing else)
        motion = render_input(show, read_motion(motion_file, **(motion_opts or {})), let_go=True)
    total = motion.n_frames if motion is not None else 0
    update, close = progress_bar(total, "rendering")
    try:
        # a .tact file holds no renderer debug: the renderer writes none (an hour at 120 fps: 58 MB less)
        track = render_show(show, motion, progress=update, debug=out_path.suffix.lower() != ".tact")
    finally:
        close()
    del motion  # its joints are not needed to write the track
    # on the --rig wearables (none: the body chart as rendered); a .tact file holds the slots bHaptics addresses
    track = rig_track(track, show.load_layout(), slots=out_path.suffix.lower() == ".tact")
    if out_path.suffix.lower() == ".tact" and track.debug:  # a .tact file holds no debug: let it go before writing
        track = dataclasses.replace(track, debug={})
    written = save_track(track, out_path)
    undriven = undriven_line(show.layout)
    if undriven:
        click.echo(undriven, err=True)
    peak = float(track.intensities.max()) if track.n_frames else 0.0
    also = f" and {', '.join(p.name for p in written[1:])}" if len(written) > 1 else ""
    click.echo(f"wrote {out_path}{also} ({track.n_frames} frames at {track.fps:g} fps, {track.duration:.2f} s, "
               f"mode {mode}, peak {peak:.0f}%)")


def rig_of(show: Show) -> bool:
    """Whether ``show`` is played on a ``--rig``."""
    return getattr(show.layout, "rig", None) is not None


def convert_track(path: str, output: str, show: Show, motion_opts: dict) -> None:
    """Write the track or pattern at ``path`` in the format of ``output`` (``show.fps``: resampled to that rate, the
    maximum of the rows each new row covers). Options that shape a render (method, music, cues, comfort) or read
    motion are refused by name: a stored track is converted as it is, never re-rendered."""
    given = [CLI_SPELLING.get(k if k != "fps_in" else "fps", k) for k, v in motion_opts.items()
             if v is not None and k != "limits"]
    if given:
        raise UsageError(f"{given[0]} is a motion reader option; {path} is a haptic track or pattern")
    if dataclasses.replace(show, fps=None, layout=None if rig_of(show) else show.layout) != Show():
        raise UsageError(f"{path} is a haptic track or pattern: render converts it as it is (only -o, --fps and "
                         "--limit apply); play it with cues or comfort limits with 'hapmotion play'")
    from ..track_files import save_track  # as in command(): the track files load with what they write

    track = read_track(path, **motion_opts)
    if show.fps is not None:
        track = track.resample(show.fps)
    tact = Path(output).suffix.lower() == ".tact"
    own, how = own_rig(track), ""
    if rig_of(show):  # a pattern of one wearable played on another, through the body chart
        layout = show.load_layout()
        if own is not None and motor_columns(own, layout.rig.actuators, rig_places(layout.rig)) is None:
            how = f", from the rig {own.name} through the body chart"
        track = rig_track(track, layout, slots=tact)
        undriven = undriven_line(layout) if how or own is None else None  # through the body chart
        if undriven:
            click.echo(undriven, err=True)
    elif own is not None and tact:  # a rig's own track: its motors on the SDK1 slots they play, as they are
        track = rig_track(track, load_layout().with_rig(own), slots=True)
    written = save_track(track, Path(output))
    also = f" and {', '.join(p.name for p in written[1:])}" if len(written) > 1 else ""
    click.echo(f"wrote {output}{also} ({track.n_frames} frames at {track.fps:g} fps, {track.duration:.2f} s, "
               f"converted from {path}{how})")

"""``hapmotion render``: a recording (and/or a song) to a haptic track file."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional

import click

from ..errors import UsageError
from ..show.settings import Show
from .motion_options import motion_options, read_motion
from .show_options import show_options


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

    With --audio the music is rendered too and mixed with the motion (audio:motion = 2:3; the default mix rule
    makes room for the motion, --mix-rule paper is the HapMotion paper's weighted sum); with --audio and no
    MOTION_FILE the track is the music alone. --cues layers authored patterns on top; --gain and the comfort limits
    come last.
    """
    if motion_file is None and show.audio is None:
        raise UsageError("give a MOTION_FILE to render, or --audio SONG for the music alone")
    # imported here, not at the top: rendering pulls in the music analysis (scipy), which `hapmotion --help` and
    # every other command's start-up would otherwise pay for
    from ..show import render_show
    from ..track_files import save_track

    mode = show.resolved_mode(motion_file is not None)
    out_path = Path(output)
    motion = None
    if motion_file is not None:  # in audio mode too: the music then plays on the motion's timeline
        motion = read_motion(motion_file, **(motion_opts or {}))
    total = motion.n_frames if motion is not None else 0
    update, close = progress_bar(total, "rendering")
    try:
        track = render_show(show, motion, progress=update)
    finally:
        close()
    written = save_track(track, out_path)
    peak = float(track.intensities.max()) if track.n_frames else 0.0
    also = f" and {', '.join(p.name for p in written[1:])}" if len(written) > 1 else ""
    click.echo(f"wrote {out_path}{also} ({track.n_frames} frames at {track.fps:g} fps, {track.duration:.2f} s, "
               f"mode {mode}, peak {peak:.0f}%)")

"""``hapmotion plot``: a printable figure of a track (actuator heat map, total intensity, motion energy)."""

from __future__ import annotations

from pathlib import Path

import click

from typing import Optional

from ..errors import UsageError
from ..show.settings import Show
from .motion_options import motion_options, read_motion, read_track
from .render import progress_bar
from .show_options import show_options, undriven_line


@click.command("plot")
@click.argument("input_path", metavar="INPUT", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Figure to write: .png, .pdf or .svg (default: INPUT's name with .png).")
@click.option("--start", "start_s", type=float, default=None, help="Draw from this time (s).")
@click.option("--end", "end_s", type=float, default=None, help="Draw up to this time (s).")
@click.option("--title", default=None, help="Figure title (default: INPUT's file name).")
@click.option("--dpi", type=click.IntRange(50, 600), default=150, show_default=True, help="Resolution of a PNG.")
@click.option("--vmax", default="auto", show_default=True, metavar="auto|NUMBER",
              help="Intensity at the top of the colour scale; auto fits weak tracks (5, 10, 20, 25, 50 or 100).")
@motion_options
@show_options("method", "preset", "mirror", "param", "layout", "fps", "audio", "audio_offset", "mode", "mix",
              "mix_rule", "cues")
def command(input_path: Path, output: Optional[Path], start_s: Optional[float], end_s: Optional[float],
            title: Optional[str], dpi: int, vmax: str, show: Show, motion_opts: dict) -> None:
    """Draw INPUT as a static figure: which actuators run when (grouped vest front, vest back, left and right
    shoulder), the total intensity and the motion energy.

    INPUT is a motion file (rendered with --method/--preset) or a saved track (.csv, .json, .npz, .tact).

    \b
    Examples:
      hapmotion plot dance.bvh -o dance.png
      hapmotion plot dance.npz --start 10 --end 40 -o detail.pdf
    """
    from ..viewer.page import load_audio_part
    from .view_input import read_view_input
    from ..viewer.plot import plot_track

    if vmax != "auto":
        try:
            vmax = float(vmax)
        except ValueError:
            raise UsageError(f"--vmax expects auto or a number 0..100, got {vmax!r}") from None
    if output is None:
        output = Path(input_path.stem + ".png")
    if output.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"{output}: the figure format follows the extension; use .png, .pdf or .svg")
    audio_path = show.audio
    mode = show.mode or ("multimodal" if audio_path else "motion")
    loaded = read_view_input(input_path, show, methods=[show.method], presets=[show.preset], modes=[mode],
                             read_motion=lambda path: read_motion(path, **motion_opts),
                             read_track=lambda path: read_track(path, **motion_opts), progress=progress_bar)
    track = loaded.tracks[0]
    audio = load_audio_part(audio_path, fps=track.fps, offset_s=show.audio_offset_s) if audio_path is not None else None
    plot_track(track, output, title=title or input_path.name, audio=audio, start_s=start_s, end_s=end_s, dpi=dpi,
               vmax=vmax)
    for note in loaded.notes:
        click.echo(f"note: {note}", err=True)
    undriven = undriven_line(show.layout)
    if undriven:
        click.echo(undriven, err=True)
    click.echo(f"wrote {output}")

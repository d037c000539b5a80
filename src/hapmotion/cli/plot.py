"""``hapmotion plot``: a printable figure of a track (actuator heat map, total intensity, motion energy)."""

from __future__ import annotations

from pathlib import Path

import click

from ..errors import UsageError
from ..show import MODES
from .motion_options import motion_options, read_motion, read_track
from .show_options import comfort_options, cues_option, mix_rule_option, preset_option, read_cues
from .render import progress_bar


@click.command("plot")
@click.argument("input_path", metavar="INPUT", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Figure to write: .png, .pdf or .svg (default: INPUT's name with .png).")
@click.option("--method", default="mst", show_default=True, help="Renderer method for a motion file: mst or baseline.")
@preset_option
@click.option("--mirror/--no-mirror", default=None,
              help="Audience feels the performer mirrored (default: the preset's choice, mirrored).")
@click.option("--audio", "audio_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Music: adds its waveform and onsets as a fourth panel (and is mixed in, see --mode).")
@click.option("--mode", type=click.Choice(MODES), default=None,
              help="What the heat map shows: motion, multimodal (music and motion mixed) or audio. "
                   "Default: multimodal with --audio, else motion.")
@click.option("--mix", "mix_ratio", default="2:3", show_default=True, help="audio:motion ratio of the multimodal mix.")
@click.option("--audio-offset", type=float, default=0.0, show_default=True,
              help="Seconds into the recording at which the music starts.")
@click.option("--start", "start_s", type=float, default=None, help="Draw from this time (s).")
@click.option("--end", "end_s", type=float, default=None, help="Draw up to this time (s).")
@click.option("--title", default=None, help="Figure title (default: INPUT's file name).")
@click.option("--dpi", type=click.IntRange(50, 600), default=150, show_default=True, help="Resolution of a PNG.")
@click.option("--vmax", default="auto", show_default=True, metavar="auto|NUMBER",
              help="Intensity at the top of the colour scale; auto fits weak tracks (5, 10, 20, 25, 50 or 100).")
@mix_rule_option
@cues_option
@comfort_options
@motion_options
def command(input_path, output, method, preset, mirror, audio_path, mode, mix_ratio, audio_offset, start_s, end_s,
            title, dpi, vmax, mix_rule, cues, comfort, motion_opts):
    """Draw INPUT as a static figure: which actuators run when (grouped vest front, vest back, left and right
    shoulder), the total intensity and the motion energy.

    INPUT is a motion file (rendered with --method/--preset) or a saved track (.csv, .json, .npz, .tact).

    \b
    Examples:
      hapmotion plot dance.bvh -o dance.png
      hapmotion plot dance.npz --start 10 --end 40 -o detail.pdf
    """
    from ..audio.mix import parse_mix_ratio
    from ..renderer.params import METHODS, PRESETS
    from ..show import Show, split_list
    from ..viewer.page import load_audio_part
    from .view_input import read_view_input
    from ..viewer.plot import plot_track

    if vmax != "auto":
        try:
            vmax = float(vmax)
        except ValueError:
            raise UsageError(f"--vmax expects auto or a number 0..100, got {vmax!r}") from None
    split_list(method, "method", METHODS)
    split_list(preset, "preset", tuple(PRESETS))
    if output is None:
        output = Path(input_path.stem + ".png")
    if output.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"{output}: the figure format follows the extension; use .png, .pdf or .svg")
    mode = mode or ("multimodal" if audio_path else "motion")
    show = Show(mirror=mirror, audio=audio_path, audio_offset_s=audio_offset, mix_ratio=parse_mix_ratio(mix_ratio),
                mix_rule=mix_rule, cues=read_cues(cues, motion_opts), comfort=comfort)
    loaded = read_view_input(input_path, show, methods=[method], presets=[preset], modes=[mode],
                             read_motion=lambda path: read_motion(path, **motion_opts),
                             read_track=lambda path: read_track(path, **motion_opts), progress=progress_bar)
    track = loaded.tracks[0]
    audio = load_audio_part(audio_path, fps=track.fps, offset_s=audio_offset) if audio_path is not None else None
    plot_track(track, output, title=title or input_path.name, audio=audio, start_s=start_s, end_s=end_s, dpi=dpi,
               vmax=vmax)
    for note in loaded.notes:
        click.echo(f"note: {note}", err=True)
    click.echo(f"wrote {output}")

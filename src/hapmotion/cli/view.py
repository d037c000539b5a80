"""``hapmotion view``: write one self-contained HTML page that plays a recording as the vest feels it."""

from __future__ import annotations

from pathlib import Path

import click

from typing import Optional

from ..errors import UsageError
from ..renderer.params import METHODS, PRESETS
from ..show.settings import MODES, Show
from .motion_options import motion_options, read_motion, read_track
from .render import progress_bar
from .show_options import show_options, split_list


@click.command("view")
@click.argument("input_path", metavar="INPUT", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Page to write (default: INPUT's name with .html in the current folder, or live.html).")
@click.option("--mode", "modes", default=None, metavar="LIST",
              help="What the vest shows: motion, multimodal (music and motion mixed) or audio; a comma list gives "
                   "a switch. Default: multimodal with --audio, else motion.")
@click.option("--methods", default=None, metavar="LIST",
              help="Several methods, comma-separated (e.g. mst,baseline); the page gets a switch.")
@click.option("--presets", default=None, metavar="LIST",
              help="Several presets, comma-separated (e.g. paper,energy); every method x preset is rendered.")
@click.option("--live", "live_url", default=None, metavar="URL",
              help="Make a page that shows a running `hapmotion live` broadcast, e.g. ws://127.0.0.1:8766.")
@click.option("--title", default=None, help="Title shown on the page (default: INPUT's file name).")
@click.option("--credit", multiple=True, metavar="TEXT",
              help="Attribution line for the page footer (e.g. the music's title, author and licence); repeatable.")
@motion_options
@show_options("method", "preset", "mirror", "param", "layout", "fps", "audio", "audio_offset", "mix", "mix_rule",
              "cues")
def command(input_path: Optional[Path], output: Optional[Path], modes: Optional[str], methods: Optional[str],
            presets: Optional[str], live_url: Optional[str], title: Optional[str], credit: tuple[str, ...],
            show: Show, motion_opts: dict) -> None:
    """Write a self-contained HTML viewer of INPUT (a motion file, or a saved track .csv/.json/.npz/.tact).

    The page needs no network: it holds the recording, the rendered intensities and the music. It shows the
    performer's skeleton in 3D with the motion salient triangle, the dynamic point and its ray to the vest; the
    vest's front and back panels and both shoulder sleeves as the wearer feels them; and a timeline with the
    actuator map, total intensity, motion energy and the music's waveform and onsets.

    With --live URL (or `?live=ws://...` added to any page's address) the page shows a live broadcast instead.

    \b
    Examples:
      hapmotion view dance.bvh --audio song.ogg -o dance.html
      hapmotion view dance.bvh --methods mst,baseline --presets paper,energy
      hapmotion view --live ws://127.0.0.1:8766 -o live.html
    """
    from .. import __version__
    from ..viewer.page import load_audio_part, write_page
    from .view_input import read_view_input

    if input_path is None and not live_url:
        raise UsageError("give a motion or track file to view, or --live URL for a live page")
    if live_url and not live_url.startswith(("ws://", "wss://")):
        raise UsageError(f"--live expects a ws:// or wss:// address, got {live_url!r}")
    audio_path = show.audio
    method_list = split_list(methods or show.method, "method", METHODS)
    preset_list = split_list(presets or show.preset, "preset", tuple(PRESETS))
    mode_list = split_list(modes or ("multimodal" if audio_path else "motion"), "mode", MODES)
    if input_path is None and live_url and (audio_path or modes or methods or presets):
        raise UsageError("a live-only page takes no --audio, --mode, --methods or --presets (the show sends them)")
    if output is None:
        output = Path(input_path.stem + ".html") if input_path is not None else Path("live.html")
    if output.suffix.lower() not in (".html", ".htm"):
        raise UsageError(f"{output}: the viewer writes an HTML page; give a name ending in .html")

    tracks, motion, notes, source_name = [], None, [], ""
    if input_path is not None:
        loaded = read_view_input(input_path, show, methods=method_list, presets=preset_list, modes=mode_list,
                                 read_motion=lambda path: read_motion(path, **motion_opts),
                                 read_track=lambda path: read_track(path, **motion_opts), progress=progress_bar)
        tracks, motion, notes, source_name = loaded.tracks, loaded.motion, loaded.notes, input_path.name
    audio = None
    if audio_path is not None:
        audio = load_audio_part(audio_path, fps=tracks[0].fps if tracks else 60.0, offset_s=show.audio_offset_s)
    footer = [f"source: {source_name}"] if source_name else []
    if audio is not None:
        footer.append(f"music: {audio.name}" + (f" (starts at {show.audio_offset_s:g} s)" if show.audio_offset_s else ""))
    footer.extend(credit)
    footer.append(f"made with hapmotion {__version__}")
    info = write_page(output, tracks, motion, audio=audio, live_url=live_url,
                      title=title if title is not None else (source_name or "live"), footer=footer)
    for note in notes:
        click.echo(f"note: {note}", err=True)
    what = f"{info.n_tracks} track{'s' if info.n_tracks != 1 else ''}, {info.duration_s:.1f} s" if tracks else "live"
    click.echo(f"wrote {info.path} ({info.n_bytes / 1e6:.2f} MB, {what})")

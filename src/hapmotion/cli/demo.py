"""``hapmotion demo``: the bundled dance with the bundled music, rendered the way the paper recommends."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import click

from ..show.settings import MODES, Show
from .show_options import preset_option

EXAMPLE_MOTION = "60_12_scaled.bvh"
"""CMU Graphics Lab Motion Capture Database, subject 60 trial 12 (salsa, lead dancer), Daz-friendly BVH,
uniformly rescaled by a third party. See examples/ATTRIBUTION.md."""
EXAMPLE_AUDIO = "vibe_ace.ogg"
""""Vibe Ace" by Kevin MacLeod, CC BY 3.0. See examples/ATTRIBUTION.md."""


def example_path(name: str) -> Path:
    """Path of a file shipped in ``hapmotion/examples``."""
    return Path(str(resources.files("hapmotion").joinpath("examples", name)))


@click.command()
@click.option("-o", "--out-dir", type=click.Path(file_okay=False), default="out", show_default=True,
              help="Folder for the results (created if missing).")
@click.option("--mode", type=click.Choice(MODES), default="multimodal", show_default=True)
@preset_option()
def command(out_dir, mode, preset):
    """Render the bundled salsa clip (CMU mocap) with the bundled music ("Vibe Ace", Kevin MacLeod) into
    OUT_DIR/demo.tact (+ sleeve files), demo.csv, a plot demo.png and a viewer page demo.html."""
    # imported here, not at the top: rendering pulls in the music analysis (scipy), which `hapmotion --help` and
    # every other command's start-up would otherwise pay for
    from ..motion_files import load_motion
    from ..show import render_show
    from ..track_files import save_track

    audio = example_path(EXAMPLE_AUDIO)
    show = Show(method="mst", preset=preset, mode=mode, audio=audio, length="motion")  # checked before any folder
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    motion = load_motion(example_path(EXAMPLE_MOTION))
    track = render_show(show, motion)
    from ..viewer.page import load_audio_part, write_page
    from ..viewer.plot import plot_track

    credits = ("Motion: CMU Graphics Lab Motion Capture Database (mocap.cs.cmu.edu), trial 60_12, salsa",
               "Music: \"Vibe Ace\" by Kevin MacLeod, CC BY 3.0")
    written = []
    for name in ("demo.tact", "demo.csv"):
        written.extend(save_track(track, out / name))
    title = f"{EXAMPLE_MOTION} + {EXAMPLE_AUDIO} ({mode}, mst/{preset})"
    audio_part = load_audio_part(audio, fps=track.fps, until_s=track.duration)  # the page ends with the dance
    plot_track(track, out / "demo.png", title=title, audio=audio_part)
    written.append(out / "demo.png")
    write_page(out / "demo.html", [track], motion, audio=audio_part, title=title, footer=credits)
    written.append(out / "demo.html")
    click.echo(f"demo: {motion.n_frames} frames at {motion.fps:g} fps ({motion.duration:.1f} s), mode {mode}, "
               f"peak {track.intensities.max():.0f}%")
    for p in written:
        click.echo(f"wrote {p}")
    click.echo("music: \"Vibe Ace\" by Kevin MacLeod (CC BY 3.0); motion: CMU Graphics Lab Motion Capture Database "
               "(mocap.cs.cmu.edu)")

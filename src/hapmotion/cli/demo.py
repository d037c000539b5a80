"""``hapmotion demo``: the bundled dance with the bundled music, rendered the way the paper recommends."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import click

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
@click.option("--mode", type=click.Choice(["multimodal", "motion", "audio"]), default="multimodal", show_default=True)
@click.option("--preset", default="paper", show_default=True)
def command(out_dir, mode, preset):
    """Render the bundled salsa clip (CMU mocap) with the bundled music ("Vibe Ace", Kevin MacLeod) into
    OUT_DIR/demo.tact (+ sleeve files), demo.csv, and, when the viewer is installed, demo.html and demo.png."""
    from ..audio import combine
    from ..readers import load_motion
    from ..render import render

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    motion = load_motion(example_path(EXAMPLE_MOTION))
    audio = example_path(EXAMPLE_AUDIO)
    motion_track = render(motion, method="mst", preset=preset)
    track = combine(motion_track, audio, mode=mode, ratio=(2.0, 3.0), offset_s=0.0, fps=motion_track.fps,
                    domain="linear", length="motion", actuators=motion_track.actuators)
    written = []
    for name in ("demo.tact", "demo.csv"):
        track.save(out / name)
        written.append(out / name)
    try:
        from ..viewer.plot import plot_track
    except ImportError:
        plot_track = None
    if plot_track is not None:
        plot_track(track, out / "demo.png", motion=motion, title=f"{EXAMPLE_MOTION} + {EXAMPLE_AUDIO} ({mode})")
        written.append(out / "demo.png")
    try:
        from ..viewer.page import write_page
    except ImportError:
        write_page = None
    if write_page is not None:
        write_page(out / "demo.html", motion=motion, tracks={f"mst/{preset}": track}, audio=audio)
        written.append(out / "demo.html")
    click.echo(f"demo: {motion.n_frames} frames at {motion.fps:g} fps ({motion.duration:.1f} s), mode {mode}, "
               f"peak {track.intensities.max():.0f}%")
    for p in written:
        click.echo(f"wrote {p}")
    click.echo("music: \"Vibe Ace\" by Kevin MacLeod (CC BY 3.0); motion: CMU Graphics Lab Motion Capture Database "
               "(mocap.cs.cmu.edu)")

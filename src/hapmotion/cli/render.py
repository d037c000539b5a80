"""``hapmotion render``: a recording (and/or a song) to a haptic track file."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click

from ..errors import UsageError
from ..renderer.params import METHODS
from ..show import LENGTH_RULES, MODES, Show, parse_param_overrides, render_show
from .motion_options import motion_options, read_motion
from .show_options import comfort_options, cues_option, mix_rule_option, preset_option, read_cues


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
@click.option("--method", type=click.Choice(METHODS), default="mst", show_default=True,
              help="mst: the paper's motion salient triangle; baseline: the active hand itself.")
@preset_option
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Override one renderer parameter (repeatable), e.g. --param release_alpha=0.2.")
@click.option("--no-mirror", is_flag=True, help="Feel the performer's left on the wearer's left (default: mirrored).")
@click.option("--fps", type=click.FloatRange(min=1.0, max=1000.0), default=None,
              help="Output rate: resample the motion to this many frames per second (default: the input's rate; "
                   "60 with --audio and no motion).")
@click.option("--layout", "layout_file", type=click.Path(dir_okay=False, exists=True), default=None,
              help="Device layout JSON (default: X40 + two shoulder Tactosy).")
@click.option("--audio", "audio_file", type=click.Path(dir_okay=False), default=None,
              help="Music file (WAV, FLAC, Ogg, MP3) for the audio channel.")
@click.option("--mode", type=click.Choice(MODES), default=None,
              help="Which channels: motion, audio, or multimodal (both mixed). Default: multimodal with a motion file and "
                   "--audio, audio with --audio alone, else motion.")
@click.option("--mix", "mix_ratio", default="2:3", show_default=True, help="audio:motion ratio of the multimodal mix.")
@mix_rule_option
@click.option("--audio-offset", type=float, default=0.0, show_default=True,
              help="Seconds to delay the music against the motion (negative: skip the start of the song).")
@click.option("--length", type=click.Choice(LENGTH_RULES), default="longer", show_default=True,
              help="Track length with both inputs: as long as the longer one, or cut to the motion.")
@cues_option
@comfort_options
@motion_options
def command(motion_file, output, method, preset, params, no_mirror, fps, layout_file, audio_file, mode, mix_ratio,
            mix_rule, audio_offset, length, cues, comfort, motion_opts=None):
    """Render MOTION_FILE (BVH, Azure Kinect JSON, AIST++ .pkl, CSV/NPZ joints) into a haptic track.

    With --audio the music is rendered too and mixed with the motion (audio:motion = 2:3; the default mix rule
    makes room for the motion, --mix-rule paper is the HapMotion paper's weighted sum); with --audio and no
    MOTION_FILE the track is the music alone. --cues layers authored patterns on top; --gain and the comfort limits
    come last.
    """
    from ..audio.mix import parse_mix_ratio

    if motion_file is None and audio_file is None:
        raise UsageError("give a MOTION_FILE to render, or --audio SONG for the music alone")
    if fps is not None and not math.isfinite(fps):  # click's FloatRange lets nan through
        raise UsageError(f"--fps must be a number in 1..1000, not {fps}")
    overrides = parse_param_overrides(params)
    show = Show(method=method, preset=preset, overrides=overrides, mirror=False if no_mirror else None, mode=mode,
                audio=audio_file, audio_offset_s=audio_offset, mix_ratio=parse_mix_ratio(mix_ratio),
                mix_rule=mix_rule, length=length, fps=fps, layout=layout_file, cues=read_cues(cues, motion_opts),
                comfort=comfort)
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
    written = track.save(out_path)
    peak = float(track.intensities.max()) if track.n_frames else 0.0
    also = f" and {', '.join(p.name for p in written[1:])}" if len(written) > 1 else ""
    click.echo(f"wrote {out_path}{also} ({track.n_frames} frames at {track.fps:g} fps, {track.duration:.2f} s, "
               f"mode {mode}, peak {peak:.0f}%)")

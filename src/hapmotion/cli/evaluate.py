"""``hapmotion evaluate``: objective metrics of every recording x method x preset, as tables and figures."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ..errors import UsageError
from ..show import parse_param_overrides
from .motion_options import motion_options, read_motion


def _names(text: str, option: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise UsageError(f"{option}: expected a comma-separated list, found {text!r}")
    return list(dict.fromkeys(names))


@click.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False),
              help="Report folder (created): metrics.md, metrics.csv, bench.csv and PNG figures.")
@click.option("--methods", default="mst,baseline", show_default=True,
              help="Comma-separated renderer methods to compare.")
@click.option("--presets", default="paper,energy", show_default=True,
              help="Comma-separated parameter presets to compare.")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Override a renderer parameter in every preset (repeatable); labels get a '*'.")
@click.option("--audio", "audio_file", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Song to mix with every track (2:3): adds onset agreement (+-50 ms), mix saturation, envelope r.")
@click.option("--no-figures", is_flag=True, help="Tables only (faster).")
@click.option("--no-bench", is_flag=True, help="Skip the synthetic sweep bench.")
@motion_options
def command(inputs, output, methods, presets, params, audio_file, no_figures, no_bench, motion_opts=None):
    """Measure the feel: render each INPUT motion file with each method and preset and score the tracks.

    \b
    Metrics (docs/metrics.md): motion-intensity coupling r and lag, locus error
    of the energy centroid against the renderer's target (cm), intensity
    constancy (dB), smoothness (jerk, SPARC, toggles/s, power above the motors'
    bandwidth), saturation and dead-zone rates; with --audio, onset agreement.
    Skin-side metrics run the commands through a first-order ERM motor model.

    \b
    Example:
      hapmotion evaluate ../shared/data/motion/*.bvh -o report/
    """
    from tqdm import tqdm

    from ..metrics.report import evaluate

    method_list = _names(methods, "--methods")
    preset_list = _names(presets, "--presets")
    overrides = parse_param_overrides(params)
    total = len(inputs) * len(method_list) * len(preset_list)
    bar = tqdm(total=total, desc="evaluating", unit="run", disable=not sys.stderr.isatty(), file=sys.stderr,
               leave=False)

    def progress(label: str) -> None:
        bar.set_postfix_str(label, refresh=False)
        bar.update(1)

    try:
        report = evaluate(
            list(inputs), method_list, preset_list, out_dir=Path(output), audio=audio_file, overrides=overrides,
            figures=not no_figures, bench=not no_bench, load=lambda p: read_motion(p, **motion_opts),
            progress=progress,
        )
    finally:
        bar.close()
    click.echo(f"scored {len(report.runs)} runs ({len(inputs)} recordings x {len(method_list)} methods x "
               f"{len(preset_list)} presets) in {report.timings['total']:.1f} s")
    for path in report.files:
        click.echo(f"wrote {path}")

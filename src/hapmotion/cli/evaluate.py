"""``hapmotion evaluate``: what a wearer would feel from every recording x method x preset, as a verdict, tables
and figures."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from ..errors import UsageError
from ..renderer.params import METHODS, PRESETS
from .motion_options import motion_options, read_motion
from ..audio.mix import parse_mix_ratio
from .show_options import SHOW_OPTIONS, mix_rule_option, param_option, parse_param_overrides, split_list


def _unsized_terminal() -> dict[str, int]:
    """tqdm's size for a terminal on stderr that reports 0 columns or rows (a serial console, a pseudo-terminal
    nobody sized): tqdm would draw nothing there, so the bar takes 80 x 24; {} for a sized terminal."""
    try:
        size = os.get_terminal_size(sys.stderr.fileno())
    except (OSError, ValueError):
        return {}
    return {} if size.columns and size.lines else {"ncols": 80, "nrows": 24}


def _names(text: str, what: str, allowed) -> list[str]:
    names = split_list(text, what, tuple(allowed))
    if not names:
        raise UsageError(f"--{what}s: expected a comma-separated list, found {text!r}")
    return names


@click.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False),
              help="Report folder (created): metrics.md, metrics.csv and PNG figures (bench.csv with --bench).")
@click.option("--methods", default="mst,baseline", show_default=True,
              help="Comma-separated renderer methods to compare.")
@click.option("--presets", default=None,
              help=f"Comma-separated parameter presets to compare (default: all, {','.join(PRESETS)}).")
@param_option
@click.option("--audio", "audio_file", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Song to mix with every track (the multimodal show): adds onset agreement, lateral accuracy "
                   "with music, how the mix follows the music.")
@SHOW_OPTIONS["mix"]
@mix_rule_option
@click.option("--no-figures", is_flag=True, help="Tables only (faster).")
@click.option("--bench/--no-bench", default=False, show_default=True,
              help="Also run the synthetic sweep bench (hand tracing known paths, not the INPUT recordings) and "
                   "add it to the report.")
@motion_options
def command(inputs, output, methods, presets, params, audio_file, mix_ratio, mix_rule, no_figures, bench,
            motion_opts=None):
    """Measure the feel: render each INPUT motion file with each method and preset and score the tracks.

    \b
    The report (docs/metrics.md) says per recording what a wearer would feel:
    whether the vest is felt while a hand moves (a motor at 15 of 100 or more),
    how closely it follows the hands' speed and reach, whether stillness is
    quieter, whether a one-hand gesture lands on the mirrored side; then locus
    error (cm), intensity constancy (dB), smoothness, saturation and commands
    under the motors' start. Felt values run the commands through an ERM motor
    model. With --audio: onsets as the motors render them, and the mix.

    On a terminal a progress bar counts the steps and names the one under way.
    The synthetic sweep bench is added only with --bench.

    \b
    Example:
      hapmotion evaluate ../shared/data/motion/*.bvh -o report/
    """
    from tqdm import tqdm

    from ..metrics.evaluation import evaluate, steps

    method_list = _names(methods, "method", METHODS)
    preset_list = _names(presets, "preset", PRESETS) if presets is not None else list(PRESETS)
    overrides = parse_param_overrides(params)
    ratio = parse_mix_ratio(mix_ratio)
    if audio_file is None and (mix_ratio != "2:3" or mix_rule is not None):
        raise UsageError(f"{'--mix' if mix_ratio != '2:3' else '--mix-rule'} sets how the music mixes: give --audio "
                         "SONG too")
    total = steps(len(inputs), len(method_list), len(preset_list), bench=bench, write=True)
    # the bar is drawn at once and names the step it waits for (reading a clip, the first run's compilation, the
    # figures), so a long evaluation never sits silent; off a terminal (a log, a pipe) nothing is drawn
    bar = tqdm(total=total, desc="evaluating", unit="step", disable=not sys.stderr.isatty(), file=sys.stderr,
               leave=False, mininterval=0.2, **_unsized_terminal())

    def status(label: str) -> None:
        bar.set_postfix_str(label, refresh=True)

    def progress(label: str) -> None:
        bar.update(1)

    try:
        report = evaluate(
            list(inputs), method_list, preset_list, out_dir=Path(output), audio=audio_file, overrides=overrides,
            figures=not no_figures, bench=bench, load=lambda p: read_motion(p, **motion_opts),
            progress=progress, status=status, mix_ratio=ratio, mix_rule=mix_rule,
        )
    finally:
        bar.close()
    click.echo(f"scored {len(report.runs)} runs ({len(inputs)} recordings x {len(method_list)} methods x "
               f"{len(preset_list)} presets) in {report.timings['total']:.1f} s")
    for path in report.files:
        click.echo(f"wrote {path}")

"""``hapmotion info INPUT [--json]``: what the reader found in a motion file."""

from __future__ import annotations

import json
from typing import Any

import click

from .motion_options import motion_options, read_motion


@click.command("info")
@click.argument("input", metavar="INPUT")
@motion_options
@click.option("--json", "as_json", is_flag=True, help="Print a JSON object instead of the table.")
def command(input: str, motion_opts: dict[str, Any], as_json: bool) -> None:
    """Show what hapmotion reads from a motion file INPUT.

    INPUT is a .bvh, Azure Kinect .json, AIST++ .pkl, or hapmotion .csv/.npz file. Prints the format, skeleton,
    frames, frame rate, units and their conversion to metres, the up axis and how it was found (detected from the
    motion, with the evidence, or given), skipped frames, which joints were found (with the file's names), which
    were derived and how, gaps filled per joint, and notes (warnings such as weak up-axis evidence included).
    """
    from ..motion_files.info import describe, format_table, summary

    motion = read_motion(input, **motion_opts)
    if as_json:
        click.echo(json.dumps(summary(motion), indent=2))
    else:
        click.echo(format_table(describe(motion)))

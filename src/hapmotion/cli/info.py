"""``hapmotion info INPUT [--json]``: what the reader found in a motion file, or what a track or pattern holds."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import click
import numpy as np

from ..errors import UsageError
from ..track import HapticTrack
from ..track_files.sniff import is_track_file
from .motion_options import CLI_SPELLING, motion_options, read_motion, read_track

FELT_LEVEL = 15.0
"""Intensity (0..100) from which a motor counts as on in ``info``'s 'felt' figures: the level below which the
bundled ERM motor model does not start (docs/metrics.md, "under motor start")."""

TRACK_FORMATS = {
    ".tact": "bHaptics .tact pattern (Designer / Player; read on the Player's 20 ms tick)",
    ".csv": "hapmotion track CSV",
    ".json": "hapmotion track JSON",
    ".npz": "hapmotion track NPZ",
}


@click.command("info")
@click.argument("input", metavar="INPUT")
@motion_options
@click.option("--json", "as_json", is_flag=True, help="Print a JSON object instead of the table.")
def command(input: str, motion_opts: dict[str, Any], as_json: bool) -> None:
    """Show what hapmotion reads from INPUT: a motion file, or a haptic track or pattern.

    A motion file (.bvh, Azure Kinect .json, AIST++ .pkl, hapmotion .csv/.npz joint table): the format, skeleton,
    frames, frame rate, units and their conversion to metres, the up axis and how it was found (detected from the
    motion, with the evidence, or given), skipped frames, which joints were found (with the file's names), which
    were derived and how, gaps filled per joint, and notes (warnings such as weak up-axis evidence included).

    A track or pattern (a bHaptics Designer .tact, or a track hapmotion wrote: .tact .csv .json .npz, told apart
    from motion files by their content): rows, rate and duration, each device with its motors, peak and how long
    it is on, the devices the default layout (X40 + two shoulder sleeves) lacks, and how the track was made.
    """
    from ..motion_files.info import describe, format_table, summary

    if is_track_file(input):
        given = [CLI_SPELLING.get(k if k != "fps_in" else "fps", k) for k, v in motion_opts.items()
                 if v is not None and k != "limits"]
        if given:
            raise UsageError(f"{given[0]} is a motion reader option; {input} is a haptic track or pattern")
        facts = track_summary(read_track(input, **motion_opts), input)
        click.echo(json.dumps(facts, indent=2) if as_json else format_table(describe_track(facts)))
        return
    motion = read_motion(input, **motion_opts)
    if as_json:
        click.echo(json.dumps(summary(motion), indent=2))
    else:
        click.echo(format_table(describe(motion)))


def track_summary(track: HapticTrack, path: "str | os.PathLike[str]") -> dict[str, Any]:
    """JSON-ready facts about a track or pattern read from ``path``.

    Per device (the ``<Device>`` of each ``<Device>_<index>`` column): its motors, the peak intensity (0..100) and
    the share of rows in which one of its motors is at :data:`FELT_LEVEL` or more."""
    from ..layout import load_layout

    x = track.intensities  # (T, N) 0..100
    devices: dict[str, list[int]] = {}
    for col, name in enumerate(track.actuators):
        devices.setdefault(name.rsplit("_", 1)[0], []).append(col)
    from ..rig import motor_columns, own_rig, rig_hint

    chart = load_layout()
    known = {a.rsplit("_", 1)[0] for a in chart.actuators}
    own = own_rig(track)  # a track rendered with --rig: its columns are that rig's motors
    lacking = sorted(set(devices) - known)
    elsewhere = own is not None and motor_columns(own, chart.actuators, chart.places(), other_devices=True) is None
    if elsewhere:
        lacking = sorted(devices)  # same names as the X40's (an Air's VestFront_0..7), other motors
    hint = own.name if own is not None else rig_hint(lacking)
    rows = max(track.n_frames, 1)
    made = {k: track.meta[k] for k in ("method", "preset", "mode", "mirror") if k in track.meta}
    return {
        "format": TRACK_FORMATS[Path(path).suffix.lower()],
        "path": os.fspath(path),
        "files": [os.fspath(p) for p in track.meta.get("files", [path])],
        "rows": track.n_frames,
        "fps": track.fps,
        "duration_s": track.duration,
        "layout": track.layout,
        "peak": float(x.max()) if x.size else 0.0,
        "felt_pct": 100.0 * float(np.count_nonzero((x >= FELT_LEVEL).any(axis=1))) / rows if x.size else 0.0,
        "devices": {
            name: {"motors": len(cols), "peak": float(x[:, cols].max()) if x.size else 0.0,
                   "felt_pct": 100.0 * float(np.count_nonzero((x[:, cols] >= FELT_LEVEL).any(axis=1))) / rows}
            for name, cols in devices.items()},
        "rig": own.name if own is not None else None,
        "devices_not_in_default_layout": lacking,
        "rig_hint": hint or None,
        "needs_rig": elsewhere,
        "made_with": made,
    }


def tact_types(devices: dict[str, dict[str, Any]]) -> list[str]:
    """The bHaptics device types (``.tact`` layouts: Tactot, TactGlove ...) of a summary's ``devices``."""
    from ..bhaptics.devices import type_for_position

    found = (type_for_position(name, d["motors"]) for name, d in devices.items())
    return list(dict.fromkeys(t.name for t in found if t is not None))


def describe_track(s: dict[str, Any]) -> list[tuple[str, str]]:
    """``(label, value)`` rows of :func:`track_summary` for the plain-text table."""
    lacking = s["devices_not_in_default_layout"]
    return [
        ("format", s["format"]),
        ("path", s["path"]),
        ("files", ", ".join(s["files"])),
        ("rows", str(s["rows"])),
        ("fps", f"{s['fps']:g}"),
        ("duration", f"{s['duration_s']:.2f} s"),
        ("peak", f"{s['peak']:.0f} of 100"),
        (f"felt (a motor at {FELT_LEVEL:g}+)", f"{s['felt_pct']:.0f}% of rows"),
        (f"devices ({len(s['devices'])})", "; ".join(
            f"{name}: {d['motors']} motors, peak {d['peak']:.0f}, felt in {d['felt_pct']:.0f}% of rows"
            for name, d in s["devices"].items())),
        ("rig", f"{s['rig']} (the columns are its motors: play with --rig {s['rig']})" if s["rig"]
         else (f"none: a .tact file holds device types ({', '.join(tact_types(s['devices']))}), not a rig; it plays on "
               f"any --rig that has {', '.join(s['devices'])}") if s["format"] == TRACK_FORMATS[".tact"]
         else "none recorded (the body chart's places, or a pattern)"),
        ("not in the default layout", "none" if not lacking else ", ".join(lacking) + (
            f" (other motors than the X40's of those names: play refuses it without --rig {s['rig']})"
            if s["needs_rig"] else " (play and cues leave them out; play them with --rig "
            f"{s['rig_hint'] or 'WEARABLES'}, or map them with --layout FILE)")),
        ("made with", ", ".join(f"{k} {v}" for k, v in s["made_with"].items()) or "not recorded"),
    ]

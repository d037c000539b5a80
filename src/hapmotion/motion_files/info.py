"""What a reader found in a file, for ``hapmotion info`` and for people checking a conversion."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..skeleton.joints import JOINTS
from ..motion import Motion


def summary(motion: Motion) -> dict[str, Any]:
    """JSON-ready facts about ``motion`` (what :func:`describe` prints, with numbers kept as numbers)."""
    meta = motion.meta
    source = meta.get("source_joints", {})
    found = {JOINTS[j]: source.get(JOINTS[j], JOINTS[j])
             for j in np.flatnonzero(motion.present & ~motion.derived)}
    derived = {JOINTS[j]: meta.get("derived_from", {}).get(JOINTS[j], "derived")
               for j in np.flatnonzero(motion.derived)}
    return {
        "format": meta.get("format", "unknown"),
        "skeleton": meta.get("skeleton", "unknown"),
        "path": meta.get("path", ""),
        "frames": motion.n_frames,
        "fps": motion.fps,
        "duration_s": motion.duration,
        "units": meta.get("units", "m"),
        "up_axis": meta.get("up_axis", "+Y (format)"),
        "frames_skipped": int(meta.get("skipped_frames", 0)),
        "joints_found": found,
        "joints_derived": derived,
        "joints_absent": [JOINTS[j] for j in np.flatnonzero(~motion.present)],
        "gaps_filled": dict(meta.get("filled_by_joint", {})),
        "notes": list(meta.get("notes", [])),
    }


def _joint_list(mapping: dict[str, str]) -> str:
    if not mapping:
        return "none"
    return ", ".join(name if src == name else f"{name} <- {src}" for name, src in mapping.items())


def describe(motion: Motion) -> list[tuple[str, str]]:
    """``(label, value)`` rows: format, skeleton, path, frames, fps, duration, units and conversion, the up axis and
    why, frames skipped,
    joints found (with the source names), joints derived (with the rule), joints absent, gaps filled per joint,
    notes."""
    s = summary(motion)
    gaps = s["gaps_filled"]
    return [
        ("format", s["format"]),
        ("skeleton", s["skeleton"]),
        ("path", s["path"]),
        ("frames", str(s["frames"])),
        ("fps", f"{s['fps']:g}"),
        ("duration", f"{s['duration_s']:.2f} s"),
        ("units", s["units"]),
        ("up axis", s["up_axis"]),
        ("frames skipped", str(s["frames_skipped"])),
        (f"joints found ({len(s['joints_found'])})", _joint_list(s["joints_found"])),
        (f"joints derived ({len(s['joints_derived'])})",
         "; ".join(f"{k} = {v}" for k, v in s["joints_derived"].items()) or "none"),
        (f"joints absent ({len(s['joints_absent'])})", ", ".join(s["joints_absent"]) or "none"),
        ("gaps filled", ", ".join(f"{k} {v} frame{'s' if v != 1 else ''}" for k, v in gaps.items()) or "none"),
        ("notes", "; ".join(s["notes"]) or "none"),
    ]


def format_table(rows: list[tuple[str, str]]) -> str:
    """Rows as plain text, labels padded to one column."""
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k.ljust(width)}  {v}" for k, v in rows)

"""The evaluation tables: score rows as Markdown (for reading) and CSV (full precision), and the bench table.

A score row is a dict with ``clip``, ``method``, ``preset`` and one value per :class:`~.scorecard.Column` key
(``None`` where undefined). Undefined values are "–" in Markdown and an empty cell in CSV, never NaN. Percent
columns (:data:`~.scorecard.PERCENT_KEYS`) are stored as fractions and shown x100; their CSV names end in ``_pct``.
"""

from __future__ import annotations

import csv
import io
import math
from typing import Any, Sequence

from .motor import MotorModel
from .scorecard import PERCENT_KEYS, Column, csv_key

__all__ = ["number", "shown", "cell", "header", "markdown_table", "legend", "csv_text", "bench_markdown", "bench_csv"]


def number(value: float, spec: str) -> str:
    """``value`` formatted by ``spec`` (``".0f"``, ``".2f"`` ...), a negative value that rounds to zero shown as
    ``0`` (``0.00``) rather than ``-0``: a reader takes the sign for a direction the value does not have."""
    text = format(value, spec)
    if text.startswith("-") and float(text) == 0.0:
        return text[1:]
    return text


def shown(key: str, value: float | None) -> float | None:
    """A value in display units (the fractions of :data:`PERCENT_KEYS` become percent)."""
    if value is None:
        return None
    return 100.0 * value if key in PERCENT_KEYS else value


def cell(col: Column, value: float | None) -> str:
    """One formatted table cell ("–" when undefined)."""
    v = shown(col.key, value)
    if v is None or not math.isfinite(v):
        return "–"
    return number(v, col.fmt)


def header(col: Column) -> str:
    """Column title with its unit, e.g. ``lateral accuracy (%)``."""
    return f"{col.header} ({col.unit})" if col.unit else col.header


def markdown_table(rows: Sequence[dict[str, Any]], columns: Sequence[Column]) -> str:
    """A Markdown pipe table of score rows (``clip``, ``method``, ``preset`` first)."""
    head = ["recording", "method", "preset"] + [header(c) for c in columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 3 + "---:|" * len(columns)]
    for r in rows:
        cells = [str(r["clip"]), str(r["method"]), str(r["preset"])] + [cell(c, r.get(c.key)) for c in columns]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def legend(columns: Sequence[Column], motor: MotorModel) -> str:
    """Markdown bullet list explaining the columns (with their CSV names) and the motor model they assume."""
    arrows = {"higher": "higher is better", "lower": "lower is better", "zero": "closer to 0 is better", "": "context"}
    out = [f"- **{header(c)}** (`{csv_key(c.key)}`): {c.text} ({arrows[c.better]})." for c in columns]
    out.append(
        f"- Motor model: first-order ERM, tau rise {1000 * motor.tau_rise_s:.0f} ms, tau fall "
        f"{1000 * motor.tau_fall_s:.0f} ms, start threshold {100 * motor.dead_zone:.0f} %, bandwidth "
        f"{motor.bandwidth_hz:.2f} Hz (docs/metrics.md)."
    )
    return "\n".join(out) + "\n"


def csv_text(rows: Sequence[dict[str, Any]], columns: Sequence[Column]) -> str:
    """CSV of score rows: full precision, units in the names (``locus_cm``, ``hf_power_pct``), empty = undefined."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["recording", "method", "preset"] + [csv_key(c.key) for c in columns])
    for r in rows:
        vals = []
        for c in columns:
            v = shown(c.key, r.get(c.key))
            vals.append("" if v is None or not math.isfinite(v) else repr(float(v)))
        w.writerow([r["clip"], r["method"], r["preset"]] + vals)
    return buf.getvalue()


BENCH_FIELDS = (
    ("range_db", "energy range (dB)", ".2f"),
    ("reasoned_range_db", "reasoned (dB)", ".2f"),
    ("range_skin_db", "felt range (dB)", ".2f"),
    ("locus_cm", "locus error (cm)", ".2f"),
    ("reasoned_locus_cm", "reasoned (cm)", ".2f"),
    ("locus_amp_cm", "locus error, amplitude (cm)", ".2f"),
    ("reasoned_locus_amp_cm", "reasoned (cm)", ".2f"),
    ("toggles_s", "toggles (1/s)", ".2f"),
    ("jerk", "jerk (1/s^3)", ".3g"),
)
"""Bench columns: key in the :func:`hapmotion.metrics.sweep.run_bench` row, Markdown title, number format."""


def bench_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table of :func:`hapmotion.metrics.sweep.run_bench` rows."""
    head = ["case", "preset", "phantom"] + [h for _, h, _ in BENCH_FIELDS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 3 + "---:|" * len(BENCH_FIELDS)]
    for r in rows:
        cells = [r["case"], r["preset"], r["phantom"]]
        for key, _, fmt in BENCH_FIELDS:
            v = r.get(key)
            cells.append("–" if v is None else number(v, fmt))
        lines.append("| " + " | ".join(map(str, cells)) + " |")
    return "\n".join(lines) + "\n"


def bench_csv(rows: Sequence[dict[str, Any]]) -> str:
    """CSV of :func:`hapmotion.metrics.sweep.run_bench` rows (the :data:`BENCH_FIELDS` keys, empty = undefined)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["case", "preset", "phantom"] + [k for k, _, _ in BENCH_FIELDS])
    for r in rows:
        w.writerow([r["case"], r["preset"], r["phantom"]]
                   + ["" if r.get(k) is None else repr(float(r[k])) for k, _, _ in BENCH_FIELDS])
    return buf.getvalue()

"""Length units a motion file may use, and the ``units``/``scale`` reader options that name them."""

from __future__ import annotations

import math
from typing import Optional

from ..errors import UsageError
from ..skeleton.naming import CMU_METRES_PER_UNIT

UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "cmu": CMU_METRES_PER_UNIT,
}
"""Length units a file may use, in metres per unit ("cmu": CMU ASF units, x0.056444, CMU FAQ)."""

UNIT_NAMES = {"m": "m", "cm": "cm", "mm": "mm", "inch": "inch", "cmu": "CMU units"}


def resolve_scale(units: Optional[str], scale: Optional[float]) -> Optional[tuple[float, str]]:
    """(metres per unit, description) from the ``units``/``scale`` options, or ``None`` when neither is given."""
    if units is not None and scale is not None:
        raise UsageError("give either units or scale, not both")
    if scale is not None:
        try:
            s = float(scale)
        except (TypeError, ValueError):
            raise UsageError(f"scale must be a positive number (metres per file unit), found {scale!r}") from None
        if not (s > 0 and math.isfinite(s)):
            raise UsageError(f"scale must be a positive number (metres per file unit), found {scale!r}")
        return s, f"x{s:g} -> m"
    if units is not None:
        key = str(units).strip().lower()
        if key not in UNITS:
            raise UsageError(f"unknown units {units!r}; expected one of {', '.join(UNITS)}")
        return UNITS[key], f"{UNIT_NAMES[key]} (x{UNITS[key]:.6g} -> m)"
    return None


def units_or_default(units: Optional[str], scale: Optional[float], default: tuple[float, str]) -> tuple[float, str]:
    """(metres per unit, description): the ``units``/``scale`` option if given (marked "(option)"), else the
    format's ``default``."""
    explicit = resolve_scale(units, scale)
    return (explicit[0], explicit[1] + " (option)") if explicit else default

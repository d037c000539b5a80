"""BodyModel: the torso and vest surface, sized from the performer's skeleton.

The vest is modelled as an elliptic cylinder around the spine in the body frame (x right, y up, z forward, origin
J_T = SPINE_NAVEL), capped at the shoulder line (top) and a little above the pelvis (bottom)::

        x^2/a^2 + z^2/b^2 <= 1,     y_bottom <= y <= y_top

``a`` is half the shoulder width (the surface reaches the shoulder joints, where the sleeves sit) and ``b`` is
0.3 x the shoulder width (about 11 cm for a 38 cm shoulder span: a typical adult chest half-depth). The vest rows
run from just below the shoulder line (row 0, collar) to just above the pelvis (row 4, belly). Every number is
relative to the performer's own skeleton, so a child-sized or a scaled skeleton gets a surface of its own size.

These proportions are this project's choice (the paper gives no surface model; see docs/algorithm.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from numbers import Real
from typing import Any, Mapping

import numpy as np

from ..skeleton.joints import JOINT_INDEX
from .frame import DEFAULT_AXES

# Proportions relative to the shoulder width / torso length; see the module docstring.
HALF_DEPTH_PER_SHOULDER_WIDTH = 0.30
COLLAR_BELOW_SHOULDERS = 0.08  # row 0 sits this fraction of the torso length below the shoulder line
BELLY_ABOVE_PELVIS = 0.12  # row 4 sits this fraction of the torso length above the pelvis
SLEEVE_ZONE_DROP = 0.20  # side hits within this fraction of the torso length below the shoulder line reach a sleeve

# A dimension read from a file or the network beyond this many metres (either sign) is not a person's.
MAX_DIMENSION_M = 5.0


@dataclass(frozen=True)
class BodyModel:
    """Performer body dimensions in the body frame, metres.

    Attributes
    ----------
    shoulder_width:
        Distance between the shoulder joints.
    shoulder_height:
        Height of the shoulder midpoint above J_T (body y).
    pelvis_height:
        Height of the pelvis relative to J_T (usually negative).
    """

    shoulder_width: float = 0.38
    shoulder_height: float = 0.33
    pelvis_height: float = -0.12

    @classmethod
    def default(cls) -> "BodyModel":
        """An average adult (used by live streams before the performer is known)."""
        return cls()

    @classmethod
    def from_motion(cls, motion) -> "BodyModel":
        """Median dimensions over all frames of a :class:`~hapmotion.motion.Motion` (:meth:`from_positions`)."""
        return cls.from_positions(motion.positions, JOINT_INDEX)

    @classmethod
    def from_joints(cls, joint) -> "BodyModel":
        """Median dimensions over all frames of the joints ``joint(name)`` returns, ``(T, 3)`` metres each (a
        motion's :meth:`~hapmotion.motion.Motion.joint`, or a table of the render joints alone), as
        :meth:`from_positions` measures them."""
        from .sizing_compiled import SIZING_JOINTS  # numba on first use: see from_positions

        table = np.stack([np.asarray(joint(name), dtype=np.float64) for name in SIZING_JOINTS], axis=1)
        return cls.from_positions(table, {name: i for i, name in enumerate(SIZING_JOINTS)})

    @classmethod
    def from_positions(cls, positions: np.ndarray, rows: Mapping[str, int]) -> "BodyModel":
        """Median dimensions over all frames of ``positions`` ``(T, J, 3)`` float64 metres, any strides, whose row
        ``rows[name]`` holds each joint (``JOINT_INDEX`` for a motion's positions): the shoulders' distance, and the
        shoulders' midpoint and the pelvis in the body frame (:mod:`hapmotion.body.frame`)."""
        # numba on first use, as the renderer's kernel: see hapmotion.body.sizing_compiled
        from .sizing_compiled import SIZING_JOINTS, body_samples

        # the compiled pass reads through the rows without bounds checks, and takes native float64 only: both
        # checked here (any other number type or byte order is converted, as numpy converts it)
        positions = np.asarray(positions, dtype=np.float64)
        index = np.array([rows[name] for name in SIZING_JOINTS], dtype=np.intp)
        if positions.ndim != 3 or positions.shape[2] != 3:
            raise ValueError(f"positions must be (T, J, 3), got {positions.shape}")
        if ((index < 0) | (index >= positions.shape[1])).any():
            raise ValueError(f"positions (T, J, 3) have {positions.shape[1]} joints: no row {index.max()} for the "
                             f"{', '.join(SIZING_JOINTS)} rows {index.tolist()}")
        n = positions.shape[0]
        width, sh, ph = np.empty(n), np.empty(n), np.empty(n)
        body_samples(positions, index, DEFAULT_AXES, width, sh, ph)
        # the samples are this function's own: partitioned in place instead of copied (the same medians)
        width, sh, ph = (float(np.median(a, overwrite_input=True)) for a in (width, sh, ph))
        if not (width > 0.05):
            width = cls.shoulder_width
        if not (sh - ph > 0.1):  # a broken skeleton: keep the proportions of the default body
            sh, ph = cls.shoulder_height, cls.pelvis_height
        return cls(shoulder_width=width, shoulder_height=sh, pelvis_height=ph)

    # ------------------------------------------------------------------ as written in tracks and show descriptions
    def to_dict(self) -> dict[str, float]:
        """``{"shoulder_width", "shoulder_height", "pelvis_height"}`` in metres: the ``body`` of a track's meta
        and of an audience show description."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}

    @classmethod
    def from_dict(cls, dims: Mapping[str, Any]) -> "BodyModel":
        """The body :meth:`to_dict` wrote (other keys are ignored).

        Raises ``ValueError`` (one line, naming the key) unless every dimension is a finite number of metres
        within +-``MAX_DIMENSION_M``, the shoulder width is positive and the shoulders are above the pelvis.
        """
        if not isinstance(dims, Mapping):
            raise ValueError(f"body: expected an object of dimensions, found {type(dims).__name__}")
        values = {}
        for f in fields(cls):
            if f.name not in dims:
                raise ValueError(f"body.{f.name}: missing")
            v = dims[f.name]
            if not isinstance(v, Real) or isinstance(v, bool) or not math.isfinite(v) or abs(v) > MAX_DIMENSION_M:
                raise ValueError(f"body.{f.name}: expected metres (a finite number within +-{MAX_DIMENSION_M:g}), "
                                 f"found {v!r}")
            values[f.name] = float(v)
        if not values["shoulder_width"] > 0:
            raise ValueError(f"body.shoulder_width: expected a positive width, found {values['shoulder_width']!r}")
        if not values["shoulder_height"] > values["pelvis_height"]:
            raise ValueError(f"body.shoulder_height: expected the shoulders above the pelvis "
                             f"({values['pelvis_height']!r}), found {values['shoulder_height']!r}")
        return cls(**values)

    # ------------------------------------------------------------------ surface
    @property
    def half_width(self) -> float:
        """``a``: half-width of the torso cylinder (x), metres."""
        return 0.5 * self.shoulder_width

    @property
    def half_depth(self) -> float:
        """``b``: half-depth of the torso cylinder (z), metres."""
        return HALF_DEPTH_PER_SHOULDER_WIDTH * self.shoulder_width

    @property
    def torso_length(self) -> float:
        return self.shoulder_height - self.pelvis_height

    @property
    def y_top(self) -> float:
        """Top cap of the surface (shoulder line)."""
        return self.shoulder_height

    @property
    def y_bottom(self) -> float:
        """Bottom cap of the surface (just above the pelvis)."""
        return self.pelvis_height + 0.5 * BELLY_ABOVE_PELVIS * self.torso_length

    @property
    def y_row_first(self) -> float:
        """Height of vest row 0 (collar)."""
        return self.shoulder_height - COLLAR_BELOW_SHOULDERS * self.torso_length

    @property
    def y_row_last(self) -> float:
        """Height of the last vest row (belly)."""
        return self.pelvis_height + BELLY_ABOVE_PELVIS * self.torso_length

    @property
    def y_sleeve_low(self) -> float:
        """Side hits above this height (and far enough out) land on a shoulder sleeve."""
        return self.shoulder_height - SLEEVE_ZONE_DROP * self.torso_length

    @property
    def target_point(self) -> np.ndarray:
        """TP in body coordinates: centroid of the vest front and back centres and both shoulders (paper, Sec. 4)."""
        y_mid = 0.5 * (self.y_row_first + self.y_row_last)
        front = np.array([0.0, y_mid, self.half_depth])
        back = np.array([0.0, y_mid, -self.half_depth])
        left = np.array([-self.half_width, self.shoulder_height, 0.0])
        right = np.array([self.half_width, self.shoulder_height, 0.0])
        return (front + back + left + right) / 4.0

    def as_array(self) -> np.ndarray:
        """Surface numbers for the renderer kernel (slot order: ``hapmotion.renderer.packed`` ``S_*``)."""
        return np.array(
            [
                self.half_width,
                self.half_depth,
                self.y_bottom,
                self.y_top,
                self.y_row_first,
                self.y_row_last,
                self.y_sleeve_low,
                *self.target_point,
            ],
            dtype=np.float64,
        )

"""The settings of one show: :class:`Show`, every choice that turns a performance into vibration, validated once.

Every command that renders builds one ``Show`` (the CLI through ``cli/show_options.show_options``) and hands it on
whole: to :func:`~hapmotion.show.offline.render_show` for files, to :func:`hapmotion.live.live` for a live show,
and, as the output stage's serialised form, to every seat of an audience.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

from ..audio.mix import check_ratio
from ..audio.params import MIX_RULES, AudioParams, params_for_preset
from ..body.model import BodyModel
from ..errors import UsageError
from ..layout import Layout, load_layout
from ..limits import LimitsArg
from ..renderer.params import DEFAULT_PRESET, METHODS, PRESETS, Params
from ..renderer.renderer import Renderer, resolve_params
from .comfort import Comfort
from .cues import CueList, load_cues

MODES = ("multimodal", "motion", "audio")
"""The paper's study-2 conditions: motion and music mixed, the motion alone, the music alone."""
LENGTH_RULES = ("longer", "motion")
"""How long a track with both inputs lasts (see :mod:`hapmotion.show.offline`)."""
MAX_OFFSET_S = 86400.0
"""The music may be shifted by at most a day against the motion."""
FPS_RANGE = (1.0, 1000.0)
"""Frames per second a show may be rendered at (inclusive)."""


def check_choice(value: Any, allowed: Sequence[str], what: str) -> None:
    """:class:`UsageError` unless ``value`` is one of ``allowed``."""
    if value not in allowed:
        raise UsageError(f"{what} {value!r}: expected one of {', '.join(allowed)}")


def closest_preset(value: Any) -> Optional[str]:
    """The preset a mistyped ``value`` most likely meant (case and small typos forgiven: ``Felt`` and ``fetl`` give
    ``felt``), or None when nothing is close."""
    if not isinstance(value, str):
        return None
    folded = {p.lower(): p for p in PRESETS}
    match = difflib.get_close_matches(value.strip().lower(), list(folded), n=1, cutoff=0.6)
    return folded[match[0]] if match else None


def check_fps(fps: Any, what: str = "fps") -> float:
    """``fps`` as a float within :data:`FPS_RANGE`; :class:`UsageError` otherwise (NaN included)."""
    lo, hi = FPS_RANGE
    try:
        value = float(fps)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and lo <= value <= hi):
        raise UsageError(f"{what} must be a finite number of frames per second from {lo:g} to {hi:g}, not {fps!r}")
    return value


@dataclass(frozen=True)
class Show:
    """Every choice that turns a performance into vibration (a value: compare, copy with :meth:`replace`).

    ``overrides`` are :class:`~hapmotion.renderer.Params` fields set on top of ``preset`` (``mirror`` wins over an
    override of the same name). ``mode`` ``None`` picks from the inputs (:meth:`resolved_mode`). ``fps`` ``None``
    keeps the motion's rate (60 frames/s for the music alone). ``layout`` ``None`` is the default X40 + two shoulder
    sleeves (a :class:`~hapmotion.layout.Layout` or a layout file). ``mix_rule`` ``None`` is the preset's
    (``paper`` for the paper preset, ``duck`` otherwise). ``cues`` is a cue list (a file or a
    :class:`~hapmotion.show.cues.CueList`) layered over motion and music by :func:`hapmotion.show.cues.layer`.
    ``comfort`` holds the wearer's gain and limits, applied to every row that leaves the show
    (:mod:`hapmotion.show.comfort`).
    """

    method: str = "mst"
    preset: str = DEFAULT_PRESET
    overrides: Mapping[str, Any] = field(default_factory=dict)
    mirror: Optional[bool] = None
    mode: Optional[str] = None
    audio: Optional[Path] = None
    audio_offset_s: float = 0.0
    mix_ratio: tuple[float, float] = (2.0, 3.0)
    mix_rule: Optional[str] = None
    length: str = "longer"
    fps: Optional[float] = None
    layout: Union[Layout, Path, str, None] = None
    comfort: Comfort = Comfort()
    cues: Union[CueList, Path, str, None] = None

    def __post_init__(self) -> None:
        check_choice(self.method, METHODS, "method")
        if self.mirror is not None and not isinstance(self.mirror, bool):
            raise UsageError(f"mirror must be True, False or None, not {self.mirror!r}")
        if not isinstance(self.overrides, Mapping):
            raise UsageError(f"overrides must be a mapping of renderer parameters, not {type(self.overrides).__name__}")
        for name, value, kinds in (("audio", self.audio, (str, os.PathLike)),
                                   ("layout", self.layout, (str, os.PathLike, Layout)),
                                   ("cues", self.cues, (str, os.PathLike, CueList))):
            if value is not None and not isinstance(value, kinds):
                raise UsageError(f"{name} must be a file path (or None), not {type(value).__name__}")
        if not isinstance(self.preset, str) or self.preset not in PRESETS:
            hint = closest_preset(self.preset)
            raise UsageError(f"unknown preset {self.preset!r}" + (f" (did you mean {hint}?)" if hint else "")
                             + f"; choose one of {', '.join(PRESETS)}")
        if self.mode is not None:
            check_choice(self.mode, MODES, "mode")
        if self.mix_rule is not None:
            check_choice(self.mix_rule, MIX_RULES, "mix rule")
        if not isinstance(self.comfort, Comfort):
            raise UsageError(f"comfort must be a hapmotion.show.comfort.Comfort, not {type(self.comfort).__name__}")
        check_choice(self.length, LENGTH_RULES, "length rule")
        object.__setattr__(self, "mix_ratio", check_ratio(self.mix_ratio))
        try:
            offset = float(self.audio_offset_s)
        except (TypeError, ValueError):
            raise UsageError(f"audio offset {self.audio_offset_s!r}: expected a number of seconds") from None
        if not math.isfinite(offset) or abs(offset) > MAX_OFFSET_S:
            raise UsageError(f"--audio-offset must be within a day (+-{MAX_OFFSET_S:g} s), not {self.audio_offset_s}")
        object.__setattr__(self, "audio_offset_s", offset)
        if self.fps is not None:
            object.__setattr__(self, "fps", check_fps(self.fps))
        if self.audio is not None:
            object.__setattr__(self, "audio", Path(self.audio))
        object.__setattr__(self, "overrides", dict(self.overrides))

    def replace(self, **changes: Any) -> "Show":
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def resolved_mode(self, has_motion: bool) -> str:
        """The condition this show plays: ``mode`` if given, else multimodal with motion and music, the music alone
        without motion, the motion alone without music. Raises :class:`UsageError` when an input it needs is
        missing."""
        mode = self.mode or ("motion" if self.audio is None else ("multimodal" if has_motion else "audio"))
        if mode in ("audio", "multimodal") and self.audio is None:
            raise UsageError(f"--mode {mode} needs --audio SONG")
        if mode in ("motion", "multimodal") and not has_motion:
            raise UsageError(f"--mode {mode} needs a MOTION_FILE")
        if self.length == "motion" and not has_motion:
            raise UsageError("length rule 'motion' needs a motion file")
        return mode

    def params(self) -> Params:
        """The renderer's parameters: the preset, then the overrides, then ``mirror``."""
        changes = dict(self.overrides)
        if self.mirror is not None:
            changes["mirror"] = self.mirror
        return resolve_params(self.preset, None, **changes)

    def audio_params(self) -> AudioParams:
        """The music channel's parameters that go with the preset (:func:`~hapmotion.audio.params_for_preset`)."""
        return params_for_preset(self.preset)

    def resolved_rule(self) -> str:
        """The mix rule: ``mix_rule``, else the preset's (``paper`` for the paper preset, ``duck`` otherwise)."""
        return self.mix_rule or self.audio_params().mix_rule

    def load_layout(self) -> Layout:
        """The device layout: ``layout`` itself, a file it names, or the default."""
        if isinstance(self.layout, Layout):
            return self.layout
        return load_layout(self.layout) if self.layout is not None else load_layout()

    def load_cues(self, limits: LimitsArg = None) -> Optional[CueList]:
        """The show's cue list, read within ``limits`` if given as a file; ``None`` without cues."""
        if self.cues is None or isinstance(self.cues, CueList):
            return self.cues
        return load_cues(self.cues, limits=limits)

    def renderer(self, fps: float, body: Optional[BodyModel] = None) -> Renderer:
        """A live :class:`~hapmotion.renderer.Renderer` for this show at ``fps`` (``body`` ``None``: average
        adult)."""
        return Renderer(self.method, self.params(), fps=fps, body=body, layout=self.load_layout())

    def describe(self, mode: str) -> dict[str, Any]:
        """How the show is rendered, for a viewer or a recording's metadata."""
        return {"method": self.method, "preset": self.preset, "mirror": self.params().mirror, "mode": mode}

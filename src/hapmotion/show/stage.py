"""The output stage: what turns the rows that come in (rendered motion, a stored track) into the rows that are sent.

One :class:`OutputStage` is built per show, layout and frame rate, and every way of playing a show drives it:

* files: :meth:`OutputStage.rows` on whole ``(T, N)`` arrays (:func:`hapmotion.show.render_show`);
* live, an audience seat and ``play``: :meth:`OutputStage.step`, one ``(N,)`` row at its show time (the live
  engine knows nothing of modes, music or cues);
* an audience: :meth:`OutputStage.to_dict` is what the show's description carries, :meth:`OutputStage.from_dict`
  builds the same stage on each seat, with the seat's own comfort and cues.

Per row, in this order (the batch and per-row drivers run the same functions, so they send the same numbers):

1. **mode** (the paper's study-2 condition): ``motion`` passes the incoming row, ``audio`` the music's row,
   ``multimodal`` mixes both (:func:`hapmotion.audio.mix.mix` with the show's ratio and rule); all three are
   clipped to 0..100 and held to the show's power limit. ``rows`` (playing a stored track) passes the row as it is.
2. **cues**: authored cues layered on (:func:`hapmotion.show.cues.layer`), under the same power limit.
3. **comfort**: the wearer's gain and limits (:mod:`hapmotion.show.comfort`), the last word on every row.

On a rig with gloves the rows sent have the hand places after the body chart
(:meth:`hapmotion.layout.Layout.played_actuators`): the incoming and music rows are the body chart's, and step 1
ends by putting the performer's hands on the gloves (:class:`hapmotion.show.hands.HandLayer`, from the skeleton
given with the row, in the ``motion`` and ``multimodal`` modes) under the same power limit; cues and comfort then
see the whole row.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence

import numpy as np

from ..audio.mix import check_ratio, limit_power, locus_kernel, mix
from ..audio.params import MIX_RULES, AudioParams, params_for_preset
from ..errors import UsageError
from ..layout import Layout
from ..renderer.params import PRESETS
from .comfort import Comfort, Limiter, limit_rows
from .cue_layer import LiveCues
from .cues import CueList, cue_layer, layer
from .hands import HandLayer
from .settings import MODES, Show, check_choice, check_fps
from .timeline import RowTimeline

POWER_LIMIT_FRACTION = 0.75
"""Total power limit of every row a show sends, as a fraction of all actuators at full drive:
``sum((I / 100) ** 2) <= fraction * N``, the whole row scaled down together (Google's audio-to-tactile
post-processor, GitHub ``google/audio-to-tactile``, limits the summed power x_c^2 across channels the same way; the
value is ours: the loudest continuous music on all 52 actuators, power 52 * 0.6^2 = 18.7, passes untouched, a
whole-suit kick, power 52, is scaled to 87 %)."""

STAGE_MODES = MODES + ("rows",)
"""The study-2 conditions, and ``rows``: a stored track played as it is."""


def power_limit_for(n_actuators: int, fraction: Optional[float] = POWER_LIMIT_FRACTION) -> Optional[float]:
    """The total power limit ``sum (I/100)^2`` for ``n_actuators`` (``fraction`` ``None``: no limit)."""
    return None if fraction is None else float(fraction) * n_actuators


def show_power_limit(n_actuators: int) -> Optional[float]:
    """The power limit every show's rows keep to, cues included: :data:`POWER_LIMIT_FRACTION` of
    ``n_actuators`` at full drive."""
    return power_limit_for(n_actuators)


class OutputStage:
    """The last stages of every row a show sends: mode, cues, comfort (see the module docstring).

    Parameters
    ----------
    mode:
        ``"motion"``, ``"audio"``, ``"multimodal"`` or ``"rows"``.
    actuators:
        The ``N`` actuator ids of the rows, in column order.
    fps:
        Rows per second (the cue patterns' rate and the comfort limiter's clock).
    ratio, rule, audio_preset:
        The mix: ``(audio, motion)`` weights, ``duck``/``paper``/``energy``, and the preset whose
        :class:`~hapmotion.audio.AudioParams` hold the ``duck`` rule's depths and start level.
    power_limit:
        Total power ``sum (I/100)^2`` every row keeps to (``None``: none); cues keep to it too.
    positions:
        ``(N, 3)`` actuator positions in metres (the ``duck`` rule finds the motion's neighbours by them), or
        ``None``.
    mirror_map:
        ``(N,)`` left/right mirror map of the layout (cues with ``side=swap``).
    comfort:
        The wearer's gain and limits.
    cues:
        The cue list layered on, or ``None``.
    music:
        The music's rows (``audio`` and ``multimodal``), read at each row's show time by :meth:`step`.
    hands:
        The glove layer (a rig with gloves): the last ``hands.width`` of ``actuators`` are the hand places, the
        incoming and music rows may stop before them (the body chart), and the skeleton given to :meth:`rows` /
        :meth:`step` drives them.
    """

    def __init__(self, mode: str, actuators: Sequence[str], fps: float, *, ratio: tuple[float, float] = (2.0, 3.0),
                 rule: str = "duck", audio_preset: str = "felt", power_limit: Optional[float] = None,
                 positions: Optional[np.ndarray] = None, mirror_map: Optional[np.ndarray] = None,
                 comfort: Comfort = Comfort(), cues: Optional[CueList] = None,
                 music: Optional[RowTimeline] = None, hands: Optional[HandLayer] = None):
        check_choice(mode, STAGE_MODES, "mode")
        check_choice(rule, MIX_RULES, "mix rule")
        check_choice(audio_preset, tuple(PRESETS), "preset")
        fps = check_fps(fps)
        if power_limit is not None and (isinstance(power_limit, bool) or not isinstance(power_limit, (int, float))
                                        or not (math.isfinite(power_limit) and power_limit > 0)):
            raise UsageError(f"power limit {power_limit!r}: expected a positive number or None")
        if not isinstance(comfort, Comfort):
            raise UsageError(f"comfort must be a hapmotion.show.comfort.Comfort, not {type(comfort).__name__}")
        n = len(actuators)
        if positions is not None and np.shape(positions) != (n, 3):
            raise ValueError(f"positions must be ({n}, 3), not {np.shape(positions)}")
        if mirror_map is not None and np.shape(mirror_map) != (n,):
            raise ValueError(f"mirror_map must be ({n},), not {np.shape(mirror_map)}")
        self.hands = hands
        self.body_n = n - (hands.width if hands is not None else 0)
        if music is not None and music.n not in (n, self.body_n):
            raise ValueError(f"the music's rows have {music.n} columns, the stage {n}")
        self.mode = mode
        self.actuators = tuple(actuators)
        self.n = len(self.actuators)
        self.fps = float(fps)
        self.ratio = check_ratio(ratio)
        self.rule = rule
        self.audio_preset = audio_preset
        self.audio_params: AudioParams = params_for_preset(audio_preset)
        self.power_limit = power_limit
        self.positions = positions
        # the duck rule's closeness of motors, (N, N): fixed for the stage, so made once, not on every row
        self._kernel = locus_kernel(positions, self.n, self.audio_params.duck_locus_radius_m)
        self._silence = np.zeros(self.n)
        self.mirror_map = np.arange(self.n) if mirror_map is None else np.asarray(mirror_map)
        self.comfort = comfort
        self.cue_list = cues
        self.music = music
        self._cues: Optional[LiveCues] = None
        self._limiter = None if comfort.is_neutral else Limiter(comfort, self.n, self.fps)

    # ------------------------------------------------------------------ construction
    @classmethod
    def for_show(cls, show: Show, mode: str, *, layout: Layout, fps: float,
                 music: Optional[RowTimeline] = None, cues: Optional[CueList] = None) -> "OutputStage":
        """The stage of ``show`` played in ``mode`` on ``layout`` at ``fps``; ``cues`` is the show's cue list when
        already read (default: :meth:`Show.load_cues`). A layout whose rig has gloves gets the glove layer,
        mirrored as the show's renderer mirrors."""
        return cls(mode, layout.played_actuators, fps, ratio=show.mix_ratio, rule=show.resolved_rule(),
                   audio_preset=show.preset, power_limit=show_power_limit(len(layout.played_actuators)),
                   positions=layout.played_positions(), mirror_map=layout.played_mirror_map(),
                   comfort=show.comfort, cues=cues if cues is not None else show.load_cues(), music=music,
                   hands=cls.hand_layer(layout, fps, show.params().mirror))

    @staticmethod
    def hand_layer(layout: Layout, fps: float, mirror: bool) -> Optional[HandLayer]:
        """The glove layer of ``layout`` (``None`` when its rig has no gloves)."""
        return HandLayer(fps, mirror=mirror) if layout.hand_devices else None

    @classmethod
    def identity(cls, actuators: Sequence[str], fps: float, *, mirror_map: Optional[np.ndarray] = None,
                 comfort: Comfort = Comfort(), cues: Optional[CueList] = None) -> "OutputStage":
        """A stage that sends the incoming rows as they are (``play``), with cues (under the show's power limit)
        and comfort if given."""
        return cls("rows", actuators, fps, power_limit=show_power_limit(len(actuators)), mirror_map=mirror_map,
                   comfort=comfort, cues=cues)

    def to_dict(self) -> dict[str, Any]:
        """The mix settings a seat needs to build the same stage (:meth:`from_dict`): JSON-friendly."""
        return {"mix_ratio": [self.ratio[0], self.ratio[1]], "mix_rule": self.rule,
                "params_preset": self.audio_preset, "power_limit": self.power_limit}

    @staticmethod
    def check_settings(settings: Any, n_actuators: int) -> dict[str, Any]:
        """:meth:`to_dict`'s settings as a seat receives them, every field typed and bounded: ``mix_ratio`` two
        finite weights >= 0 (not both 0), ``mix_rule`` and ``params_preset`` known names, ``power_limit`` ``None``
        or within (0, ``n_actuators``] (every motor at full drive). UsageError naming the field otherwise. A seat
        never plays above the show's own limit (:func:`show_power_limit`): a missing limit, or one above it, is
        that limit."""
        if not isinstance(settings, dict):
            raise UsageError(f"music: expected an object of mix settings, found {type(settings).__name__}")
        ratio = settings.get("mix_ratio", [2.0, 3.0])
        if not (isinstance(ratio, (list, tuple)) and len(ratio) == 2
                and all(isinstance(r, (int, float)) and not isinstance(r, bool) for r in ratio)):
            raise UsageError(f"music.mix_ratio: expected [audio, motion] weights, found {ratio!r}"[:200])
        try:
            ratio = check_ratio(ratio)
        except OverflowError:  # a JSON integer of hundreds of digits has no float
            raise UsageError("music.mix_ratio: expected [audio, motion] weights, found a number beyond float "
                             "range") from None
        except UsageError as exc:
            raise UsageError(f"music.mix_ratio: {exc}") from None
        rule, preset = settings.get("mix_rule", "duck"), settings.get("params_preset", "felt")
        if not isinstance(rule, str) or rule not in MIX_RULES:
            raise UsageError(f"music.mix_rule: expected one of {', '.join(MIX_RULES)}, found {rule!r}"[:200])
        if not isinstance(preset, str) or preset not in PRESETS:
            raise UsageError(f"music.params_preset: expected one of {', '.join(PRESETS)}, found {preset!r}"[:200])
        limit = settings.get("power_limit")
        # compared before math.isfinite: a 400-digit integer compares fine but has no float (OverflowError)
        if limit is not None and not (isinstance(limit, (int, float)) and not isinstance(limit, bool)
                                      and 0 < limit <= n_actuators and math.isfinite(limit)):
            raise UsageError(f"music.power_limit: expected null or a number in (0, {n_actuators}] (every motor at "
                             f"full drive), found {limit!r}"[:200])
        ceiling = show_power_limit(n_actuators)
        return {"mix_ratio": [ratio[0], ratio[1]], "mix_rule": rule, "params_preset": preset,
                "power_limit": ceiling if limit is None else min(float(limit), ceiling)}

    @classmethod
    def from_dict(cls, settings: Optional[dict[str, Any]], mode: str, *, layout: Layout, fps: float,
                  comfort: Comfort = Comfort(), cues: Optional[CueList] = None,
                  music: Optional[RowTimeline] = None, mirror: bool = True) -> "OutputStage":
        """The stage :meth:`to_dict` describes, on ``layout`` at ``fps``, with a seat's own ``comfort`` and
        ``cues`` (and, when the seat's rig has gloves, the glove layer, mirrored as the seat's renderer
        mirrors). ``settings`` ``None`` or empty: a motion-only show (no mix; the show's power limit). Every field
        is checked (:meth:`check_settings`): UsageError naming the field, never an internal error."""
        n = len(layout.played_actuators)
        checked = cls.check_settings(settings or {"power_limit": show_power_limit(n)}, n)
        return cls(mode, layout.played_actuators, fps, ratio=tuple(checked["mix_ratio"]), rule=checked["mix_rule"],
                   audio_preset=checked["params_preset"], power_limit=checked["power_limit"],
                   positions=layout.played_positions(), mirror_map=layout.played_mirror_map(), comfort=comfort,
                   cues=cues, music=music, hands=cls.hand_layer(layout, fps, mirror))

    # ------------------------------------------------------------------ the mode stage (stateless)
    def condition(self, incoming: Optional[np.ndarray], music: Optional[np.ndarray], *,
                  out: Optional[np.ndarray] = None) -> np.ndarray:
        """Step 1 on ``(N,)`` or ``(T, N)`` rows 0..100: the incoming rows (``None``: silence) and the music's
        rows (``None``: silence) in this stage's mode; written into ``out`` (float64, the rows' shape, which may be
        ``incoming`` itself) when given."""
        if self.mode == "rows":
            return np.asarray(incoming, dtype=np.float64)
        if self.mode == "multimodal":
            return mix(incoming, music, ratio=self.ratio, power_limit=self.power_limit, rule=self.rule,
                       params=self.audio_params, kernel=self._kernel, out=out)
        chosen = incoming if self.mode == "motion" else music
        return limit_power(np.clip(chosen, 0.0, 100.0, out=out), self.power_limit, copy=False)  # in the clip's rows

    # ------------------------------------------------------------------ files: whole arrays
    def _full(self, rows: Optional[np.ndarray]) -> Optional[np.ndarray]:
        """Body-chart rows widened with silent hand places (rows already full width as they are)."""
        if rows is None or self.hands is None or np.shape(rows)[-1] == self.n:
            return rows
        rows = np.asarray(rows, dtype=np.float64)
        return np.concatenate([rows, np.zeros(rows.shape[:-1] + (self.n - rows.shape[-1],))], axis=-1)

    def _with_hands(self, out: np.ndarray, hands: np.ndarray) -> np.ndarray:
        """The hand places take the performer's hands (the stronger of the two), the row held to the power limit."""
        out = np.array(out, dtype=np.float64)
        out[..., self.body_n:] = np.maximum(out[..., self.body_n:], hands)
        return limit_power(out, self.power_limit)

    def rows(self, incoming: Optional[np.ndarray], music: Optional[np.ndarray],
             skeleton: Optional[np.ndarray] = None, *, out: Optional[np.ndarray] = None) -> np.ndarray:
        """The ``(T, N)`` rows sent for ``(T, N)`` incoming and music rows (either ``None``: silence), from a fresh
        state: mode, every cue of the list on the timeline, comfort. ``skeleton`` ``(T, 32, 3)`` (metres, NaN = not
        sent) drives the glove layer, when the stage has one. ``out``: a float64 ``(T, N)`` array of the caller's
        that step 1 writes into, which may be either input (an hour at 120 fps needs no second 180 MB); ignored
        when the rows are widened with hand places."""
        if incoming is None and music is None:
            raise ValueError("rows() needs the incoming rows, the music's rows, or both")
        if out is not None and self.hands is not None and np.shape(out)[-1] != self.n:
            out = None  # the rows are widened with the hand places: step 1 makes its own
        incoming, music = self._full(incoming), self._full(music)
        shape = (incoming if incoming is not None else music).shape
        out = self.condition(incoming if incoming is not None else np.zeros(shape),
                             music if music is not None else np.zeros(shape), out=out)
        if self.hands is not None and skeleton is not None and self.mode in ("motion", "multimodal"):
            out = self._with_hands(out, self.hands.rows(skeleton))
        if self.cue_list is not None:
            energy = cue_layer(self.cue_list, fps=self.fps, n_frames=out.shape[0], actuators=self.actuators,
                               mirror_map=self.mirror_map)
            out = layer(out, energy, self.power_limit)
        if not self.comfort.is_neutral:
            out, _ = limit_rows(out, self.comfort, self.fps)
        return out

    # ------------------------------------------------------------------ live: one row at a time
    @property
    def cues(self) -> Optional[LiveCues]:
        """The per-row cue layer (``None`` without cues), built on first use: :meth:`step` layers it on, a live
        session fires its cues by name and announces them to an audience."""
        if self._cues is None and self.cue_list is not None:
            self._cues = LiveCues(self.cue_list, fps=self.fps, actuators=self.actuators, mirror_map=self.mirror_map,
                                  power_limit=self.power_limit)
        return self._cues

    def step(self, incoming: Optional[np.ndarray], t: float, skeleton: Optional[np.ndarray] = None) -> np.ndarray:
        """The ``(N,)`` row sent at show time ``t`` seconds for the ``(N,)`` incoming row (``None``: none, as
        when the music plays alone); the cue layer and the comfort limiter move on by one row. ``skeleton``
        ``(32, 3)`` is the frame the row was rendered from (the glove layer's input; ``None``: the gloves rest)."""
        if not math.isfinite(t):
            raise ValueError(f"show time must be a finite number of seconds, not {t!r}")
        music = self._full(self.music.row(t)) if self.music is not None else self._silence
        if self.mode == "rows":
            row = np.array(self._full(incoming), dtype=np.float64)
        elif self.mode == "audio":
            row = self.condition(None, music)
        else:
            if incoming is None:
                raise ValueError(f"mode {self.mode} needs an incoming row")
            row = self.condition(self._full(incoming), music)
            if self.hands is not None and skeleton is not None and np.shape(skeleton) == (32, 3):
                row = self._with_hands(row, self.hands.step(skeleton, t))
        cues = self.cues
        if cues is not None:
            row = cues.layer(row, t)
        if self._limiter is not None:
            row = self._limiter.step(row)
        return row

    def describe(self) -> dict[str, Any]:
        """The stage's settings for a recording's metadata."""
        return {"mode": self.mode, **self.to_dict(), "comfort": self.comfort.to_dict(),
                "cues": str(self.cue_list.source) if self.cue_list is not None else None}

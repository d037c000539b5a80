"""A verdict per recording: what a wearer would feel, in words and numbers, for each method and preset.

The words are fixed bands of the metrics of :data:`~.scorecard.COLUMNS` (so two verdicts can be compared), the
numbers beside them the measured values.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .felt import FELT_LEVEL, MOVING_MPS
from .motor import DEFAULT_MOTOR, MotorModel
from .tables import number

__all__ = ["felt_words", "coupling_words", "stillness_words", "side_words", "run_sentence", "clip_verdict"]


def felt_words(share: float) -> str:
    """How often the show is felt while a hand moves (``share`` 0..1 of those frames)."""
    if share >= 0.9:
        return "clearly felt"
    if share >= 0.5:
        return "felt much of the time"
    if share >= 0.1:
        return "felt only now and then"
    return "barely felt"


def coupling_words(rho: float) -> str:
    """Whether the intensity follows the hands' speed (Spearman ``rho``)."""
    if rho >= 0.4:
        return "grows with the hands' speed"
    if rho >= 0.2:
        return "loosely follows the hands' speed"
    if rho > -0.2:
        return "does not follow the hands' speed"
    return "is weaker when the hands move faster"


def stillness_words(ratio: float) -> str:
    """Stillness against motion (mean total intensity while still / while moving)."""
    if ratio < 0.5:
        return "much quieter when the performer stands still"
    if ratio < 0.9:
        return "a little quieter when the performer stands still"
    if ratio <= 1.1:
        return "as strong when the performer stands still as in motion"
    return "stronger when the performer stands still than in motion"


def side_words(accuracy: float) -> str:
    """Where a one-hand gesture lands (share of its energy on the mirrored side)."""
    if accuracy >= 0.75:
        return "on the mirrored side"
    if accuracy >= 0.55:
        return "mostly on the mirrored side"
    if accuracy >= 0.45:
        return "on both sides alike"
    return "on the wrong side"


def _pct(x: float) -> str:
    return f"{number(100 * x, '.0f')} %"


def run_sentence(run, motor: MotorModel = DEFAULT_MOTOR) -> str:
    """One sentence on one (method, preset): strength, coupling, stillness, side, and with a song the mix."""
    s = run.scores
    start = 100 * motor.dead_zone
    parts = []
    if s.get("felt_moving") is None:
        parts.append(f"no hand moves faster than {MOVING_MPS:g} m/s, so nothing is asked of it")
    else:
        peak = s["peak_moving"]
        low = f", under the motors' start at {start:.0f}" if peak < start else ""
        parts.append(f"it is {felt_words(s['felt_moving'])} while a hand moves (a motor at {FELT_LEVEL:.0f} or more "
                     f"in {_pct(s['felt_moving'])} of those frames, strongest motor {peak:.0f} of 100{low})")
    if s.get("speed_rho") is not None:
        parts.append(f"it {coupling_words(s['speed_rho'])} (rank correlation {number(s['speed_rho'], '.2f')})")
    if s.get("still_ratio") is not None:
        parts.append(f"it is {stillness_words(s['still_ratio'])} ({_pct(s['still_ratio'])} of the moving level)")
    if s.get("lateral") is not None:
        parts.append(f"a one-hand gesture lands {side_words(s['lateral'])} ({_pct(s['lateral'])} of its energy "
                     "there)")
    text = f"With {run.method}/{run.preset}, " + "; ".join(parts) + "."
    if s.get("mix_lateral") is not None or s.get("onset_f") is not None:
        music = []
        if s.get("mix_lateral") is not None:
            covered = s.get("lateral") is not None and s["lateral"] >= 0.55 and s["mix_lateral"] < 0.55
            music.append(("the gesture's side is drowned: it" if covered else "the gesture")
                         + f" lands {side_words(s['mix_lateral'])} ({_pct(s['mix_lateral'])})")
        if s.get("onset_f") is not None:
            music.append(f"the music's onsets arrive as kicks the motors render with F = "
                         f"{number(s['onset_f'], '.2f')}")
        if s.get("mix_follows_audio") is not None:
            music.append(f"the overall level follows the music with a rank correlation of "
                         f"{number(s['mix_follows_audio'], '.2f')}")
        text += " With the music, " + ", ".join(music) + "."
    return text


def clip_verdict(clip, runs: Sequence, motor: MotorModel = DEFAULT_MOTOR) -> str:
    """One Markdown paragraph on one recording: what the performer does, then one sentence per run."""
    f = clip.facts
    n = max(f.n_frames, 1)
    duration = f.n_frames / f.fps
    one_hand = np.count_nonzero(f.hand >= 0) / n
    head = (f"**{clip.name}** ({duration:.1f} s): a hand moves faster than {MOVING_MPS:g} m/s in "
            f"{_pct(np.count_nonzero(f.moving) / n)} of the frames, one hand alone in {_pct(one_hand)}, and the "
            f"performer stands still in {_pct(np.count_nonzero(f.still) / n)}.")
    return " ".join([head] + [run_sentence(r, motor) for r in runs])

"""Measure the feel (issue 6): an ERM motor model, objective metrics of haptic tracks, a synthetic sweep bench and
the evaluation report behind ``hapmotion evaluate``.

* :mod:`.motor` -- first-order ERM model (spin-up/spin-down time constants, start threshold, saturation).
* :mod:`.metrics` -- pure metric functions over arrays (coupling and lag, locus error, constancy, smoothness,
  saturation and dead-zone rates, onset agreement).
* :mod:`.scorecard` -- every metric of one rendered track (a row of the table).
* :mod:`.sweep` -- synthetic motions of a hand tracing known paths, with metric values that can be reasoned out.
* :mod:`.report` -- renders recordings with each method and preset and writes Markdown/CSV tables and PNG figures.

docs/metrics.md defines each metric, its units and its source.
"""

from .motor import DEFAULT_MOTOR, MotorModel, simulate, step_times
from .scorecard import AUDIO_COLUMNS, COLUMNS, score_audio, score_track

__all__ = [
    "AUDIO_COLUMNS",
    "COLUMNS",
    "DEFAULT_MOTOR",
    "MotorModel",
    "score_audio",
    "score_track",
    "simulate",
    "step_times",
]

"""Measure the feel: an ERM motor model, objective metrics of haptic tracks, a synthetic sweep bench and the
evaluation behind ``hapmotion evaluate``.

* :mod:`.motor` -- first-order ERM model (spin-up/spin-down time constants, start threshold, saturation).
* Metric functions over arrays, one module per question: :mod:`.coupling` (does the vibration follow the hands'
  speed and reach, and how late), :mod:`.felt` (is it felt while the performer moves, quieter while still),
  :mod:`.locus` (where it is: centroid error, target jumps, the side of the vest), :mod:`.constancy` (does its
  strength hold between motors), :mod:`.smoothness` (jerk, SPARC, toggles, power above the motors' bandwidth),
  :mod:`.saturation` (commands pinned at full scale, commands under the motors' start), :mod:`.events` (tactile kicks, onset agreement).
* :mod:`.scorecard` -- every metric of one rendered track (a row of the table) and the column definitions.
* :mod:`.sweep` -- synthetic motions of a hand tracing known paths, with metric values that can be reasoned out.
* :mod:`.evaluation` -- the evaluation run; :mod:`.tables`, :mod:`.figures` and :mod:`.verdict` its outputs.

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

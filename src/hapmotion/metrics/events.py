"""Events in time: the tactile kicks of a track, and which estimated event times match reference times.

Agreement is the usual music-information-retrieval onset evaluation (precision, recall and F-measure within
+-50 ms, as mir_eval's ``onset.f_measure`` computes it): each estimated event may match at most one reference event
within the tolerance, and the number of matches is the maximum over all such one-to-one pairings (a maximum
bipartite matching, as mir_eval does). A maximum matching never counts fewer pairs than a greedy closest-first
pairing (kicks at 0 and 90 ms, onsets at -49 and 45 ms: greedy finds 1 pair, the maximum is 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal, sparse
from scipy.sparse.csgraph import maximum_bipartite_matching

__all__ = ["Agreement", "match_events", "kick_times"]


@dataclass(frozen=True)
class Agreement:
    """Precision, recall and F-measure of estimated events against reference events."""

    precision: float
    recall: float
    f_measure: float
    matched: int
    n_estimated: int
    n_reference: int

    def __str__(self) -> str:
        return (f"P={self.precision:.3f} R={self.recall:.3f} F={self.f_measure:.3f} "
                f"({self.matched} matched, {self.n_estimated} estimated, {self.n_reference} reference)")


def match_events(estimated: np.ndarray, reference: np.ndarray, tolerance_s: float = 0.05) -> Agreement:
    """One-to-one agreement of event times (seconds) within ``+-tolerance_s``.

    Empty inputs follow the usual convention: precision is 1 with no estimates, recall is 1 with no references.
    """
    est = np.sort(np.asarray(estimated, dtype=np.float64).ravel())
    ref = np.sort(np.asarray(reference, dtype=np.float64).ravel())
    matched = 0
    if est.size and ref.size:
        # candidate pairs: for each estimate, the references inside its window (both sorted, so a range each)
        lo = np.searchsorted(ref, est - tolerance_s - 1e-9, side="left")
        hi = np.searchsorted(ref, est + tolerance_s + 1e-9, side="right")
        counts = hi - lo
        rows = np.repeat(np.arange(est.size), counts)
        cols = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)]) if counts.sum() else np.zeros(0, int)
        if rows.size:
            graph = sparse.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(est.size, ref.size))
            matched = int((maximum_bipartite_matching(graph, perm_type="column") >= 0).sum())
    precision = matched / est.size if est.size else 1.0
    recall = matched / ref.size if ref.size else 1.0
    f = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return Agreement(precision, recall, f, matched, int(est.size), int(ref.size))


def kick_times(amplitude: np.ndarray, fps: float, min_rise: float = 0.1, min_gap_s: float = 0.05) -> np.ndarray:
    """Times of the tactile kicks in a track: sharp rises of its overall amplitude.

    ``S_t = sqrt(mean_i A_ti^2)`` (the vest's RMS amplitude, 0..1 whatever the number of motors); a kick is a local
    maximum of the rise ``S_t - S_{t-1}`` of at least ``min_rise`` at least ``min_gap_s`` after the previous kick.
    The 0.1 rise is the one Meta's Haptics SDK emphasis detector asks of its single 0..1 amplitude
    (``emphasis_detection.rs`` in facebook/meta-haptics-sdk), hence the mean over actuators: with a sum, a 1.4 % step
    of a bed on 52 motors would already count. The 50 ms spacing is the minimum peak spacing of Google's
    audio-to-tactile peak picker (``tactile_lite.c`` in google/audio-to-tactile). The kick's time is the start of
    the row where the rise happens (``t / fps``).

    Pass what the motors are driven with (:func:`hapmotion.metrics.motor.drive`), not the raw commands: a kick under
    the motors' start threshold starts no motor and is not a kick.

    ``amplitude``: ``(T, N)`` 0..1. Returns ``(K,)`` seconds, increasing.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    s = np.sqrt(np.einsum("tn,tn->t", a, a) / max(1, a.shape[1]))
    rise = np.diff(s, prepend=0.0)
    dist = max(1, int(np.ceil(min_gap_s * fps - 1e-9)))
    peaks, _ = signal.find_peaks(np.concatenate(([-np.inf], rise, [-np.inf])), height=min_rise, distance=dist)
    return (peaks - 1) / fps

"""Event agreement (onsets, kicks, beats): which estimated event times match reference times.

Agreement is the usual MIR onset evaluation (research doc section 5: precision/recall/F within +-50 ms): each
estimated event may match at most one reference event within the tolerance, and the number of matches is the
maximum over all such one-to-one pairings (a maximum bipartite matching, as mir_eval does).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import maximum_bipartite_matching


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

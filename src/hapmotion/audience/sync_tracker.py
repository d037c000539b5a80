"""From a stream of delay estimates to the delay a seat plays at: searching, locked, lost (sans-I/O).

Each :class:`~hapmotion.audience.sync_estimator.Estimate` is *good* when its score reaches :data:`MIN_SCORE` and
its margin :data:`MIN_MARGIN`, or, over a window whose both halves hold onsets, its score :data:`CLEAR_SCORE` and its
margin :data:`CLEAR_MARGIN`. The thresholds come from what unrelated signals reach: over a 3 s window, 6-10 s of
lags and five bands, a different song (the two shared songs against each other and against synthetic songs)
scored about 0.3 at most, a speech-like signal too, room noise 0.15, while the right song through a low-quality Vorbis
copy with room noise at 10 dB SNR scored 0.48 and more once the window was full of music.

A false lock is worse than a slow one, so only an estimate whose peak is the only candidate votes for a lock or a
jump: its margin (the score minus the best score at any other offset searched) reaches :data:`UNIQUE_MARGIN`. Music
that repeats its rhythm bar to bar puts a second peak a bar away, close to the true one and through noise sometimes
above it; such a close pair waits for audio that tells them apart: either a window where one stands clear, or one
offset that is the best in every window for :data:`STREAK_S` (the later windows hold audio the first did not).
Nor does a window vote for its best offset, alone or in a streak, where the band levels of the reference *as the seat
hears them* (under the heard copy's own noise floor: :func:`~hapmotion.audience.sync_estimator.heard_envelope_scores`)
do not favour it over its closest rival by :data:`HEARD_LEAD` (:func:`heard_tells`), and a locked seat moves to a
candidate only where they favour it over the offset it holds by :data:`HELD_LEAD` (:func:`favours`): through room
noise the onset score takes noise in the reference (a riser under a loop) for a match, which the levels as heard do
not, or by less than any real jump did.

* **searching**: voting estimates of the last :data:`VOTE_S` seconds; when :data:`LOCK_VOTES` of them agree
  within :data:`AGREE_S` and span at least :data:`LOCK_SPAN_S` (so they do not all come from one stretch of
  audio), the seat locks on their median. *Sharp* estimates (margin at least
  :data:`~hapmotion.audience.sync_estimator.SHARP_MARGIN`: the peak stands
  well clear of every other delay, which unrelated signals did not reach with a full window, over a window whose
  both halves hold onsets: two songs starting together after silence line up on their first onsets) need fewer:
  :data:`SHARP_VOTES` agreeing within :data:`SHARP_AGREE_S` over :data:`SHARP_SPAN_S`.
* **locked**: a Kalman filter on (offset, drift) follows the good estimates that fall within :data:`GATE_S` of its
  prediction; a drift of 0.1 % is 1 ms a second, which the drift state follows. Voting estimates outside the gate
  that agree among themselves (:data:`JUMP_VOTES`, spanning :data:`JUMP_SPAN_S`) are a jump (the viewer's player
  re-buffered or re-synced): the filter restarts there; sharp ones again need only :data:`SHARP_VOTES`, and an
  unbroken :data:`STREAK_S` of one offset outside the gate is one too. A match
  elsewhere votes for a jump only when it beats the held offset's own score (``Estimate.near_score``) by
  :data:`JUMP_LEAD`; music that repeats a section exactly scores the same at both, and one that does not beat the
  held offset confirms it instead (the seat keeps playing where it was rather than hopping to the repeat; it stays
  *locked*, the vest in step with what is heard, its confidence the held offset's own score).
* **after a jump in music that repeats** (a loop, bars that repeat their rhythm), the new offset and its aliases one
  period away score alike and none stands :data:`UNIQUE_MARGIN` clear until the music leaves the repeat. The offset
  just held is then a prior (:func:`prior_pick`): players re-sync at small drifts and re-buffer by about a second,
  so among the candidates within :data:`UNIQUE_MARGIN` of the best score the one nearest the held offset, within
  :data:`PRIOR_MAX_S` of it, votes for the jump (as a voting estimate does) when every other one lies at least
  :data:`PRIOR_FAR` times as far (a repeat one period further); a candidate that scores clearly better is never
  passed over (it is then the only candidate), and where two lie at like distances (a short repeat) none votes:
  the seat keeps the held offset and, since that no longer matches what is heard, says it lost the music after
  :data:`LOST_AFTER_S`. Before the prior, the loudness of what was heard since the jump is asked
  (:func:`envelope_pick`): bars that repeat a rhythm often differ in loudness (a chord, a fill, a drone), so among
  the same ambiguous candidates the one whose band-energy score (``Estimate.envelopes``, the window's last 1.5 s)
  stands :data:`ENVELOPE_LEAD` above every other and reaches :data:`ENVELOPE_MIN` votes for the jump the same way.
  That score alone is no evidence of a delay (it does not whiten the music, and unrelated music reaches 0.8): it
  only weighs candidates the onset score found, and the votes a jump needs stay the same. A jump the prior or the
  loudness decided is a guess (a jump of two thirds of a loop or more puts a wrong alias nearest; room noise that
  swells after a jump matches a riser in the next repeat better than the flat repeat heard): the seat reports it
  with :data:`ASSUMED_CONFIDENCE` at most (:attr:`DelayTracker.assumed`) until a window stands :data:`UNIQUE_MARGIN`
  clear at the offset held.
* **the notes** (chroma, ``Estimate.chroma_lead`` and ``Estimate.recent``): no estimate votes for a lock or a jump
  unless its offset's chroma score stands :data:`CHROMA_LEAD` above the median of the other candidates'
  (:func:`chroma_tells`: a different song at the venue's tempo lines its onsets up, not its notes); and a locked seat
  whose held offset the onsets cannot tell from the best (an alias of it a beat or a bar from the new offset after a
  jump: a 1 s re-buffer at 124 bpm is two beats and 32 ms) votes for the candidate whose notes and levels heard over
  the last 1.5 s lead the held offset's and every other candidate's (:func:`tonal_pick`), instead of confirming the
  held one.
* **lost**: no good estimate within the gate for :data:`LOST_AFTER_S`: the seat keeps the prediction (the stream
  most likely still plays where it did) and says so; after :data:`HOLD_S` more it is searching again and plays
  the user's fallback (the manual delay, or nothing).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .sync_estimator import N_PEAKS, SHARP_MARGIN, Estimate

MIN_SCORE = 0.40
MIN_MARGIN = 0.02
"""Margin (score minus the best score elsewhere) of an estimate that confirms the offset a locked seat holds."""
CLEAR_SCORE = 0.30
CLEAR_MARGIN = 0.20
"""An estimate whose window holds onsets in both halves (``Estimate.even``) and whose peak stands this far clear of
every other offset is good from :data:`CLEAR_SCORE` on, under :data:`MIN_SCORE`: over 9252 windows of unrelated
signals (benchmarks/sync_margins.py) no such window stood more than 0.15 clear at any score, while the right song
through a noisy copy can stand 0.2-0.3 clear at a score of 0.36-0.39 for its first seconds (vibe_ace through room
noise at 10 dB SNR: the seat waited 3 s more for the score to reach :data:`MIN_SCORE`)."""
UNIQUE_MARGIN = 0.10
"""Margin of an estimate that votes for a lock or a jump: its peak must be the only candidate. Over the right song
0.3-3 s late through the low-quality codec (twelve songs, 10 s of delays searched, benchmarks/sync_margins.py),
windows whose best offset was a wrong one (a bar that repeats the rhythm) stood at most 0.05 clear through room noise
at 10 dB SNR (0.08 in other draws of the delays) and none through the codec alone; with speech as loud as the music
over it one window of 2817 stood 0.19 clear, alone. Of the windows at the right delay 96 % (codec), 85 % (room noise)
and 46 % (speech over) stood 0.10 clear."""
STREAK_S = 1.5
"""How long one offset must be the best (score and the ordinary margin reached) in every window, unbroken, to lock or
jump on it when no window stands :data:`UNIQUE_MARGIN` clear (the later windows hold audio the first did not): a
wrong offset of the right song stayed best for 0.6 s at most through room noise and 0.1 s with speech over it (0.9 s
in other draws of the delays), the right one for 3.8 s and more in every song (benchmarks/sync_margins.py)."""
VOTE_S = 3.0
LOCK_VOTES = 4
AGREE_S = 0.025
LOCK_SPAN_S = 0.75
GATE_S = 0.045
JUMP_VOTES = 4
JUMP_SPAN_S = 0.5
JUMP_LEAD = 0.05
"""How far a match elsewhere must beat the held offset's own score to count towards a jump; below it the held offset
is confirmed. Through a noisy copy (room noise at 10 dB SNR) a bar that repeats the rhythm of the true one scored up
to 0.06 above it over a 3 s window (benchmarks/sync_margins.py): such a lead passes this test but not
:data:`UNIQUE_MARGIN` (the held offset is among the offsets it must stand clear of), nor, lasting 0.9 s at most,
:data:`STREAK_S`."""
PRIOR_MAX_S = 1.5
"""How far from the offset a locked seat held the new offset after a jump may be for the prior to pick it among
aliases: players re-sync at drifts of 0.1-0.9 s (VR world video players) and a short re-buffer or skip moves the
stream about a second; further jumps wait for the music to tell the aliases apart."""
PRIOR_FAR = 2.0
"""The prior picks the candidate nearest the held offset only when every other candidate within
:data:`UNIQUE_MARGIN` of the best score lies at least this many times as far from it (a repeat of the music one
period away from a short jump lies a period further, 1.6-4 s for bars and loops of songs)."""
ASSUMED_CONFIDENCE = 0.2
"""The confidence a seat reports while it plays at an offset the prior or the loudness chose (:func:`prior_pick`,
:func:`envelope_pick`) and no window has
yet stood :data:`UNIQUE_MARGIN` clear at it: the music itself did not tell that offset from its aliases (a jump of
two thirds of a loop or more puts the nearest alias, a wrong one, nearest the held offset), so the seat does not claim
what a lock the audio decided claims (the scores of those reach :data:`CLEAR_SCORE` and more)."""
ENVELOPE_LEAD = 0.10
"""How far one ambiguous candidate's band-energy score must stand above every other's for :func:`envelope_pick` to
pick it. After a jump (0.5-1.5 s both ways, twelve songs through the codec and with room noise at 10 dB SNR,
benchmarks/sync_margins.py), over 621 windows whose onset candidates were ambiguous the truth's band-energy score was
ahead of every alias's in all of them, by 0.10 or more in 70 % (the synthetic songs' smallest lead 0.06, median
0.11-1.2; vibe_ace's loop, which repeats its loudness too, 0.00-0.08: the prior decides there)."""
ENVELOPE_MIN = 0.70
"""Band-energy score the picked candidate must reach: the truth's was 0.74 at least in those windows (median 0.87);
music that is not the venue's reached 0.64 at its 99th percentile and 0.83 at most, standing up to 0.70 above the
next candidate: no evidence by itself, but over 9238 such windows none had the onset score (:data:`MIN_SCORE`, two
candidates within :data:`UNIQUE_MARGIN`) the pick needs first."""
HEARD_LEAD = 0.02
"""How far the band-energy score as heard (:func:`~hapmotion.audience.sync_estimator.heard_envelope_scores`) must
favour an offset over its rival, or over the offset a locked seat holds, for an estimate to vote for it. A loop under
a noise riser heard through steady room noise (seven runs: loops of 1.8-3.7 s, the riser 12 to 0 dB under the music,
5 to 20 dB SNR) put the onset score one loop off up to 0.22 clear of the truth, where this score favoured it by 0.000
at most; every vote at the right delay through the codec and room noise had a lead of 0.07 or more (median 0.32-0.38;
with speech as loud as the music over it 99 % reached 0.02), every jump followed 0.21 or more
(benchmarks/sync_margins.py). Room sound that changes within the window (noise switching on and off, applause, a
long reverberation) can defeat it: a locked seat asks more before it moves (:data:`HELD_LEAD`)."""
HELD_LEAD = 0.10
"""How far the band-energy score as heard must favour a candidate over the offset a locked seat holds for the seat to
move there (:func:`favours`). Every jump followed in benchmarks/sync_margins.py (1 s both ways, six songs through the
codec and room noise) led the held offset by 0.21 or more in the window the seat moved (median 0.84); the moves
back to the truth in the scenes below by 0.27 or more. Room sound that changes within the window over a loop with a
riser (noise switching on and off, swelling every 2.5 s, bursts of applause, a compressor, a 1 s reverberation;
loops of 1.8-2.2 s, the riser 6-12 dB over the music, the low-quality codec) moved seats holding the truth one loop
off for 2-17 s at confidence 0.45-0.76, with leads of 0.03-0.06 in the window they moved
(tests/test_audio_sync.py holds such cases). One scene still passes (a riser 18 dB over the music heard under
applause led by 0.21: docs/audience.md). A move the notes decide (:func:`tonal_pick`) asks the same lead of the
levels over the window's last 1.5 s; over the whole window, which still holds audio from before the jump, its lead
can be lower (0.03 in the least of 22 runs of benchmarks/sync_margins.py since)."""
CHROMA_LEAD = 0.20
"""How far the chroma score of an estimate's best offset must stand above the median of its other candidates'
(``Estimate.chroma_lead``, the whole window) for it to vote for a lock or a jump (:func:`chroma_tells`). A different
song at the venue's tempo lines its onsets up with the reference, not its notes: over the attack scenes (synthetic
songs and house tracks at one tempo, through the low-quality codec and room noise at 10 dB SNR) the windows good by
the onset score reached 0.20 in 1.7 % (synthetic) and 0.7 % (house) of them, never four agreeing, while the right
song did in 99-100 % of them (real songs, synthetic ones, house through laptop speakers: its 5th percentile 0.24)
(study behind docs/audience.md). The absolute chroma score does not decide it: laptop speakers' distortion lowered
the truth's to 0.44 (median), under a different house track's 0.59."""
CHROMA_HELD_LEAD = 0.15
"""How far a candidate's chroma score over the window's last 1.5 s must stand above the held offset's for a locked
seat to move there although the onset score does not tell them apart (:func:`tonal_pick`): after a 1 s jump in house
music the held offset lies within the gate of an alias two beats from the new offset, whose onsets score alike; 1-1.5
s after the jump the true offset's chroma led the held one's by 0.30 (median), 1.5-2 s after by 0.12 at the least
(house tracks through the codec, room noise, laptop speakers)."""
CHROMA_RIVAL_LEAD = 0.10
"""How far that candidate's chroma score must stand above every other candidate's (median lead of the truth over
every wrong candidate 1-2 s after a jump: 0.18-0.19 on house tracks, 0.45 on synthetic songs). Every candidate the
onsets found is a rival, also those beyond :data:`PRIOR_MAX_S`: in a loop that repeats exactly, the new offset and
its alias a loop away hold the same notes, and a pick among them would be the prior's guess by another name."""
SHARP_VOTES = 3
SHARP_AGREE_S = 0.010
SHARP_SPAN_S = 0.2
LOST_AFTER_S = 5.0
HOLD_S = 20.0
MEASUREMENT_S = 0.008
"""Standard deviation of one estimate (about one hop, from the harness) for the filter."""
OFFSET_WALK_S = 0.002
"""How far the offset may wander per square-root second apart from drift (jitter of the player's clock)."""
DRIFT_WALK = 2e-5
"""How fast the drift itself may change, per square-root second."""


@dataclass(frozen=True)
class SyncState:
    """What the seat reports: ``state`` ``searching`` | ``locked`` | ``lost``; ``offset_s`` the offset it plays at
    (local time minus media time of the heard music; None while searching), ``confidence`` 0..1 (the mean score of
    the held offset over the last windows that heard music, those that confirmed it and those that did not; 0 while
    searching, :data:`ASSUMED_CONFIDENCE` at most while lost or at a guessed offset),
    ``drift`` (seconds per second), ``jumps`` and ``locks`` counted."""

    state: str
    offset_s: Optional[float]
    confidence: float
    drift: float = 0.0
    jumps: int = 0
    locks: int = 0


def _agreed(points: list[tuple[float, float, float]]) -> Optional[float]:
    """The offset that ``(at, offset, margin)`` votes agree on by the ordinary or the sharp rule, or None."""
    size, median, span = _cluster([(a, o) for a, o, _ in points], AGREE_S)
    if size >= LOCK_VOTES and span >= LOCK_SPAN_S:
        return median
    return _sharp_median(points)


def _sharp_median(points: list[tuple[float, float, float]]) -> Optional[float]:
    """The offset that the sharp ``(at, offset, margin)`` votes (margin at least ``SHARP_MARGIN``) agree on, enough
    of them over a long enough time, or None."""
    size, median, span = _cluster([(a, o) for a, o, m in points if m >= SHARP_MARGIN], SHARP_AGREE_S)
    return median if size >= SHARP_VOTES and span >= SHARP_SPAN_S else None


def prior_pick(est: Estimate, held: float) -> Optional[float]:
    """The candidate of ``est`` a seat that held ``held`` (seconds) moves to when the music does not tell its
    candidates apart (module docstring), or None: every candidate within :data:`UNIQUE_MARGIN` of the best score is
    ambiguous (a clearly better one is never passed over); the nearest ambiguous one to ``held`` is picked when it
    lies beyond the gate and within :data:`PRIOR_MAX_S` of it, reaches :data:`MIN_SCORE`, and every other ambiguous
    one lies :data:`PRIOR_FAR` times as far. The held offset itself scoring among them (``near_score``), or the
    candidates listed running out before the ambiguous ones do, picks nothing."""
    if not est.peaks or (est.near_score is not None and est.near_score > est.score - UNIQUE_MARGIN):
        return None
    close = [(abs(o - held), o, s) for o, s in est.peaks if s > est.score - UNIQUE_MARGIN]
    if len(close) == len(est.peaks) and len(close) >= N_PEAKS:
        return None  # more candidates may lie beyond the ones listed
    close.sort()
    dist, offset, score = close[0]
    if not (GATE_S < dist <= PRIOR_MAX_S) or score < MIN_SCORE:
        return None
    if any(d < PRIOR_FAR * dist for d, _, _ in close[1:]):
        return None
    return offset


def envelope_pick(est: Estimate, held: float) -> Optional[float]:
    """The candidate of ``est`` whose band-energy score (``Estimate.envelopes``, the audio heard since a jump)
    stands out among the candidates the onset score leaves ambiguous (module docstring), or None: the candidates
    within :data:`UNIQUE_MARGIN` of the best onset score, the held offset not among them (``near_score``); the one
    with the highest band-energy score is picked when it lies beyond the gate from ``held``, its onset score reaches
    :data:`MIN_SCORE`, its band-energy score :data:`ENVELOPE_MIN`, and every other ambiguous one's band-energy score
    is known and :data:`ENVELOPE_LEAD` under it, and so is the held offset's (``Estimate.held_envelope``). The
    candidates listed running out before the ambiguous ones do picks nothing, and so does a held offset whose
    reference is not whole: where the heard music runs past the reference received (the show's end, a gap), the true
    offset cannot score and a bar that repeats earlier in the reference would win (benchmarks/bench_sync.py: a seat
    jumped one bar off 40 s into a 40 s show)."""
    if not est.peaks or len(est.envelopes) != len(est.peaks) or est.held_envelope is None or (
            est.near_score is not None and est.near_score > est.score - UNIQUE_MARGIN):
        return None
    close = [(e, o, s) for (o, s), e in zip(est.peaks, est.envelopes) if s > est.score - UNIQUE_MARGIN]
    if len(close) < 2 or (len(close) == len(est.peaks) and len(close) >= N_PEAKS):
        return None
    if any(e is None for e, _, _ in close):
        return None
    close.sort(reverse=True)
    env, offset, score = close[0]
    if abs(offset - held) <= GATE_S or score < MIN_SCORE or env < ENVELOPE_MIN:
        return None
    if max(close[1][0], est.held_envelope) > env - ENVELOPE_LEAD:
        return None
    return offset


def heard_tells(est: Estimate) -> bool:
    """The band levels as the seat hears them favour ``est``'s best offset over its closest rival by
    :data:`HEARD_LEAD` (``Estimate.rival_lead``; True where it has none): only then may the estimate vote for it,
    alone or in a streak."""
    return est.rival_lead is None or est.rival_lead >= HEARD_LEAD


def chroma_tells(est: Estimate) -> bool:
    """The chroma does not say that ``est``'s best offset lines up the onsets of another song: its lead over the other
    candidates (``Estimate.chroma_lead``) reaches :data:`CHROMA_LEAD` (True where unknown)."""
    return est.chroma_lead is None or est.chroma_lead >= CHROMA_LEAD


def tonal_pick(est: Estimate, held: float) -> Optional[float]:
    """The candidate of ``est`` a locked seat moves to although the onset score leaves it ambiguous with the offset
    held (``Estimate.recent``, the window's last 1.5 s), or None: the one with the best chroma score, beyond the
    gate from ``held``, leading the held offset's chroma by :data:`CHROMA_HELD_LEAD`, every other candidate's by
    :data:`CHROMA_RIVAL_LEAD` (every candidate the onsets found, not only the ambiguous ones: two speakers 0.25 s
    apart, equally loud, moved a seat to the second one's copy while the first's scored under the ambiguous ones), and
    the held offset's band-energy score as heard by :data:`HELD_LEAD`, and lying within :data:`PRIOR_MAX_S` of the
    held offset (a re-buffer or a player's re-sync, the prior's range: a loop's next repeat holding a noise riser,
    heard through room noise that swells after a jump, put that repeat 0.10-0.14 ahead of the truth's chroma, 1.6 s
    from the held offset, as it does the band levels; tests/test_audio_sync.py)."""
    if len(est.recent) < 2:
        return None
    *cands, (_, env_held, ch_held) = est.recent
    known = sorted(((c, e, o) for o, e, c in cands if c is not None), key=lambda k: k[0], reverse=True)
    if not known or ch_held is None or env_held is None:
        return None
    ch, env, offset = known[0]
    if not GATE_S < abs(offset - held) <= PRIOR_MAX_S or env is None or ch < ch_held + CHROMA_HELD_LEAD \
            or env < env_held + HELD_LEAD:
        return None
    if len(known) > 1 and known[1][0] > ch - CHROMA_RIVAL_LEAD:
        return None
    return offset


def favours(est: Estimate, offset: float) -> bool:
    """The band levels as the seat hears them favour candidate ``offset`` of ``est`` over the offset a locked seat
    holds by :data:`HELD_LEAD` (``Estimate.held_leads``): only then may the seat move there. True where that is
    unknown (the held offset not asked or outside the range searched, a reference not whole) or ``offset`` is no
    candidate."""
    for (o, _), lead in zip(est.peaks, est.held_leads):
        if abs(o - offset) <= AGREE_S:
            return lead is None or lead >= HELD_LEAD
    return True


def _cluster(points: list[tuple[float, float]], agree: float) -> tuple[int, float, float]:
    """The largest group of ``(at, offset)`` within ``agree`` of one member's offset: (size, median offset, span of
    their times)."""
    if not points:
        return 0, 0.0, 0.0
    offs = np.array([p[1] for p in points])
    ats = np.array([p[0] for p in points])
    best = (0, 0.0, 0.0)
    for o in offs:
        near = np.abs(offs - o) <= agree
        size = int(near.sum())
        if size > best[0]:
            best = (size, float(np.median(offs[near])), float(ats[near].max() - ats[near].min()))
    return best


def is_good(est: Optional[Estimate]) -> bool:
    """An estimate sure enough to count towards a lock: a high score with any margin, or a clear margin over a
    window with onsets throughout."""
    return est is not None and ((est.score >= MIN_SCORE and est.margin >= MIN_MARGIN)
                                or (est.even and est.score >= CLEAR_SCORE and est.margin >= CLEAR_MARGIN))


class DelayTracker:
    """Feed :meth:`update` every estimate (or None) with its time; read :attr:`state` (a :class:`SyncState`) and
    :meth:`offset_at` (the offset to play at, local time ``t``)."""

    def __init__(self) -> None:
        self.state = SyncState("searching", None, 0.0)
        self._votes: deque[tuple[float, float, float, float]] = deque()  # (at, offset, score, margin), good ones
        # (at, offset, margin, clear): votes for a jump; clear ones stood UNIQUE_MARGIN clear, the others are picks
        self._jump: deque[tuple[float, float, float, bool]] = deque()
        self._x = np.zeros(2)     # offset at _t, drift
        self._p = np.eye(2)
        self._t = 0.0
        self._confirmed = 0.0
        self._scores: deque[float] = deque(maxlen=8)
        # the same best offset, unbroken: when it began, and its latest (at, offset, score) (bounded: a locked seat's
        # streak lasts as long as the show)
        self._streak_from = 0.0
        self._streak: deque[tuple[float, float, float]] = deque(maxlen=16)
        self.jumps = 0
        self.locks = 0
        self.assumed = False
        """The offset held was chosen by the prior or the loudness tie-break and the music has not yet confirmed it
        (:data:`ASSUMED_CONFIDENCE`)."""

    # ------------------------------------------------------------------ filter
    def _start(self, at: float, offset: float) -> None:
        self._x = np.array([offset, 0.0])
        self._p = np.diag([MEASUREMENT_S ** 2, (5e-4) ** 2])
        self._t = at
        self._confirmed = at
        self._jump.clear()
        self._streak.clear()
        self.assumed = False

    def _predict(self, at: float) -> tuple[np.ndarray, np.ndarray]:
        dt = max(0.0, at - self._t)
        f = np.array([[1.0, dt], [0.0, 1.0]])
        q = np.diag([OFFSET_WALK_S ** 2 * dt, DRIFT_WALK ** 2 * dt])
        return f @ self._x, f @ self._p @ f.T + q

    def offset_at(self, t: float) -> Optional[float]:
        """The offset to play at local time ``t`` (None while searching)."""
        if self.state.state == "searching":
            return None
        return float(self._x[0] + self._x[1] * (t - self._t))

    # ------------------------------------------------------------------ update
    def update(self, est: Optional[Estimate], at: float) -> SyncState:
        good = is_good(est)
        while self._votes and self._votes[0][0] < at - VOTE_S:
            self._votes.popleft()
        while self._jump and self._jump[0][0] < at - VOTE_S:
            self._jump.popleft()
        # only a peak that stands clear of every other offset votes: a bar that repeats the rhythm of the true one
        # scores close to it (or above it), and such a pair of candidates waits for audio that tells them apart
        # the band levels as the seat hears them must not favour a rival: else the onset score's lead rests on noise
        told = good and heard_tells(est) and chroma_tells(est)
        unique = told and est.margin >= UNIQUE_MARGIN
        if unique:
            self._votes.append((at, est.offset_s, est.score, est.margin if est.even else 0.0))
        # a close pair of candidates is told apart by more audio: the same offset best in every window for
        # STREAK_S, each window holding audio the first did not, is a vote of its own
        if not (told and self._streak and abs(est.offset_s - self._streak[-1][1]) <= AGREE_S):
            self._streak.clear()
            self._streak_from = at
        if told:
            self._streak.append((at, est.offset_s, est.score))
        streak = (float(np.median([o for _, o, _ in self._streak]))
                  if self._streak and at - self._streak_from >= STREAK_S else None)
        mode = self.state.state
        if mode == "searching":
            median = _agreed([(a, o, m) for a, o, _, m in self._votes])
            if median is None and streak is not None:
                median = streak
                self._votes.extend((a, o, s, 0.0) for a, o, s in self._streak)  # (their scores: confidence)
            if median is not None:
                self._start(at, median)
                self._scores.extend(s for _, o, s, _ in self._votes if abs(o - median) <= AGREE_S)
                self.locks += 1
                self._votes.clear()
                return self._report("locked")
            return self._report("searching")
        x, p = self._predict(at)
        # the notes heard since a jump tell the new offset from an alias of the held one that the onsets cannot
        tonal = tonal_pick(est, float(x[0])) if est is not None and est.near_whole else None
        if good and tonal is None and abs(est.offset_s - x[0]) <= GATE_S:
            s = p[0, 0] + MEASUREMENT_S ** 2
            k = p[:, 0] / s
            self._x = x + k * (est.offset_s - x[0])
            self._p = p - np.outer(k, p[0, :])
            self._t = at
            self._confirmed = at
            self._jump.clear()
            self._scores.append(est.score)
            if unique:
                self.assumed = False  # the music alone now tells the offset held from every other
            return self._report("locked")
        if tonal is None and est is not None and est.near_score is not None and est.near_score >= MIN_SCORE \
                and est.score - est.near_score < JUMP_LEAD:
            # the held offset scores as well as the best one (a repeated section): still the music played here, and
            # the vest in step with what is heard; the confidence follows the held offset's own score
            self._confirmed = at
            self._scores.append(est.near_score)
            return self._report("locked")
        if est is not None and not (est.near_whole and favours(est, est.offset_s)):
            # a lost reference batch over the held offset's window lowers its score and not an alias's whose window
            # misses the gap, and a best offset the levels as heard do not favour over the held one leads on noise:
            # no vote to move (nor a streak) rests on such a comparison
            unique, streak = False, None
            self._streak.clear()
            self._streak_from = at
        # music that repeats its rhythm leaves the candidates no margin: the loudness of what was heard since the jump
        # tells them apart where it differs, else the prior weighs them on their distances
        prior = None
        if tonal is not None:
            unique = False
            self._jump.append((at, tonal, 0.0, True))  # the music's own evidence: a clear vote
        elif est is not None and not unique and est.near_whole:
            prior = envelope_pick(est, float(x[0]))
            if prior is None:
                prior = prior_pick(est, float(x[0]))
            if prior is not None and not favours(est, prior):
                prior = None
        if unique or streak is not None or prior is not None or tonal is not None:
            if unique:
                self._jump.append((at, est.offset_s, est.margin if est.even else 0.0, True))
            elif prior is not None:
                # the loudness or the distance picked among candidates the onsets could not tell apart: a guess
                # either way (the heard copy's loudness, room noise that swells over it, is not the
                # reference's), so a jump it decides is assumed until a window stands clear at it
                self._jump.append((at, prior, 0.0, False))
            size, median, span = _cluster([(a, o) for a, o, _, _ in self._jump], AGREE_S)
            sharp = _sharp_median([(a, o, m) for a, o, m, _ in self._jump])
            if sharp is not None:  # here sharp votes win over the ordinary cluster (a jump follows them sooner)
                size, median, span = JUMP_VOTES, sharp, JUMP_SPAN_S
            by_music = sharp is not None
            if streak is not None and abs(streak - x[0]) > GATE_S:
                size, median, span = JUMP_VOTES, streak, JUMP_SPAN_S
                by_music = True
            if size >= JUMP_VOTES and span >= JUMP_SPAN_S:
                # a jump the clear votes alone would have made is the music's; one that needed the prior's is assumed
                clear_size, _, clear_span = _cluster([(a, o) for a, o, _, clear in self._jump
                                                      if clear and abs(o - median) <= AGREE_S], AGREE_S)
                by_music = by_music or (clear_size >= JUMP_VOTES and clear_span >= JUMP_SPAN_S)
                self.jumps += 1
                self._start(at, median)
                self.assumed = not by_music
                self._scores.clear()
                self._scores.append(est.score)
                return self._report("locked")
        silent_for = at - self._confirmed
        if silent_for > LOST_AFTER_S + HOLD_S:
            self._votes.clear()
            self._scores.clear()
            return self._report("searching")
        if est is not None and est.near_score is not None:
            # music heard that does not confirm the held offset (another song, a jump not followed yet): the
            # confidence follows the held offset's own score down (silence, no estimate, leaves it as it was)
            self._scores.append(max(0.0, est.near_score))
        return self._report("lost" if silent_for > LOST_AFTER_S else mode)

    def _report(self, state: str) -> SyncState:
        offset = None if state == "searching" else float(self._x[0])
        confidence = float(np.mean(self._scores)) if (self._scores and state != "searching") else 0.0
        if (self.assumed and state != "searching") or state == "lost":
            # a guess, or a delay no match has confirmed for LOST_AFTER_S: not what the music decided
            confidence = min(confidence, ASSUMED_CONFIDENCE)
        self.state = SyncState(state, offset, confidence, float(self._x[1]) if offset is not None else 0.0,
                               self.jumps, self.locks)
        return self.state

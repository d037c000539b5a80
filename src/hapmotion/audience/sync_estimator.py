"""How far behind the venue a seat hears the music: the offset that best lines the heard levels up with the venue's
reference (sans-I/O, numpy only).

The heard levels ``(W, B)`` (:mod:`hapmotion.audio.sync_features`, hop ``n`` at local time ``t_heard + n / RATE``)
and the reference levels ``(N, B)`` (hop ``j`` at media time ``t_ref + j / RATE``) are turned into onset novelty,
and each band's heard novelty is cross-correlated with the reference at every lag, normalised by both sides'
energy over the window (a normalised cross-correlation; the novelty's two-hop difference already whitens the slow
envelope, which is what GCC-PHAT's weighting does to a spectrum, without PHAT's noise gain in bands the music
leaves empty). The bands' coefficients are averaged, so a lag scores 1 only where every band's onsets line up.

An :class:`Estimate` gives the best lag as an offset (local time minus media time, seconds, refined between hops
by a parabola through the peak), its score (-1..1), and its *margin*: the score minus the best score more than
:data:`EXCLUSION_S` away. Music repeats itself (beats, bars), so a second peak one beat away is normal; what tells
a real match from chance is a score well above what unrelated signals reach over that many lags and bands. The
thresholds that decide it live in :mod:`hapmotion.audience.sync_tracker`.

The onsets carry rhythm, not pitch: given both sides' chroma (:class:`Chroma`), :func:`match` adds what the notes
say of its candidates (:func:`chroma_scores`): how far the best one's notes line up better than the others'
(:attr:`Estimate.chroma_lead`: a different song at the venue's tempo lines up its onsets, not its notes), and, for a
locked seat whose held offset scores among the best, every candidate's chroma and band-energy scores over the
window's last :data:`RECENT_S` (:attr:`Estimate.recent`: after a jump, an alias of the held offset a beat or a bar
from the new one scores as well on onsets, not on notes).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Optional

import numpy as np
from scipy.ndimage import uniform_filter1d

from ..audio.sync_features import CHROMA_RATE, RATE, novelty

EXCLUSION_S = 0.06
"""The second-best peak is looked for at least this far from the best one."""
LOCAL_MEAN_S = 0.5
"""Each side's novelty has its mean over this long taken out before matching: onsets are one or two hops wide and
pass, while where the music is merely busy (a song starting after silence or noise) does not: two different songs
that both start after silence would otherwise line up on the step from quiet to busy."""
MIN_ACTIVE_BANDS = 2
"""Bands whose heard novelty varies over the window; fewer (silence, a pure tone) gives no estimate."""
MIN_NOVELTY_DB = 0.05
"""A band whose heard novelty has a smaller standard deviation (dB) is silent or stationary noise: left out."""
MIN_EVENTS = 40.0
"""A band's heard novelty must spread over at least this many hops' worth of rises (its participation ratio,
``(sum |h|)^2 / sum h^2``: 1 for a single click, about 100 for 3 s of music): a window holding one or two onsets
(the music just starting, a door slam) lines up with almost anything, so it is no evidence."""

MIN_ONSET_HOPS = 20.0
"""The same participation ratio of the novelty *before* the local mean is taken out must reach this: the mean's
removal spreads each onset over :data:`LOCAL_MEAN_S`, so the first 0.2 s of a song after silence passed the
ratio above, and two different songs that start together lined up on their first onsets (score 0.77)."""

N_PEAKS = 8
"""Candidates an estimate lists: music that repeats a stretch within the offsets searched puts a peak at each repeat
(the seat's default 10 s of delays hold two or three repeats of a 3-4 s loop, and four of a 2.6 s bar with the
peaks between bars that its rhythm adds: after synthetic-2026's jump, benchmarks/bench_sync.py, four listed
candidates all lay within the voting margin of the best for a second, which a pick cannot decide on)."""

NEAR_S = 0.045
"""How close to a held offset a peak counts as that offset (the tracker's gate)."""


def _participation(x: np.ndarray) -> np.ndarray:
    """``(n, B)`` -> ``(B,)``: ``(sum x)^2 / sum x^2``, how many hops' worth of non-negative values each band holds."""
    return x.sum(axis=0) ** 2 / np.maximum((x * x).sum(axis=0), 1e-12)


@dataclass(frozen=True)
class Estimate:
    """One match of a window of heard audio: ``offset_s`` local time minus media time of the heard music, ``score``
    the averaged normalised correlation at that offset (-1..1), ``margin`` the score minus the best score elsewhere,
    ``bands`` how many bands took part, ``at`` the local time of the window's last hop."""

    offset_s: float
    score: float
    margin: float
    bands: int
    at: float
    even: bool = False
    """Both halves of the heard window hold onsets (:data:`MIN_ONSET_HOPS` / 2 in at least :data:`MIN_ACTIVE_BANDS`
    bands each) and the reference over the best offset's window was all received (none of it before the song's start
    or in a gap): the match does not rest on the music starting (or stopping) inside the window on either side. Room
    noise before a song passes the first test; with the second, a window holding noise and under a second of the song
    no longer made sharp votes for an offset where the song's first second resembles a later one (the true offset
    lines the noise up with the reference before the song's start, whose bands hold too few onsets to count)."""
    near_score: Optional[float] = None
    """The best score within :data:`NEAR_S` of the ``near`` offset asked for (the offset a locked seat holds), None
    when not asked or out of the range searched."""
    peaks: tuple[tuple[float, float], ...] = ()
    """The candidates: ``(offset_s, score)`` of the highest peaks of the score, at most :data:`N_PEAKS`, each at least
    :data:`EXCLUSION_S` from a higher one, best first (the first is ``offset_s``, ``score``)."""
    envelopes: tuple[Optional[float], ...] = ()
    """The band-energy score (:func:`envelope_scores`) of each of :attr:`peaks` over the window's last
    :data:`RECENT_S` (in order; None where the reference is not whole there): filled in by :func:`match` for a
    locked seat whose window lands away from the offset it holds (after a jump), empty otherwise."""
    held_envelope: Optional[float] = None
    """The same band-energy score at the offset the locked seat holds, None when not asked or where the reference
    there is not whole (the music heard has run past the reference received, a gap)."""
    rival_lead: Optional[float] = None
    """How far the best offset's band-energy score *as heard* (:func:`heard_envelope_scores`) stands above that of
    its closest rival, the best of the candidates scoring within :data:`RIVAL` of it; None where there is none or a
    score is unknown."""
    held_leads: tuple[Optional[float], ...] = ()
    """The same lead of each of :attr:`peaks` over the ``near`` offset (in order; empty when not asked or out of
    the range searched, None where a score is unknown)."""
    near_whole: bool = True
    """The reference over the ``near`` offset's window was all received (True when not asked or out of the range
    searched): where it was not (a lost batch), the held offset's score is lowered by the gap while an alias whose
    window misses the gap keeps its own, so the scores do not compare (the tracker takes no vote to move from it)."""
    chroma_lead: Optional[float] = None
    """How far the best offset's chroma score (:func:`chroma_scores`, the whole window) stands above the median of
    the other candidates' (:attr:`peaks`): about 0 for a different song, whose notes line up with the reference at no
    offset in particular; None where fewer than three candidates' are known (no chroma given, the reference not
    whole)."""
    recent: tuple[tuple[float, Optional[float], Optional[float]], ...] = ()
    """For a locked seat (``held`` given to :func:`match`) whose offset the onset score does not tell from the best
    (its score within :data:`AMBIGUOUS` of it): ``(offset, band-energy score as heard, chroma score)`` over the
    window's last :data:`RECENT_S` of every candidate (:attr:`peaks`) away from the held offset, the held offset last
    (None where unknown); empty otherwise."""


def estimate(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
             near: Optional[float] = None) -> Optional[Estimate]:
    """The best offset of ``heard_db`` ``(W, B)`` within ``ref_db`` ``(N, B)`` (N > W; NaN rows: reference hops not
    received, they match nothing). Offsets searched: ``t_heard - t_ref - l / RATE`` for lags ``l = 0 .. N - W``;
    ``near`` (an offset, seconds) asks for the best score around it as well (:attr:`Estimate.near_score`).
    None when the heard window is silent or stationary, or the reference holds no music over the range."""
    w, n = heard_db.shape[0], ref_db.shape[0]
    if w < 8 or n <= w:
        return None
    size = max(3, int(round(LOCAL_MEAN_S * RATE)) | 1)
    h = novelty(heard_db)
    # onsets counted before the local mean is taken out: the mean's removal spreads one onset over LOCAL_MEAN_S of
    # hops, and 0.2 s of music after silence would then pass for a window full of onsets
    raw_events = _participation(h)
    half = w // 2
    even = bool(((_participation(h[:half]) >= MIN_ONSET_HOPS / 2).sum() >= MIN_ACTIVE_BANDS)
                and ((_participation(h[half:]) >= MIN_ONSET_HOPS / 2).sum() >= MIN_ACTIVE_BANDS))
    h -= uniform_filter1d(h, size, axis=0, mode="nearest")
    missing = ~np.isfinite(ref_db).all(axis=1)
    r = novelty(np.where(missing[:, None], np.nan, ref_db))
    r -= uniform_filter1d(r, size, axis=0, mode="nearest")
    # hops next to a gap carry a difference across it: zeroed by novelty(); the gap itself matches nothing
    h = h - h.mean(axis=0, keepdims=True)
    h_norm = np.sqrt((h * h).sum(axis=0))
    events = np.abs(h).sum(axis=0) ** 2 / np.maximum(h_norm ** 2, 1e-12)
    active = (h_norm / np.sqrt(w) > MIN_NOVELTY_DB) & (events >= MIN_EVENTS) & (raw_events >= MIN_ONSET_HOPS)
    if active.sum() < MIN_ACTIVE_BANDS:
        return None
    h, h_norm, r = h[:, active], h_norm[active], r[:, active]
    n_lags = n - w + 1
    size = 1 << (n + w - 1).bit_length()  # (the FFT's length from here on)
    # cross-correlation of every band at every lag by FFT: c[l] = sum_k h[k] r[k + l]
    spec = np.fft.rfft(r, size, axis=0) * np.conj(np.fft.rfft(h, size, axis=0))
    c = np.fft.irfft(spec, size, axis=0)[:n_lags]
    # the reference's energy over each lag's window (its mean taken out: h has zero mean, so c is unchanged)
    s1 = np.concatenate([np.zeros((1, r.shape[1])), np.cumsum(r, axis=0)])
    s2 = np.concatenate([np.zeros((1, r.shape[1])), np.cumsum(r * r, axis=0)])
    win1 = s1[w:] - s1[:-w]
    win2 = s2[w:] - s2[:-w]
    var = np.maximum(win2 - win1 * win1 / w, 0.0)
    denom = h_norm[None, :] * np.sqrt(var)
    s_abs = np.concatenate([np.zeros((1, r.shape[1])), np.cumsum(np.abs(r), axis=0)])
    r_events = (s_abs[w:] - s_abs[:-w]) ** 2 / np.maximum(win2, 1e-12)
    # a reference band with hardly any onsets over the lag's window (not received yet, a few hops of music at the
    # window's edge) is no evidence either way: it counts 0. Half the heard side's minimum: at the true lag of a
    # song that just started, both sides hold the same second of music and the same number of onsets
    quiet = (var < 1e-4 * (h_norm[None, :] ** 2)) | (r_events < MIN_EVENTS / 2)
    coef = np.where(quiet, 0.0, c / np.where(quiet, 1.0, denom))
    score = coef.mean(axis=1)
    if not np.isfinite(score).any() or np.all(quiet):
        return None
    best = int(np.argmax(score))
    # the reference at the best lag must be whole as well: a window that lines the heard audio up with the song's
    # start (or a gap) rests on the music starting inside it on the reference's side
    even = even and not bool(missing[best:best + w].any())
    peak = float(score[best])
    frac = _refine(score, best)
    ex = max(1, int(round(EXCLUSION_S * RATE)))
    others = np.concatenate([score[:max(0, best - ex)], score[best + ex + 1:]])
    second = float(others.max()) if others.size else -1.0
    offset = t_heard - t_ref - (best + frac) / RATE
    peaks = _peaks(score, ex, t_heard - t_ref)
    near_score, near_whole = None, True
    if near is not None:
        lags = np.arange(n_lags)
        dist = np.abs(t_heard - t_ref - lags / RATE - near)  # offset of lag l: t_heard - t_ref - l / RATE
        close = dist <= NEAR_S
        if close.any():
            near_score = float(score[close].max())
            near_lags = lags[close]
            near_whole = not bool(missing[near_lags.min():near_lags.max() + w].any())
    moving = near_score is not None and abs(offset - near) > NEAR_S
    rival_lead, held_leads = _heard_leads(heard_db, t_heard, ref_db, t_ref, peaks, near if moving else None)
    return Estimate(float(offset), peak, peak - second, int(active.sum()), t_heard + (w - 1) / RATE, even,
                    near_score, peaks, rival_lead=rival_lead, held_leads=held_leads, near_whole=near_whole)


def _heard_leads(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
                 peaks: tuple[tuple[float, float], ...], held: Optional[float]
                 ) -> tuple[Optional[float], tuple[Optional[float], ...]]:
    """:attr:`Estimate.rival_lead` and :attr:`Estimate.held_leads` of ``peaks`` (best first): the band-energy scores
    as heard (:func:`heard_envelope_scores`) of the best against its rivals and, given ``held`` (a locked seat whose
    best lies elsewhere: a move to weigh), of every candidate against the offset held."""
    best, best_score = peaks[0]
    rivals = [i for i, (_, s) in enumerate(peaks) if i and s >= best_score - RIVAL]  # indices into peaks
    asked = list(range(1, len(peaks))) if held is not None else rivals  # a move to weigh: every candidate
    if not asked:
        return None, ()
    env = heard_envelope_scores(heard_db, t_heard, ref_db, t_ref,
                                [best] + [peaks[i][0] for i in asked] + ([held] if held is not None else []))
    by_peak = dict(zip(asked, env[1:]))
    known = [by_peak[i] for i in rivals if by_peak[i] is not None]
    rival_lead = env[0] - max(known) if env[0] is not None and known else None
    if held is None:
        return rival_lead, ()
    at_held = env[-1]
    return rival_lead, tuple(None if e is None or at_held is None else e - at_held for e in env[:len(peaks)])

RIVAL = 0.25
"""Candidates scoring within this of the best are its rivals (:attr:`Estimate.rival_lead`)."""
FLOOR_PERCENTILE = 5.0
"""The heard copy's noise floor in a band: this percentile of its level over the window (the quiet between notes,
where a room's or a codec's noise shows)."""
LOUD_PERCENTILE = 95.0
"""Each side's loud level in a band; their difference carries the heard floor to the reference's scale (the
stream's volume and equalisation are unknown)."""
_NEPER = np.log(10.0) / 10.0
"""dB to the natural logarithm of a power."""


def as_heard(heard_db: np.ndarray, ref_db: np.ndarray) -> np.ndarray:
    """The reference levels ``ref_db`` ``(N, B)`` dB (NaN rows: not received) as a seat hears them: with the noise
    floor of the heard levels ``heard_db`` ``(W, B)`` added in power, each band's floor (:data:`FLOOR_PERCENTILE`)
    carried to the reference's scale by the difference of the two sides' loud levels (:data:`LOUD_PERCENTILE`).
    ``(N, B)`` dB, NaN rows kept. A clean copy (a loopback's digital silence between notes) adds nothing."""
    hd = np.asarray(heard_db, dtype=np.float64)
    rd = np.asarray(ref_db, dtype=np.float64)
    heard_rows = hd[np.isfinite(hd).all(axis=1)]
    ref_rows = rd[np.isfinite(rd).all(axis=1)]
    if not (heard_rows.size and ref_rows.size):
        return rd
    quiet, loud = np.percentile(heard_rows, [FLOOR_PERCENTILE, LOUD_PERCENTILE], axis=0)
    floor = quiet - (loud - np.percentile(ref_rows, LOUD_PERCENTILE, axis=0))
    with np.errstate(invalid="ignore"):  # NaN rows stay NaN
        return np.logaddexp(rd * _NEPER, floor * _NEPER) / _NEPER


def heard_envelope_scores(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
                          offsets: "list[float]") -> tuple[Optional[float], ...]:
    """:func:`envelope_scores` of the heard levels ``(W, B)`` against the reference ``(N, B)`` as heard
    (:func:`as_heard`) at each offset (seconds).

    The onset score of an offset depends on all of its reference window, including what the heard copy shows only
    as noise: where a band's notes poke through a noise floor, the noise's rises come and go with the music, and a
    reference with noise of its own (a riser swelling under a loop) shows the same pattern, which the score takes
    for a match. A loop under a riser, heard through room noise, thus scored one loop off (where the riser is
    loudest) 0.1-0.3 clear of the truth for seconds. The band levels of the reference under the heard copy's own
    floor compare like with like: there the wrong loop never led the truth (by 0.000 at most), while the true offset
    led its rivals by 0.07 and more through the codec and room noise (benchmarks/sync_margins.py)."""
    return envelope_scores(heard_db, t_heard, as_heard(heard_db, ref_db), t_ref, offsets)


SHARP_MARGIN = 0.15
"""Margin of a *sharp* estimate, one whose peak stands well clear of every other offset searched. Over 3 s windows
that are :attr:`Estimate.even`, a different song (the shared songs and synthetic ones from benchmarks/sync_scenes.py
against each other, through the low-quality codec, with and without room noise) or a speech-like signal stood
0.15 at most above its next peak, 0.15 or more in 1 of 9252 windows (never three agreeing, which a lock needs); the
right song through the codec with room noise at 10 dB SNR was sharp in 57 % of its windows at the right delay, 82 %
without the noise (benchmarks/sync_margins.py, 10 s of delays searched). The tracker locks and follows jumps on
fewer sharp estimates; a recent part of the window (below) is believed only when sharp."""

RECENT_S = 1.5
"""A locked seat whose full window does not confirm the offset it holds matches the last this-many seconds of it as
well (the shortest window a seat matches at all): after a jump, the full window holds audio of both offsets and their
two peaks share its score for as long as both halves last, while the recent part holds the new one alone."""


ENVELOPE_SMOOTH = 5
"""Hops (50 ms) of each band's level averaged before the envelopes are compared: through room noise a band's level
hop to hop is noise's, the envelope of notes and bars is not."""


def envelope_scores(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
                    offsets: "list[float] | tuple[float, ...]") -> tuple[Optional[float], ...]:
    """How well the heard band levels ``(W, B)`` dB follow the reference's ``(N, B)`` at each offset (seconds, as
    :func:`estimate` counts them): the Pearson correlation of each band's level (smoothed over
    :data:`ENVELOPE_SMOOTH` hops), averaged over the bands whose heard level varies; -1..1, None where the reference
    at that offset is not whole or lies outside ``ref_db``. The onset score sees only rises, so two bars with the
    same rhythm score alike; their loudness over the bars (a chord change, a fill, a louder section) often differs,
    which this sees. Unlike the onset score it does not whiten: by itself it peaks broadly and is no evidence of a
    delay; it only weighs candidates the onset score already found."""
    w = heard_db.shape[0]
    h = uniform_filter1d(np.asarray(heard_db, dtype=np.float64), ENVELOPE_SMOOTH, axis=0, mode="nearest")
    h = h - h.mean(axis=0)
    h_norm = np.sqrt((h * h).sum(axis=0))
    live = h_norm / np.sqrt(max(w, 1)) > MIN_NOVELTY_DB
    out: list[Optional[float]] = []
    for o in offsets:
        lag = int(round((t_heard - t_ref - o) * RATE))
        if not live.any() or lag < 0 or lag + w > ref_db.shape[0] or not np.isfinite(ref_db[lag:lag + w]).all():
            out.append(None)
            continue
        r = uniform_filter1d(np.asarray(ref_db[lag:lag + w], dtype=np.float64), ENVELOPE_SMOOTH, axis=0,
                             mode="nearest")
        r = r - r.mean(axis=0)
        r_norm = np.sqrt((r * r).sum(axis=0))
        ok = live & (r_norm > 1e-9)
        if not ok.any():
            out.append(None)
            continue
        out.append(float(np.mean((h[:, ok] * r[:, ok]).sum(axis=0) / (h_norm[ok] * r_norm[ok]))))
    return tuple(out)


@dataclass(frozen=True)
class Chroma:
    """The chroma of both sides for :func:`match`: ``heard`` ``(Wc, 12)`` dB, its hop ``i`` heard at local time
    ``t_heard + i / CHROMA_RATE``; ``ref`` ``(Nc, 12)`` dB, hop ``j`` at media time ``t_ref + j / CHROMA_RATE`` (NaN
    rows: not received)."""

    heard: np.ndarray
    t_heard: float
    ref: np.ndarray
    t_ref: float


CHROMA_WHOLE = 0.8
"""Share of the heard chroma hops whose reference must be there for a chroma score (a window at the edge of the
reference received scores on the rest)."""


def chroma_scores(ch: Chroma, offsets: "list[float] | tuple[float, ...]", last_s: Optional[float] = None
                  ) -> tuple[Optional[float], ...]:
    """How well the heard chroma follows the reference's at each offset (seconds, local minus media time), over the
    heard chroma's last ``last_s`` seconds (all of it when None): each pitch class's mean over the window is taken
    out on each side (a codec's or a speaker's colouring, the song's key held throughout), then each hop's profile
    is correlated with the reference's across the twelve classes and the correlations averaged over the hops;
    -1..1, None where under :data:`CHROMA_WHOLE` of the reference is there or nothing varies. Two songs at one
    tempo line their onsets up but not their notes (study of the attack scenes: a different song scored 0.39 at
    most against the synthetic songs through the codec and room noise, the right song 0.65 and more); a beat or a
    bar off the notes differ too, unless the music repeats them exactly."""
    h_all = np.asarray(ch.heard, dtype=np.float64)
    if last_s is not None:
        h_all = h_all[max(0, h_all.shape[0] - int(round(last_s * CHROMA_RATE))):]
    t_h = ch.t_heard + (ch.heard.shape[0] - h_all.shape[0]) / CHROMA_RATE
    w = h_all.shape[0]
    out: list[Optional[float]] = []
    for o in offsets:
        first = int(round((t_h - o - ch.t_ref) * CHROMA_RATE))
        lo, hi = max(0, first), min(ch.ref.shape[0], first + w)
        if hi - lo < CHROMA_WHOLE * w or w < 4:
            out.append(None)
            continue
        r = np.asarray(ch.ref[lo:hi], dtype=np.float64)
        h = h_all[lo - first:hi - first]
        ok = np.isfinite(r).all(axis=1)
        if ok.sum() < CHROMA_WHOLE * w:
            out.append(None)
            continue
        h, r = h[ok], r[ok]
        h = h - h.mean(axis=0)
        r = r - r.mean(axis=0)
        h = h - h.mean(axis=1, keepdims=True)
        r = r - r.mean(axis=1, keepdims=True)
        den = np.sqrt((h * h).sum(axis=1) * (r * r).sum(axis=1))
        live = den > 1e-9
        out.append(float(np.mean((h * r).sum(axis=1)[live] / den[live])) if live.sum() >= CHROMA_WHOLE * w / 2
                   else None)
    return tuple(out)


def _with_chroma(est: Optional[Estimate], heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
                 held: Optional[float], ch: Optional[Chroma]) -> Optional[Estimate]:
    """``est`` with :attr:`Estimate.chroma_lead` and, for a locked seat whose candidates the onset score leaves
    ambiguous with the offset held, :attr:`Estimate.recent`."""
    if est is None or ch is None or not est.peaks:
        return est
    offs = [o for o, _ in est.peaks]
    full = chroma_scores(ch, offs)
    others = [c for c, o in zip(full[1:], offs[1:]) if c is not None and abs(o - offs[0]) > NEAR_S]
    lead = full[0] - float(np.median(others)) if full[0] is not None and len(others) >= 3 else None
    recent: tuple = ()
    if held is not None and est.near_score is not None and est.near_score > est.score - AMBIGUOUS:
        cands = [o for o, _ in est.peaks if abs(o - held) > NEAR_S] + [held]
        if len(cands) > 1:
            k = heard_db.shape[0] - int(round(RECENT_S * RATE))
            env = heard_envelope_scores(heard_db[k:], t_heard + k / RATE, ref_db[k:], t_ref + k / RATE, cands) \
                if k > 0 else (None,) * len(cands)
            recent = tuple(zip(cands, env, chroma_scores(ch, cands, RECENT_S)))
    return replace(est, chroma_lead=lead, recent=recent)


AMBIGUOUS = 0.10
"""A held offset scoring within this of the best has its candidates weighed by :attr:`Estimate.recent` (the
tracker's ``UNIQUE_MARGIN``: one further under the best is left by the onset score's own votes)."""


def match(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
          held: Optional[float] = None, chroma: Optional[Chroma] = None) -> Optional[Estimate]:
    """:func:`_match` with the chroma's evidence added (:attr:`Estimate.chroma_lead`, :attr:`Estimate.recent`)
    when ``chroma`` is given."""
    return _with_chroma(_match(heard_db, t_heard, ref_db, t_ref, held), heard_db, t_heard, ref_db, t_ref, held,
                        chroma)


def _match(heard_db: np.ndarray, t_heard: float, ref_db: np.ndarray, t_ref: float,
           held: Optional[float] = None) -> Optional[Estimate]:
    """The estimate a seat acts on: :func:`estimate` of the whole heard window ``(W, B)`` (``held``: the offset a
    locked seat holds, its score asked for), or, when that does not land within :data:`NEAR_S` of ``held``, of the
    window's last :data:`RECENT_S` seconds (the same offsets searched), which says where the music is now, if that
    is sharp (:data:`SHARP_MARGIN`): a shorter window fits inside a repeated bar more easily, and music that repeats
    within the offsets searched leaves its peak no margin, so then the whole window's estimate stands, its candidates
    weighed by their band-energy scores over that recent part (:attr:`Estimate.envelopes`, :func:`envelope_scores`:
    what was heard since a jump)."""
    est = estimate(heard_db, t_heard, ref_db, t_ref, near=held)
    k = heard_db.shape[0] - int(round(RECENT_S * RATE))
    if held is None or k <= 0 or (est is not None and abs(est.offset_s - held) <= NEAR_S):
        return est
    # hop k of the window against reference hop k + l: the same offsets t_heard - t_ref - l / RATE as above
    recent = estimate(heard_db[k:], t_heard + k / RATE, ref_db[k:], t_ref + k / RATE, near=held)
    if recent is not None and recent.margin >= SHARP_MARGIN:
        return recent
    if est is None or not est.peaks:
        return est
    # the candidates weighed by the loudness of the audio heard since the jump (the recent part alone)
    env = envelope_scores(heard_db[k:], t_heard + k / RATE, ref_db[k:], t_ref + k / RATE,
                          [o for o, _ in est.peaks] + [held])
    return replace(est, envelopes=env[:-1], held_envelope=env[-1])


def _peaks(score: np.ndarray, ex: int, zero: float) -> tuple[tuple[float, float], ...]:
    """The :data:`N_PEAKS` highest local maxima of ``score`` ``(L,)`` at least ``ex`` lags from a higher one, as
    ``(offset, score)`` best first (lag ``l`` is offset ``zero - l / RATE``, refined as the best one is)."""
    s = score.copy()
    out = []
    for _ in range(N_PEAKS):
        k = int(np.argmax(s))
        if not np.isfinite(s[k]):  # every lag taken
            break
        out.append((float(zero - (k + _refine(score, k)) / RATE), float(score[k])))
        s[max(0, k - ex):k + ex + 1] = -np.inf
    return tuple(out)


def _refine(score: np.ndarray, k: int) -> float:
    """Fraction of a lag (-0.5..0.5) of the parabola's vertex through ``score[k - 1 .. k + 1]`` (0 at the ends or
    where ``k`` is no peak)."""
    if 0 < k < score.size - 1:
        a, b, c = score[k - 1], score[k], score[k + 1]
        den = a - 2.0 * b + c
        if den < 0:
            return float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))
    return 0.0


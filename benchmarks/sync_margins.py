"""What the sync thresholds rest on: the scores and margins a seat's matching gives the right music and music that is
not the venue's (offline, no network; about 2 minutes of CPU). Not a timed test: figures are printed beside the
thresholds of :mod:`hapmotion.audience.sync_tracker` and :mod:`hapmotion.audience.sync_estimator`.

``python -m benchmarks.sync_margins [--seconds S]``

The songs: the two shared songs and six synthetic ones (:func:`benchmarks.sync_scenes.synth_song`, seeds 100-105).
For each as the venue's reference, a seat's matching (levels in 20 ms blocks, a 3 s window every 0.1 s, offsets
from -0.25 to 10 s, the seat's default, the tracker fed as a seat feeds it) runs over what a viewer hears: *wrong*,
two other songs through the low-quality codec (1 s of silence first), each clean and with room noise at 10 dB SNR,
and a speech-like signal with room noise; *right*, the song itself (and the harness's synthetic songs, seeds 2026,
2027, 7, 8) 0.3-3 s late through the codec, alone, with room noise at 10 dB SNR, and with speech as loud as the music
over it. Printed: for the wrong signals, the highest score and margin, the windows whose margin (both halves holding
onsets) reaches the sharp margin, the locks; for the right one, the share of correct estimates that stand clear
enough to vote for a lock or a jump and that are sharp, the highest margin an estimate at a wrong delay (a bar away
in music that repeats its rhythm) reached, which the voting margin must exceed, and the longest unbroken run of
windows whose best offset is one wrong delay, which the streak a lock may rest on must exceed; and, for the shared
songs and the harness's synthetic ones (seeds 2026, 2027, 7, 8) heard 1.3 s late through the codec with room noise,
how far a peak elsewhere (a bar that repeats the rhythm) ever scored above the true offset; whether the right music
without a jump ever made the seat jump or play off the truth; and a 1 s jump 20 s into the music (both ways, the six
songs through the codec and with room noise, delays of 1.3-3 s): how long the seat took to re-lock, whether it played
at an offset that was neither the old nor the new one, and for the slowest re-locks the candidates that competed 2 s
after the jump (each one's distance from the offset held and its score under the best: aliases a period apart score
alike, and :func:`~hapmotion.audience.sync_tracker.prior_pick` decides among them by their distances); how far the
band levels as heard (:func:`~hapmotion.audience.sync_estimator.heard_envelope_scores`) favoured each vote at the
right delay over its rival and each followed jump over the delay held, and how far they ever favoured a wrong loop
that the onset score put first in music that loops under a noise riser, heard through room noise (seven runs); and
whether the band-energy score (:func:`~hapmotion.audience.sync_estimator.envelope_scores`, the levels of the audio heard
since a jump) tells those aliases apart: after jumps of 0.5-1.5 s both ways in twelve songs (the shared ones, the
harness's synthetic ones, six more) through the codec and with room noise, the truth's lead over the best alias in
every window the onset score left ambiguous, and, over music that is not the venue's, how high a wrong candidate's
band-energy score and lead reach and how often the pick
(:func:`~hapmotion.audience.sync_tracker.envelope_pick`) would act on one (about 50 s more). For the wrong signals'
windows with a good score and the right music's votes, the chroma lead a vote needs
(:data:`~hapmotion.audience.sync_tracker.CHROMA_LEAD`: how far the best offset's chroma score stands above the
median of the other candidates').
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import soundfile as sf

from hapmotion.audience.sync_estimator import NEAR_S, RECENT_S, SHARP_MARGIN, envelope_scores, estimate
from hapmotion.audience.seat_sync import SyncSettings
from hapmotion.audience.sync_tracker import (AGREE_S, CHROMA_LEAD, CLEAR_MARGIN, CLEAR_SCORE, ENVELOPE_LEAD,
                                             ENVELOPE_MIN, HEARD_LEAD, HELD_LEAD, JUMP_LEAD, MIN_MARGIN, MIN_SCORE,
                                             STREAK_S, UNIQUE_MARGIN, heard_tells)
from hapmotion.audio.sync_features import N_BANDS, RATE, dequantise, quantise, signal_levels

from tests.support.data import AUDIO
from tests.support.sync_signals import follow as seat_matching
from tests.support.sync_signals import riser_loop

from . import sync_scenes as scenes

SR = scenes.SR
MAX_DELAY_S = SyncSettings().max_delay_s  # the seat's default range (--sync-max-delay)


def _jumped(coded: np.ndarray, ref: np.ndarray, delay: float, jump: float, after_s: float, kind: str,
            seed: int) -> tuple[float, np.ndarray, list]:
    """``coded`` heard ``delay`` s late, jumping by ``jump`` s 20 s into the music (as in the harness: vibe_ace is in
    its loop then), for ``after_s`` more, with room noise at 10 dB SNR when ``kind`` is ``noisy``; the seat's matching
    against ``ref``: (the jump's local time, the heard signal, [(local time, Estimate, SyncState)])."""
    jump_t = delay + 20.0
    tau = np.arange(int((jump_t + after_s) * SR)) / SR
    h = scenes.heard(coded, np.where(tau < jump_t, tau - delay, tau - delay - jump))
    if kind == "noisy":
        h = scenes.add_noise(h, 10.0, seed)
    history, _ = seat_matching(h, ref, max_delay_s=MAX_DELAY_S)
    return jump_t, h, history


def follow(heard: np.ndarray, source: np.ndarray, states: bool = False) -> tuple:
    """The seat's matching of ``heard`` (local time: its sample time) against ``source`` (media time: its sample
    time) over the seat's default range of delays: [Estimate or None] per window and the tracker after it all (and,
    with ``states``, the tracker's SyncState after each window)."""
    history, tracker = seat_matching(heard, source, max_delay_s=MAX_DELAY_S)
    ests = [est for _, est, _ in history]
    return (ests, tracker, [s for _, _, s in history]) if states else (ests, tracker)


def longest_runs(ests: list, delay_s: float) -> tuple[float, float]:
    """The longest unbroken runs (seconds from the first window to the last) of consecutive windows whose estimate
    reaches the score and the ordinary margin at one offset (within the tracker's agreement), at a wrong offset and at
    the true one ``delay_s``: what :data:`~hapmotion.audience.sync_tracker.STREAK_S` must tell apart."""
    wrong = right = 0.0
    run: list = []
    for e in ests:
        if e is None or e.score < MIN_SCORE or e.margin < MIN_MARGIN:
            run = []
            continue
        run = run + [e] if run and abs(e.offset_s - run[-1].offset_s) <= AGREE_S else [e]
        span = run[-1].at - run[0].at
        if abs(run[-1].offset_s - delay_s) > 0.04:
            wrong = max(wrong, span)
        else:
            right = max(right, span)
    return wrong, right


def leads(heard: np.ndarray, source: np.ndarray, delay_s: float) -> np.ndarray:
    """For each 3 s window of ``heard`` (``source`` ``delay_s`` late) matched as a seat holding the true offset
    does: how far the best peak elsewhere scores above the truth (0 where the truth is the best)."""
    ref = dequantise(quantise(signal_levels(source, SR)))
    levels = dequantise(quantise(signal_levels(heard, SR)))
    out = []
    for end in range(600, levels.shape[0] - 10, 10):
        t_heard = (end - 300) / RATE
        first = int(math.floor((t_heard - MAX_DELAY_S) * RATE))
        span = 300 + int((MAX_DELAY_S + 0.25) * RATE)
        idx = np.arange(first, first + span)
        r = np.full((span, N_BANDS), np.nan)
        ok = (idx >= 0) & (idx < ref.shape[0])
        r[ok] = ref[idx[ok]]
        est = estimate(levels[end - 300:end], t_heard, r, first / RATE, near=delay_s)
        if est is not None and est.near_score is not None:
            out.append(est.score - est.near_score if abs(est.offset_s - delay_s) > NEAR_S else 0.0)
    return np.array(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=25.0, help="seconds heard per signal (default 25)")
    args = ap.parse_args(argv)
    secs = args.seconds
    n = int(secs * SR)

    real = [sf.read(AUDIO / name, dtype="float64")[0] for name in ("vibe_ace.ogg", "lets_go_fishin.ogg")]
    songs = [x if x.ndim == 1 else x.mean(axis=1) for x in real] + [scenes.synth_song(100 + k, secs)
                                                                   for k in range(6)]
    # the harness's synthetic songs (seeds 2026, 2027, 7, 8) as the right music only
    extra = [scenes.synth_song(k, secs + 16.0) for k in (2026, 2027, 7, 8)]
    rng = np.random.default_rng(5)

    def lead(x: np.ndarray) -> np.ndarray:
        return np.concatenate([np.zeros(SR), x])[:n]

    wrong, right, wrong_locks, lead_rows, runs = [], [], 0, [], []
    right_jumps = right_off = 0
    for i, song in enumerate(songs):
        ref = song[:int((secs + 15.0) * SR)]
        heard = []
        for j in ((i + 1) % len(songs), (i + 3) % len(songs)):
            h = scenes.codec_copy(lead(songs[j][:n]))
            heard += [h, scenes.add_noise(h, 10.0, i)]
        heard.append(scenes.add_noise(lead(scenes.speech_like(i, secs)), 10.0, i + 7))
        for h in heard:
            ests, tracker = follow(h, ref)
            wrong += [e for e in ests if e is not None]
            wrong_locks += tracker.locks
    for i, song in enumerate(songs + extra):
        ref = song[:int((secs + 15.0) * SR)]
        for kind in ("codec", "noisy", "speech over"):
            delay = float(rng.uniform(0.3, 3.0))
            tau = np.arange(n) / SR
            h = scenes.codec_copy(scenes.heard(ref, tau - delay))
            if kind == "noisy":
                h = scenes.add_noise(h, 10.0, i)
            elif kind == "speech over":  # as loud as the music (0 dB)
                o = np.resize(scenes.speech_like(i + 1, secs), n)
                h = h + o * float(np.sqrt(np.mean(h * h))) / max(1e-9, float(np.sqrt(np.mean(o * o))))
            ests, tracker, states = follow(h, ref, states=True)
            runs.append((kind, *longest_runs(ests, delay)))
            right_jumps += tracker.jumps
            right_off += sum(s.state != "searching" and abs(s.offset_s - delay) > 0.04 for s in states)
            right += [(e, abs(e.offset_s - delay) < 0.04, kind) for e in ests if e is not None]
    w = np.array([(e.score, e.margin, e.even) for e in wrong])
    even = w[:, 2] > 0
    sharp = even & (w[:, 1] >= SHARP_MARGIN)
    print(f"wrong music and speech: {len(w)} windows matched, {wrong_locks} locks (target 0)")
    print(f"  highest score {w[:, 0].max():.2f} (a vote needs {MIN_SCORE:.2f} and others to agree); windows at or "
          f"above it {int((w[:, 0] >= MIN_SCORE).sum())}")
    print(f"  highest margin with onsets in both halves {w[even, 1].max():.2f} (sharp: {SHARP_MARGIN:.2f}); "
          f"99.9th percentile {np.percentile(w[even, 1], 99.9):.2f}; sharp windows {int(sharp.sum())}")
    good_wrong = [e.chroma_lead for e in wrong if e.score >= MIN_SCORE and e.margin >= MIN_MARGIN
                  and e.chroma_lead is not None]
    print(f"  chroma lead (the best offset's chroma score over the other candidates' median) of the {len(good_wrong)} "
          f"windows with a good score: {CHROMA_LEAD:.2f} or more in "
          f"{np.mean(np.array(good_wrong) >= CHROMA_LEAD) * 100 if good_wrong else 0.0:.1f} % (a vote needs it), "
          f"95th percentile {np.percentile(good_wrong, 95) if good_wrong else math.nan:.2f}, highest "
          f"{max(good_wrong, default=math.nan):.2f}")
    clear = even & (w[:, 0] >= CLEAR_SCORE) & (w[:, 1] >= CLEAR_MARGIN)
    print(f"  windows with onsets in both halves, a score of {CLEAR_SCORE:.2f} or more and {CLEAR_MARGIN:.2f} clear "
          f"(good under the score {MIN_SCORE:.2f}): {int(clear.sum())} (target 0)")
    kinds = np.array([k for _, _, k in right])
    for kind in ("codec", "noisy", "speech over"):
        sel = kinds == kind
        ok = np.array([good for _, good, _ in right])[sel]
        r = np.array([(e.score, e.margin, e.even) for e, _, _ in right])[sel]
        r_sharp = (r[:, 2] > 0) & (r[:, 1] >= SHARP_MARGIN)
        vote = r[:, 0] >= MIN_SCORE
        wrong = vote & ~ok
        top = f"{r[wrong, 1].max():.3f}" if wrong.any() else "-"
        print(f"right music ({kind}; {len(songs) + len(extra)} songs): {len(r)} windows, {ok.mean() * 100:.0f} % at "
              f"the right delay; of those {vote[ok].mean() * 100:.0f} % reach the score, "
              f"{(vote[ok] & (r[ok, 1] >= UNIQUE_MARGIN)).mean() * 100:.0f} % stand {UNIQUE_MARGIN:.2f} clear (a "
              f"lock or jump vote), {r_sharp[ok].mean() * 100:.0f} % are sharp; at a wrong delay {int(wrong.sum())} "
              f"reach the score, their margin at most {top} (a vote needs {UNIQUE_MARGIN:.2f}), "
              f"{int((wrong & (r[:, 1] >= UNIQUE_MARGIN)).sum())} reach it")
        votes = [e for (e, good, k) in right if k == kind and good and e.score >= MIN_SCORE
                 and e.margin >= UNIQUE_MARGIN]
        kept = sum(heard_tells(e) for e in votes)
        rivals = [e.rival_lead for e in votes if e.rival_lead is not None]
        print(f"  of those votes at the right delay {kept / max(len(votes), 1) * 100:.1f} % have the band levels as "
              f"heard favouring them over their closest rival by {HEARD_LEAD:.2f} or more (a vote needs it; "
              f"{len(rivals)} had a rival): the least lead {min(rivals, default=math.nan):.3f}, 5th percentile "
              f"{np.percentile(rivals, 5) if rivals else math.nan:.3f}, median "
              f"{np.median(rivals) if rivals else math.nan:.3f}")
        tonal = [e.chroma_lead for e in votes if e.chroma_lead is not None]
        print(f"  their chroma lead over the other candidates: {CHROMA_LEAD:.2f} or more in "
              f"{np.mean(np.array(tonal) >= CHROMA_LEAD) * 100 if tonal else 0.0:.1f} % of {len(tonal)} (a vote needs "
              f"it), 5th percentile {np.percentile(tonal, 5) if tonal else math.nan:.2f}, median "
              f"{np.median(tonal) if tonal else math.nan:.2f}")
        low = (r[:, 2] > 0) & (r[:, 0] >= CLEAR_SCORE) & (r[:, 0] < MIN_SCORE) & (r[:, 1] >= CLEAR_MARGIN)
        print(f"  under the score {MIN_SCORE:.2f} but from {CLEAR_SCORE:.2f}, {CLEAR_MARGIN:.2f} clear with onsets in "
              f"both halves: {int((low & ok).sum())} at the right delay, {int((low & ~ok).sum())} at a wrong one; at a "
              f"wrong delay from {CLEAR_SCORE:.2f}, with onsets in both halves, the margin at most "
              f"{np.max(r[~ok & (r[:, 0] >= CLEAR_SCORE) & (r[:, 2] > 0), 1], initial=0.0):.3f}")
        rr = np.array([(w, g) for k, w, g in runs if k == kind])
        print(f"  one offset best in every window, unbroken, at most: {rr[:, 0].max():.1f} s at a wrong delay, "
              f"{rr[:, 1].min():.1f}-{rr[:, 1].max():.1f} s at the right one per song (a lock or jump on that "
              f"alone needs {STREAK_S:.1f} s)")
    print(f"right music, no jump (all three kinds): jumps followed {right_jumps}, windows played more than 40 ms off "
          f"the truth {right_off} (target 0 and 0)")
    # the lead of a repeated bar: the shared songs and the harness's synthetic songs (seeds 2026, 2027, 7, 8), 44 s
    # each at 1.3 s, two noise draws each
    tau = np.arange(int(44.0 * SR)) / SR
    for song in songs[:2] + [scenes.synth_song(k, 45.0) for k in (2026, 2027, 7, 8)]:
        ref = song[:int(45.0 * SR)]
        clean = scenes.codec_copy(scenes.heard(ref, tau - 1.3))
        lead_rows.append(np.concatenate([leads(scenes.add_noise(clean, 10.0, seed), ref, 1.3) for seed in (3, 4)]))
    worst = max(float(x.max()) for x in lead_rows)
    print(f"right music through room noise, a seat holding the true offset: a peak elsewhere (a bar repeating the "
          f"rhythm) scored at most {worst:.3f} above the truth over {sum(x.size for x in lead_rows)} windows of "
          f"{len(lead_rows)} songs (a jump vote needs a lead of {JUMP_LEAD:.2f}); songs where one ever led: "
          f"{sum(bool((x > 0).any()) for x in lead_rows)}")
    relocks(secs)
    risers()
    envelope_margins(secs)
    return 0


def risers() -> None:
    """A loop under a noise riser heard through room noise (:func:`tests.support.sync_signals.riser_loop`, heard 2 s
    late): how far the onset score put a wrong loop ahead of the truth, how far the band levels as heard favoured it
    (its lead over the offset held, or over its rival while searching), and where the seat played."""
    worst_margin, worst_lead, wrong, windows = 0.0, -math.inf, 0, 0
    cases = [(1.8, -6.0, 10.0), (1.8, -3.0, 20.0), (1.8, 0.0, 5.0), (2.6, -12.0, 10.0), (2.6, -3.0, 10.0),
             (2.6, -6.0, 5.0), (3.7, -3.0, 10.0)]
    for loop_s, riser_db, snr_db in cases:
        src = riser_loop(loop_s, riser_db)
        heard = scenes.add_noise(scenes.heard(src, np.arange(int(52 * SR)) / SR - 2.0), snr_db, 3)
        history, _ = seat_matching(heard, src)
        for _, est, state in history:
            wrong += state.offset_s is not None and abs(state.offset_s - 2.0) > 0.02
            if est is None or abs(est.offset_s - 2.0) <= 0.04 or est.score < MIN_SCORE:
                continue
            windows += 1
            worst_margin = max(worst_margin, est.margin)
            leads = [est.rival_lead] + [ld for (o, _), ld in zip(est.peaks[:1], est.held_leads[:1])]
            worst_lead = max([worst_lead] + [ld for ld in leads if ld is not None])
    print(f"a loop under a noise riser through room noise ({len(cases)} runs: loops of 1.8-3.7 s, the riser 12-0 dB "
          f"under the music, 5-20 dB SNR): {windows} windows whose best offset was a wrong loop, standing up to "
          f"{worst_margin:.2f} clear of the rest; the band levels as heard favoured it by {worst_lead:.3f} at most "
          f"(a vote needs {HEARD_LEAD:.2f}); windows played off the truth: {wrong} (target 0)")


def _recent_envelopes(heard: np.ndarray, ref_levels: np.ndarray, history: list, since: float = -math.inf,
                      until: float = math.inf) -> list:
    """For each window of ``history`` (the seat's matching of ``heard``) ending between ``since`` and ``until``
    whose candidates within the voting margin of the best are two or more: ``(at, [(offset, onset score, band-energy
    score)])`` of those candidates, the band-energy score over the window's last RECENT_S as the seat weighs them."""
    levels = dequantise(quantise(signal_levels(heard, SR)))
    k = int(round(RECENT_S * RATE))
    out = []
    for at, est, _ in history:
        if est is None or not since <= at <= until or est.score < MIN_SCORE:
            continue
        close = [(o, s) for o, s in est.peaks if s > est.score - UNIQUE_MARGIN]
        end = int(round(at * RATE)) + 1
        if len(close) < 2 or end - k < 0 or end > levels.shape[0]:
            continue
        env = envelope_scores(levels[end - k:end], (end - k) / RATE, ref_levels, 0.0, [o for o, _ in close])
        out.append((at, [(o, s, e) for (o, s), e in zip(close, env)]))
    return out


def envelope_margins(secs: float) -> None:
    """Does the band-energy score tell apart the candidates the onset score leaves ambiguous? After a jump (0.5, 1
    and 1.5 s, both ways, 20 s into the music, the shared songs, the harness's synthetic ones and six more, through
    the codec and with room noise at 10 dB SNR), over the windows from 1.5 s after the jump (the last RECENT_S all
    heard since it) to 4 s: the band-energy score at the truth minus the best one at any other ambiguous candidate
    (its *margin*), per scene its smallest and median; and over music that is not the venue's (two other songs and
    speech, as above), the best band-energy score any ambiguous candidate reached and how far it stood above the
    next one (every candidate there is wrong)."""
    songs = [("vibe_ace", sf.read(AUDIO / "vibe_ace.ogg", dtype="float64")[0]),
             ("lets_go_fishin", sf.read(AUDIO / "lets_go_fishin.ogg", dtype="float64")[0])]
    songs += [(f"synthetic-{k}", scenes.synth_song(k, 2 * secs + 10.0)) for k in (2026, 2027, 7, 8, *range(100, 106))]
    rng = np.random.default_rng(13)
    rows = []
    right = []
    for i, (name, song) in enumerate(songs):
        song = song if song.ndim == 1 else song.mean(axis=1)
        ref = song[:int((2 * secs + 10.0) * SR)]
        ref_levels = dequantise(quantise(signal_levels(ref, SR)))
        coded = scenes.codec_copy(ref)
        for kind in ("codec", "noisy"):
            for jump in (1.0, -1.0, 0.5, -1.5):
                delay = float(rng.uniform(1.6, 3.0))
                jump_t, h, history = _jumped(coded, ref, delay, jump, 4.5, kind, 40 + i)
                truth = delay + jump
                margins = []
                for _, cands in _recent_envelopes(h, ref_levels, history, jump_t + RECENT_S, jump_t + 4.0):
                    at_truth = [e for o, _, e in cands if abs(o - truth) <= 0.04]
                    others = [e for o, _, e in cands if abs(o - truth) > 0.04 and e is not None]
                    if at_truth and at_truth[0] is not None and others:
                        margins.append(at_truth[0] - max(others))
                        right.append((at_truth[0], max(others)))
                if margins:
                    rows.append((name, kind, jump, len(margins), min(margins), float(np.median(margins))))
    print("band-energy score of the ambiguous candidates after a jump (truth minus the best other; windows 1.5-4 s "
          "after the jump with two or more candidates within the voting margin):")
    for name, kind, jump, n, lo, med in rows:
        print(f"  {name} {kind} {jump:+.1f} s: {n} windows, margin smallest {lo:+.2f}, median {med:+.2f}")
    if right:
        r = np.array(right)
        m = r[:, 0] - r[:, 1]
        print(f"  all: {len(m)} windows, the truth ahead in {(m > 0).mean() * 100:.0f} %, by 0.10 or more in "
              f"{(m >= 0.10).mean() * 100:.0f} %; an alias ahead by 0.05 or more in {(m <= -0.05).sum()}, by 0.10 or "
              f"more in {(m <= -0.10).sum()}; truth's band-energy score median {np.median(r[:, 0]):.2f}, smallest "
              f"{r[:, 0].min():.2f}")
    # music that is not the venue's: every candidate is wrong
    real = [s if s.ndim == 1 else s.mean(axis=1) for _, s in songs[:2]]
    others = real + [scenes.synth_song(100 + k, secs) for k in range(6)]
    n = int(secs * SR)
    tops, leads_, picks = [], [], 0
    for i, song in enumerate(others):
        ref = song[:int((secs + 15.0) * SR)]
        ref_levels = dequantise(quantise(signal_levels(ref, SR)))
        heard = []
        for j in ((i + 1) % len(others), (i + 3) % len(others)):
            h = scenes.codec_copy(np.concatenate([np.zeros(SR), others[j][:n]])[:n])
            heard += [h, scenes.add_noise(h, 10.0, i)]
        heard.append(scenes.add_noise(np.concatenate([np.zeros(SR), scenes.speech_like(i, secs)])[:n], 10.0, i + 7))
        for h in heard:
            history, _ = seat_matching(h, ref, max_delay_s=MAX_DELAY_S)
            # every window, whatever its onset score (a wrong song's never reach the score a vote needs)
            levels = dequantise(quantise(signal_levels(h, SR)))
            k = int(round(RECENT_S * RATE))
            for at, est, _ in history:
                end = int(round(at * RATE)) + 1
                if est is None or len(est.peaks) < 2 or end - k < 0 or end > levels.shape[0]:
                    continue
                env = sorted((e for e in envelope_scores(levels[end - k:end], (end - k) / RATE, ref_levels, 0.0,
                                                         [o for o, _ in est.peaks]) if e is not None), reverse=True)
                if len(env) >= 2:
                    tops.append(env[0])
                    leads_.append(env[0] - env[1])
                    # what the pick needs besides: the onset score reaching MIN_SCORE with two candidates close
                    close = sum(s > est.score - UNIQUE_MARGIN for _, s in est.peaks)
                    picks += (est.score >= MIN_SCORE and close >= 2 and env[0] >= ENVELOPE_MIN
                              and env[0] - env[1] >= ENVELOPE_LEAD)
    t, ld = np.array(tops), np.array(leads_)
    print(f"music that is not the venue's ({len(t)} windows, every candidate wrong): the best candidate's band-energy "
          f"score at most {t.max():.2f} (99th percentile {np.percentile(t, 99):.2f}); its lead over the next one at "
          f"most {ld.max():.2f} (99th percentile {np.percentile(ld, 99):.2f}); a lead of 0.10 or more with a score of "
          f"0.5 or more in {int(((ld >= 0.10) & (t >= 0.5)).sum())} windows; windows the pick would act on (also an onset "
          f"score of {MIN_SCORE:.2f} and two candidates within {UNIQUE_MARGIN:.2f}; {ENVELOPE_MIN:.2f} and a lead of "
          f"{ENVELOPE_LEAD:.2f}): {picks} (target 0)")


def relocks(secs: float) -> None:
    """A 1 s jump 20 s into the music (both ways) through the codec and with room noise at 10 dB SNR, on the shared
    songs and the harness's synthetic ones: how long the re-lock took, whether it went anywhere wrong, and, in the
    slowest, the candidates that competed (each one's distance from the offset held, and its score under the best)."""
    songs = [("vibe_ace", sf.read(AUDIO / "vibe_ace.ogg", dtype="float64")[0]),
             ("lets_go_fishin", sf.read(AUDIO / "lets_go_fishin.ogg", dtype="float64")[0])]
    songs += [(f"synthetic-{k}", scenes.synth_song(k, 2 * secs + 10.0)) for k in (2026, 2027, 7, 8)]
    rng = np.random.default_rng(11)
    rows, wrong, moved_leads = [], 0, []
    for i, (name, song) in enumerate(songs):
        song = song if song.ndim == 1 else song.mean(axis=1)
        ref = song[:int((2 * secs + 10.0) * SR)]
        coded = scenes.codec_copy(ref)
        for kind in ("codec", "noisy"):
            for jump in (1.0, -1.0):
                delay = float(rng.uniform(1.3, 3.0))
                jump_t, h, history = _jumped(coded, ref, delay, jump, 8.0, kind, 20 + i)
                truth = delay + jump
                t = [at - jump_t for at, _, st in history if at >= jump_t and st.state == "locked"
                     and abs(st.offset_s - truth) <= 0.04]
                wrong += sum(st.state != "searching" and min(abs(st.offset_s - delay), abs(st.offset_s - truth)) > 0.04
                             for _, _, st in history)
                # how far the band levels as heard favoured the new offset over the held one when the seat moved
                moved = next((e for at, e, st in history if at >= jump_t and st.state == "locked"
                              and abs(st.offset_s - truth) <= 0.04), None)
                if moved is not None:
                    moved_leads += [ld for (o, _), ld in zip(moved.peaks, moved.held_leads)
                                    if abs(o - truth) <= 0.04 and ld is not None][:1]
                # the candidates within the voting margin of the best, 2 s after the jump (the held offset's distance)
                est = next((e for at, e, _ in history if at >= jump_t + 2.0 and e is not None), None)
                near = "" if est is None else " ".join(
                    f"{o - delay:+.2f} s ({s - est.score:+.2f})" for o, s in est.peaks if s > est.score - UNIQUE_MARGIN)
                rows.append((t[0] if t else math.inf, name, kind, delay, jump, near))
    times = np.array([r[0] for r in rows])
    print(f"a 1 s jump 20 s into the music ({len(rows)} runs: {len(songs)} songs, through the codec and with room "
          f"noise, both ways): re-locked in median {np.median(times):.1f} s, worst {times.max():.1f} s (target 3 s); "
          f"windows played at neither the old nor the new offset: {wrong} (target 0); the slowest, with the candidates 2 s after "
          f"the jump (offset from the one held, score under the best):")
    for t, name, kind, delay, jump, near in sorted(rows, key=lambda r: -r[0])[:4]:
        print(f"  {name} {kind} {delay * 1000:.0f} ms {jump:+.0f} s: {t:.1f} s; {near}")
    print(f"  the band levels as heard favoured the new offset over the one held, in the window the seat moved: by "
          f"{min(moved_leads, default=math.nan):.3f} at least, median "
          f"{np.median(moved_leads) if moved_leads else math.nan:.3f} ({len(moved_leads)} of the runs; a move needs "
          f"{HELD_LEAD:.2f})")


if __name__ == "__main__":
    raise SystemExit(main())

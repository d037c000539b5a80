"""Does a show feel the same on every rig? The body-chart render played on six and more rigs, against the X40 render.

What a user runs: ``hapmotion render CLIP --rig RIG`` with the default options (the ``felt`` preset, mirrored): the
show is rendered once on the body chart (the X40 + shoulder Tactosy of the paper) and projected onto the rig's
motors (:mod:`hapmotion.rig`). The clips are the recordings of the motion folder with one-hand gestures in them,
judged per gesture, and, in a second table, the seeded synthetic one-hand gestures of ``benchmarks.feel`` (whole
clips, the hand known by construction).

A one-hand gesture (the reading used here) is a run of at least 0.5 s in which one hand leads, by its movement or
by its speed, each taken over a centred 0.5 s window: a hand's movement is the RMS displacement of its position
relative to the neck about its own mean (m; relative to the neck so that jumping, travelling and turning the whole
body move neither hand), its speed the mean of its speed relative to the hips; a hand leads while its movement is
at least 1.5 times the other's and at least 5 mm (a still hand's capture jitter and sway stay under it), or its
speed at least 1.5 times the other's and at least 0.5 m/s. The movement catches a wave of the hand alone (the
``byebye`` recording's right hand, 1-2 cm swings at 0.1-0.2 m/s), which a speed threshold misses; the speed catches
a fast hand whose path is short. Every gesture is judged on its own: a clip with many gestures counts each. ``--old-reading`` gives the earlier reading instead: per clip, the frames where one hand
moves faster than 0.5 m/s relative to the hips and at least twice as fast as the other
(``hapmotion.metrics.locus.active_hand``), in clips with at least 0.5 s of them.

Targets, per rig (each printed beside its figure, ``!`` when missed):

- side: the mirrored half of the rig (its motors on the wearer's side opposite the performer's hand) gets more
  energy (sum of squared intensity) than the other half over the gesture: >= 95 % of one-hand gestures;
- raised hands: in every run of at least 0.5 s where a hand is 5 cm or more above its shoulder, the upper half of
  the rig (vest motors above mid-height, shoulder sleeves) gets more energy than the lower half: >= 90 % of runs
  (runs where the rig is silent do not count);
- locus: the felt locus (energy-weighted centroid of the motors' places on the body, a forearm motor at the place
  of the shoulder it stands for) is within one motor pitch of the X40 render's, per gesture frame with any drive
  (mean distance <= the X40's pitch: the mean distance between neighbouring motors of its front panel, on the
  default adult);
- energy: each body side's energy over all gestures within +-1 dB of the X40 render's;
- gloves (``pro+gloves``): a clap, a wave and a point felt where they should be, with their own targets
  (:mod:`benchmarks.gloves`).

Run::

    PYTHONPATH=src python3 -m benchmarks.rigs
    PYTHONPATH=src python3 -m benchmarks.rigs --rig air --rig pro+gloves -v
    PYTHONPATH=src python3 -m benchmarks.rigs --preset paper          # the paper's (amplitude) split
    PYTHONPATH=src python3 -m benchmarks.rigs --old-reading --no-gloves   # the earlier per-clip reading
"""

from __future__ import annotations

import argparse
import os
import tempfile

import numpy as np

import hapmotion
from benchmarks import gloves
from benchmarks.feel import SHARED, hand_speeds, real_clips, runs, smooth, synthetic_clips
from hapmotion.body.model import BodyModel
from hapmotion.layout import CHART_BACK, CHART_FRONT, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from hapmotion.metrics.locus import active_hand
from hapmotion.rig import parse_rig
from hapmotion.show import Show, render_show

RIGS = ("x40+tactosy-shoulders", "x40+tactosy", "x16", "air", "pro", "pro+gloves", "pro+tactosy", "x40")
"""The rigs measured by default: the paper's rig, its sleeves on the forearms, the X16, the Air, the Pro alone, with
gloves and with forearm sleeves, and the X40 alone."""

ONE_HAND_S = 0.5  # seconds: a gesture run lasts at least this long
MOVE_WINDOW_S = 0.5  # seconds: the window of a hand's movement (RMS displacement about its mean)
LEAD_RATIO = 1.5  # a hand leads while its movement is at least this many times the other's ...
LEAD_FLOOR_M = 0.005  # ... and at least this (m); or its mean speed LEAD_RATIO times the other's and ...
LEAD_SPEED = 0.5  # ... at least this (m/s, relative to the hips: benchmarks.feel's "a hand moves")
RAISED_M = 0.05   # a hand this far above its shoulder is raised
RAISED_S = 0.5    # for at least this long
TARGETS = {"side": 0.95, "raised": 0.90, "energy_db": 1.0}

_CHART_CODE = {"front": CHART_FRONT, "back": CHART_BACK, "shoulder_left": CHART_SHOULDER_LEFT,
               "shoulder_right": CHART_SHOULDER_RIGHT, "forearm_left": CHART_SHOULDER_LEFT,
               "forearm_right": CHART_SHOULDER_RIGHT}


def place_positions(places, layout, body) -> np.ndarray:
    """``(K, 3)`` body positions (m) of chart places ``(chart, across, height)``: bilinear on the grid of the body
    chart's device for that chart (a forearm place at its shoulder's); NaN for places with no torso chart (hands,
    head)."""
    grid_pos = layout.positions(body)
    out = np.full((len(places), 3), np.nan)
    for k, (chart, u, v) in enumerate(places):
        if chart not in _CHART_CODE:
            continue
        d = layout.chart_device(_CHART_CODE[chart])
        g = grid_pos[d.offset:d.offset + d.size].reshape(d.rows, d.cols, 3)
        cu, cv = u * (d.cols - 1), v * (d.rows - 1)
        i0, j0 = min(int(cu), d.cols - 2), min(int(cv), d.rows - 2)
        fu, fv = cu - i0, cv - j0
        out[k] = ((1 - fu) * (1 - fv) * g[j0, i0] + fu * (1 - fv) * g[j0, i0 + 1] + (1 - fu) * fv * g[j0 + 1, i0]
                  + fu * fv * g[j0 + 1, i0 + 1])
    return out


def motor_pitch(layout, body) -> float:
    """Mean distance (m) between neighbouring motors of the X40's front panel (rows and columns)."""
    d = layout.chart_device(CHART_FRONT)
    g = layout.positions(body)[d.offset:d.offset + d.size].reshape(d.rows, d.cols, 3)
    steps = np.concatenate([np.linalg.norm(np.diff(g, axis=0), axis=2).ravel(),
                            np.linalg.norm(np.diff(g, axis=1), axis=2).ravel()])
    return float(steps.mean())


class RigView:
    """One rig's motors: sides, halves and body positions, and its projection of body-chart rows."""

    def __init__(self, name: str, layout, body, show: Show):
        self.name = name
        self.rig = parse_rig(name, energy=show.params().phantom == "energy")  # as --rig does for the show's preset
        self.project = self.rig.projection(layout)
        motors = self.rig.motors
        self.left = np.array([m.side == "left" for m in motors])
        self.right = np.array([m.side == "right" for m in motors])
        self.upper = np.array([(m.limb == "torso" and m.height < 0.5 - 1e-6) or m.limb == "shoulder" for m in motors])
        self.lower = np.array([m.limb == "torso" and m.height > 0.5 + 1e-6 for m in motors])
        self.pos = place_positions([(m.chart, m.across, m.height) for m in motors], layout, body)


def centroids(rows: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """``(T, 3)`` energy-weighted centroid per row (NaN where nothing placed drives)."""
    ok = np.isfinite(pos).all(axis=1)
    w = rows[:, ok] ** 2
    tot = w.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(tot[:, None] > 0, (w @ pos[ok]) / tot[:, None], np.nan)


def raised_runs(motion) -> list[tuple[int, int]]:
    """Runs of at least :data:`RAISED_S` where a hand is :data:`RAISED_M` above its shoulder."""
    up = np.zeros(motion.n_frames, dtype=bool)
    for hand, shoulder in (("HAND_LEFT", "SHOULDER_LEFT"), ("HAND_RIGHT", "SHOULDER_RIGHT")):
        up |= (motion.joint(hand)[:, 1] - motion.joint(shoulder)[:, 1]) > RAISED_M
    return runs(up, max(1, int(round(RAISED_S * motion.fps))))


def movement(motion) -> np.ndarray:
    """``(T, 2)`` each hand's movement (m): the RMS displacement of its position relative to the neck about its mean
    over a centred :data:`MOVE_WINDOW_S` window (left hand first)."""
    n = max(2, int(round(MOVE_WINDOW_S * motion.fps)))
    neck = motion.joint("NECK")
    out = np.zeros((motion.n_frames, 2))
    for k, name in enumerate(("HAND_LEFT", "HAND_RIGHT")):
        r = motion.joint(name) - neck
        var = sum(smooth(r[:, i] ** 2, n) - smooth(r[:, i], n) ** 2 for i in range(3))
        out[:, k] = np.sqrt(np.maximum(var, 0.0))
    return out


def leading_hand(motion) -> np.ndarray:
    """``(T,)`` the hand that leads per frame (0 left, 1 right, -1 neither): its :func:`movement` at least
    :data:`LEAD_RATIO` times the other's and at least :data:`LEAD_FLOOR_M`, or its speed relative to the hips,
    averaged over the same centred window, at least :data:`LEAD_RATIO` times the other's and at least
    :data:`LEAD_SPEED`; where movement and speed name different hands, neither leads."""
    mv = movement(motion)
    n = max(2, int(round(MOVE_WINDOW_S * motion.fps)))
    sp = hand_speeds(motion)
    speed = np.stack([smooth(sp[:, 0], n), smooth(sp[:, 1], n)], axis=1)
    by = []
    for x, floor in ((mv, LEAD_FLOOR_M), (speed, LEAD_SPEED)):
        lead = np.full(motion.n_frames, -1)
        for h in (0, 1):
            lead[(x[:, h] >= LEAD_RATIO * x[:, 1 - h]) & (x[:, h] >= floor)] = h
        by.append(lead)
    return np.where(by[0] == -1, by[1], np.where((by[1] == -1) | (by[1] == by[0]), by[0], -1))


def gestures(clip, old_reading: bool = False) -> list[tuple[np.ndarray, np.ndarray]]:
    """The one-hand gestures of a clip, each ``(frames (K,), hand per frame (K,))`` (0 left, 1 right): the whole
    clip for a synthetic one-hand clip; for a recording each run of at least :data:`ONE_HAND_S` of one leading hand
    (:func:`leading_hand`), or with ``old_reading`` one gesture of all the clip's ``active_hand`` frames when they
    add up to :data:`ONE_HAND_S`."""
    m = clip.motion
    if clip.hand is not None:
        return [(np.arange(m.n_frames), np.full(m.n_frames, clip.hand))]
    if old_reading:
        hand = active_hand(hand_speeds(m))
        idx = np.flatnonzero(hand >= 0)
        return [(idx, hand[idx])] if len(idx) >= ONE_HAND_S * m.fps else []
    lead = leading_hand(m)
    n = max(1, int(round(ONE_HAND_S * m.fps)))
    return sorted(((np.arange(a, b), np.full(b - a, h)) for h in (0, 1) for a, b in runs(lead == h, n)),
                  key=lambda g: g[0][0])


def measure(clips, rig_names, verbose: bool, show: Show, old_reading: bool = False) -> dict:
    layout = hapmotion.load_layout()
    body = BodyModel.default()
    views = {name: RigView(name, layout, body, show) for name in rig_names}
    ref_pos = layout.positions(body)
    ref_left, ref_right = ref_pos[:, 0] < -1e-9, ref_pos[:, 0] > 1e-9
    res = {name: {"side": [], "raised": [], "locus": [], "e_left": 0.0, "e_right": 0.0, "shares": []}
           for name in rig_names}
    ref_e = {"left": 0.0, "right": 0.0}
    for clip in clips:
        m = clip.motion
        chart = render_show(show, m).intensities  # the body chart, as every rig gets it
        found = gestures(clip, old_reading)
        frames = np.unique(np.concatenate([f for f, _ in found])) if found else np.zeros(0, dtype=int)
        ref_c = centroids(chart[frames], ref_pos)
        raised = raised_runs(m)
        e = (chart[frames] ** 2).sum(axis=0)
        ref_e["left"] += e[ref_left].sum()
        ref_e["right"] += e[ref_right].sum()
        line = f"  {clip.name[:40]:40s}"
        for name, v in views.items():
            rows = v.project(chart)
            r = res[name]
            e2 = rows ** 2
            shares = []
            for idx, hand in found:
                g = e2[idx]
                # mirrored: the performer's left hand (0) is felt on the wearer's right
                correct = g[hand == 0][:, v.right].sum() + g[hand == 1][:, v.left].sum()
                wrong = g[hand == 0][:, v.left].sum() + g[hand == 1][:, v.right].sum()
                if correct + wrong > 0:
                    r["side"].append(correct > wrong)
                    shares.append(correct / (correct + wrong))
            r["shares"].extend(shares)
            if shares:
                line += f" {name}:{np.mean(np.array(shares) > 0.5):.0%} of {len(shares)}"
            r["e_left"] += e2[frames][:, v.left].sum()
            r["e_right"] += e2[frames][:, v.right].sum()
            d = np.linalg.norm(centroids(rows[frames], v.pos) - ref_c, axis=1)
            r["locus"].extend(d[np.isfinite(d)].tolist())
            for a, b in raised:
                ea = e2[a:b].sum(axis=0)
                if ea.sum() > 0:
                    r["raised"].append(ea[v.upper].sum() > ea[v.lower].sum())
        if verbose:
            if found and not old_reading and clip.hand is None:
                line += "  gestures: " + " ".join(f"{'LR'[h[0]]}{f[0] / m.fps:.1f}-{(f[-1] + 1) / m.fps:.1f}s"
                                                  for f, h in found)
            print(line)
    for name in rig_names:
        r = res[name]
        r["ref_left"], r["ref_right"] = ref_e["left"], ref_e["right"]
    return res


def report(title: str, res: dict, pitch: float, n_clips: int) -> bool:
    n_gestures = len(next(iter(res.values()))["side"]) if res else 0
    print(f"\n{title}: {n_gestures} one-hand gestures in {n_clips} clips; X40 motor pitch {pitch * 100:.1f} cm")
    head = (f"  {'rig':24s} {'side (>= 95 %)':>16s} {'raised up (>= 90 %)':>20s} "
            f"{'locus cm (<= {:.1f})'.format(pitch * 100):>20s} {'left dB (+-1)':>14s} {'right dB (+-1)':>15s}")
    print(head)
    ok_all = True
    for name, r in res.items():
        side = float(np.mean(r["side"])) if r["side"] else float("nan")
        raised = float(np.mean(r["raised"])) if r["raised"] else float("nan")
        locus = float(np.mean(r["locus"])) if r["locus"] else float("nan")
        dbl = 10 * np.log10(r["e_left"] / r["ref_left"]) if r["e_left"] > 0 else -np.inf
        dbr = 10 * np.log10(r["e_right"] / r["ref_right"]) if r["e_right"] > 0 else -np.inf
        marks = [side >= TARGETS["side"], raised >= TARGETS["raised"], locus <= pitch,
                 abs(dbl) <= TARGETS["energy_db"], abs(dbr) <= TARGETS["energy_db"]]
        ok_all &= all(marks)
        f = ["" if k else "!" for k in marks]
        print(f"  {name:24s} {side:15.1%}{f[0]:1s} {raised:19.1%}{f[1]:1s} {locus * 100:19.2f}{f[2]:1s} "
              f"{dbl:+13.2f}{f[3]:1s} {dbr:+14.2f}{f[4]:1s}   (raised runs: {len(r['raised'])})")
    return ok_all


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", action="append", help=f"rig(s) to measure (default: {', '.join(RIGS)})")
    ap.add_argument("--motion-dir", default=os.path.join(SHARED, "motion"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--preset", default=None, help="renderer preset (default: the default, felt)")
    ap.add_argument("--no-synthetic", action="store_true", help="the recordings only")
    ap.add_argument("--no-gloves", action="store_true", help="leave out the glove figures (benchmarks.gloves)")
    ap.add_argument("--old-reading", action="store_true",
                    help="the earlier reading of a one-hand gesture: per clip, frames one hand > 0.5 m/s and 2x the other")
    ap.add_argument("-v", "--verbose", action="store_true", help="per-clip sides")
    args = ap.parse_args(argv)
    rig_names = args.rig or list(RIGS)
    layout, body = hapmotion.load_layout(), BodyModel.default()
    pitch = motor_pitch(layout, body)
    show = Show(preset=args.preset) if args.preset else Show()
    print(f"preset {show.preset} ({show.params().phantom} split), mirrored: rendered once on the body chart and "
          "projected on each rig")
    real = [c for c in real_clips(args.motion_dir) if gestures(c, args.old_reading)]
    reading = ("old reading: per clip, frames one hand > 0.5 m/s and 2x the other" if args.old_reading else
               f"gesture runs >= {ONE_HAND_S} s of one hand moving {LEAD_RATIO}x the other and >= "
               f"{LEAD_FLOOR_M * 1000:.0f} mm, or {LEAD_RATIO}x as fast and >= {LEAD_SPEED} m/s")
    print(f"recordings with one-hand gestures ({reading}): {', '.join(c.name for c in real)}")
    ok = report("recordings", measure(real, rig_names, args.verbose, show, args.old_reading), pitch, len(real))
    if not args.no_synthetic:
        with tempfile.TemporaryDirectory() as tmp:
            synth = [c for c in synthetic_clips(tmp, args.seed) if c.hand is not None]
            report("synthetic (benchmarks.feel, seeded)", measure(synth, rig_names, args.verbose, show), pitch, len(synth))
    if not args.no_gloves:  # the hands on the gloves (benchmarks.gloves): clap, wave and point
        ok &= gloves.run(args.seed, args.motion_dir)
    print("('!' = target missed)")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())

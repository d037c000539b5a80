"""Does a show feel the same on every rig? The body-chart render played on six and more rigs, against the X40 render.

What a user runs: ``hapmotion render CLIP --rig RIG`` with the default options (the ``felt`` preset, mirrored): the
show is rendered once on the body chart (the X40 + shoulder Tactosy of the paper) and projected onto the rig's
motors (:mod:`hapmotion.rig`). The clips are the recordings of the motion folder with one-hand gestures in them (at
least 0.5 s of frames where one hand moves faster than 0.5 m/s and at least twice as fast as the other: the
``lateral`` metric's frames, ``hapmotion.metrics.locus.active_hand``), measured over those frames, and, in a second
table, the seeded synthetic one-hand gestures of ``benchmarks.feel`` (whole clips).

Targets, per rig (each printed beside its figure, ``!`` when missed):

- side: the mirrored half of the rig (its motors on the wearer's side opposite the performer's hand) gets more
  energy (sum of squared intensity) than the other half: >= 95 % of one-hand gestures;
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
"""

from __future__ import annotations

import argparse
import os
import tempfile

import numpy as np

import hapmotion
from benchmarks import gloves
from benchmarks.feel import SHARED, hand_speeds, real_clips, runs, synthetic_clips
from hapmotion.body.model import BodyModel
from hapmotion.layout import CHART_BACK, CHART_FRONT, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from hapmotion.metrics.locus import active_hand
from hapmotion.rig import parse_rig
from hapmotion.show import Show, render_show

RIGS = ("x40+tactosy-shoulders", "x40+tactosy", "x16", "air", "pro", "pro+gloves", "pro+tactosy", "x40")
"""The rigs measured by default: the paper's rig, its sleeves on the forearms, the X16, the Air, the Pro alone, with
gloves and with forearm sleeves, and the X40 alone."""

ONE_HAND_S = 0.5  # seconds of one-hand frames a recording needs (the lateral metric's hapmotion.metrics ONE_HAND_S)
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


def one_hand_frames(clip) -> np.ndarray:
    """``(T,)`` the hand alone making a gesture per frame (0 left, 1 right, -1 none): the whole clip for a
    synthetic one-hand clip, the ``active_hand`` frames of a recording."""
    if clip.hand is not None:
        return np.full(clip.motion.n_frames, clip.hand)
    return active_hand(hand_speeds(clip.motion))


def measure(clips, rig_names, verbose: bool, show: Show) -> dict:
    layout = hapmotion.load_layout()
    body = BodyModel.default()
    views = {name: RigView(name, layout, body, show) for name in rig_names}
    ref_pos = layout.positions(body)
    ref_left, ref_right = ref_pos[:, 0] < -1e-9, ref_pos[:, 0] > 1e-9
    res = {name: {"side": [], "raised": [], "locus": [], "e_left": 0.0, "e_right": 0.0} for name in rig_names}
    ref_e = {"left": 0.0, "right": 0.0}
    for clip in clips:
        m = clip.motion
        chart = render_show(show, m).intensities  # the body chart, as every rig gets it
        hand = one_hand_frames(clip)
        gesture = hand >= 0
        ref_c = centroids(chart, ref_pos)
        raised = raised_runs(m)
        e = (chart[gesture] ** 2).sum(axis=0)
        ref_e["left"] += e[ref_left].sum()
        ref_e["right"] += e[ref_right].sum()
        line = f"  {clip.name[:40]:40s}"
        for name, v in views.items():
            rows = v.project(chart)
            r = res[name]
            e2 = rows ** 2
            # mirrored: the performer's left hand (0) is felt on the wearer's right
            correct = e2[hand == 0][:, v.right].sum() + e2[hand == 1][:, v.left].sum()
            wrong = e2[hand == 0][:, v.left].sum() + e2[hand == 1][:, v.right].sum()
            if correct + wrong > 0:
                r["side"].append(correct > wrong)
                line += f" {name}:{correct / (correct + wrong):.0%}"
            r["e_left"] += e2[gesture][:, v.left].sum()
            r["e_right"] += e2[gesture][:, v.right].sum()
            d = np.linalg.norm(centroids(rows[gesture], v.pos) - ref_c[gesture], axis=1)
            r["locus"].extend(d[np.isfinite(d)].tolist())
            for a, b in raised:
                ea = e2[a:b].sum(axis=0)
                if ea.sum() > 0:
                    r["raised"].append(ea[v.upper].sum() > ea[v.lower].sum())
        if verbose:
            print(line)
    for name in rig_names:
        r = res[name]
        r["ref_left"], r["ref_right"] = ref_e["left"], ref_e["right"]
    return res


def report(title: str, res: dict, pitch: float, n_gestures: int) -> bool:
    print(f"\n{title}: {n_gestures} clips with one-hand gestures; X40 motor pitch {pitch * 100:.1f} cm")
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
    ap.add_argument("-v", "--verbose", action="store_true", help="per-clip sides")
    args = ap.parse_args(argv)
    rig_names = args.rig or list(RIGS)
    layout, body = hapmotion.load_layout(), BodyModel.default()
    pitch = motor_pitch(layout, body)
    show = Show(preset=args.preset) if args.preset else Show()
    print(f"preset {show.preset} ({show.params().phantom} split), mirrored: rendered once on the body chart and "
          "projected on each rig")
    real = [c for c in real_clips(args.motion_dir)
            if np.count_nonzero(one_hand_frames(c) >= 0) >= ONE_HAND_S * c.motion.fps]
    print(f"recordings with one-hand gestures: {', '.join(c.name for c in real)}")
    ok = report("recordings", measure(real, rig_names, args.verbose, show), pitch, len(real))
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

"""``hapmotion plot``: a printable PNG from a motion file or a saved track; readable, non-trivial, atomic."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from hapmotion.track_files import save_track
import hapmotion
from hapmotion.cli import main
from hapmotion.layout import load_layout
from hapmotion.track import HapticTrack
from hapmotion.viewer.colors import plot_cmap, scale_top
from hapmotion.viewer.bodymap import body_layout
from hapmotion.viewer.plot import actuator_groups, plot_track, pool_max, row_ticks, track_figure
from support.data import SHARED_DATA

PUNCH = SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh"    # Bandai Namco (CC BY-NC), test use only
SONG = SHARED_DATA / "audio" / "vibe_ace.ogg"


def run(args, capsys):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def image_facts(path: Path) -> dict:
    img = mpimg.imread(path)[..., :3]
    flat = (np.round(img * 255).astype(np.uint8)).reshape(-1, 3)
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    return dict(shape=img.shape, n_colours=int((counts > 50).sum()), variance=float(img.var()),
                bytes=path.stat().st_size, img=img)


def render_png(track: HapticTrack, path: Path, dpi: int = 75):
    """Save ``track``'s figure as a PNG at ``dpi``; returns the image ``(H, W, 3)`` and the figure, whose transforms
    then map data to the image's pixels (x right, y up from the image's bottom row)."""
    fig = track_figure(track)
    fig.set_dpi(dpi)
    fig.savefig(path, dpi=dpi, facecolor="white")
    return mpimg.imread(path)[..., :3], fig


def pixel(img, ax, x, y) -> tuple[int, int]:
    """Image row and column of the data point (x, y) of axes ``ax``."""
    px, py = ax.transData.transform((x, y))
    return int(round(img.shape[0] - py)), int(round(px))


def test_pool_max_keeps_short_pulses():
    v = np.zeros((10_000, 2))
    v[5_001, 1] = 80.0                                   # one frame out of 10 000
    pooled, k = pool_max(v, max_columns=3000)
    assert k == 4 and pooled.shape == (2500, 2)
    assert pooled[:, 1].max() == 80.0 and pooled[1250, 1] == 80.0 and pooled[:, 0].max() == 0.0


def test_scale_top_by_hand():
    assert [scale_top(p) for p in (0.0, 4.9, 5.0, 5.1, 22.3, 30, 99, 100)] == [5, 5, 5, 10, 25, 50, 100, 100]


@pytest.mark.slow
def test_plot_from_motion_file(tmp_path, capsys):
    out = tmp_path / "punch.png"
    code, stdout, err = run(["plot", PUNCH, "-o", out], capsys)
    assert code == 0, err
    facts = image_facts(out)
    assert facts["shape"][0] >= 1000 and facts["shape"][1] >= 1500          # A4 landscape at 150 dpi
    assert facts["bytes"] > 50_000
    assert facts["n_colours"] >= 20 and facts["variance"] > 0.005


def test_heat_map_rows_follow_the_track(tmp_path):
    # A hand-made track: only VestBack_0 runs (full), first half of the time; every other actuator is off.
    lay = load_layout()
    n = 600
    inten = np.zeros((n, lay.n_actuators))
    col = lay.actuators.index("VestBack_0")
    inten[: n // 2, col] = 100.0
    track = HapticTrack(inten, 60.0, lay.actuators, layout=lay.name, meta={"method": "test"})
    img, fig = render_png(track, tmp_path / "one.png")  # the geometry is relative: a small figure is enough
    top = np.array(plot_cmap()(1.0)[:3])             # colour of a motor at the top of the scale
    ax = fig.axes[1]                                  # the heat map, under the body drawing
    (r0, c0), (r1, c1) = pixel(img, ax, 0.0, -0.5), pixel(img, ax, track.duration, lay.n_actuators - 0.5)
    hit = np.linalg.norm(img - top, axis=2) < 0.04
    rows, cols = np.nonzero(hit[r0:r1, c0:c1])
    assert rows.size > 0, "the running motor is not drawn"
    # One actuator of 52 high, the 21st row from the top of the map (VestBack_0 follows the 20 front motors); half
    # of the time axis long, starting at its left end.
    map_h, map_w = r1 - r0, c1 - c0
    height = rows.max() - rows.min() + 1
    assert height <= map_h / 52 + 2 and height == np.unique(rows).size
    assert abs(rows.mean() - 20.5 * map_h / 52) <= 1.5
    assert abs(cols.min()) <= 1 and abs(cols.max() + 1 - map_w / 2) <= 2


def test_odd_actuator_ids_are_grouped_by_one_parse_and_do_not_crash(tmp_path):
    # Saved tracks can carry any header; ids that are not <Device>_<index> are each their own group, never merged
    # into the device whose name they start with, and "$" in a name is text, not matplotlib math.
    ids = ("Vest", "Vest_a", "X_1", "Y_", "VestFront_3", "VestFront_4", "$\\bad$_0", "$\\bad$_1")
    track = HapticTrack(np.full((60, len(ids)), 30.0), 30.0, ids)
    groups = actuator_groups(track.actuators)
    assert groups == [("Vest", 0, 1), ("Vest_a", 1, 1), ("X", 2, 1), ("Y_", 3, 1), ("VestFront", 4, 2),
                      ("$\\bad$", 6, 2)]
    _, labels = row_ticks(track.actuators, groups)
    assert labels[4] == "3-4"                         # the ids' own indices, not their position in the group
    assert labels[:4] == ["", "", "1", ""]            # no index to show for ids without one
    out = plot_track(track, tmp_path / "odd.png", dpi=60)
    assert image_facts(out)["bytes"] > 5_000


def test_plot_saved_tracks_and_music(tmp_path, capsys):
    motion = hapmotion.load_motion(PUNCH)
    track = hapmotion.render(motion, preset="energy")
    for ext in ("csv", "npz"):
        saved = tmp_path / f"punch.{ext}"
        save_track(track, saved)
        out = tmp_path / f"from_{ext}.png"
        code, _, err = run(["plot", saved, "--dpi", "75", "-o", out], capsys)
        assert code == 0, err
        assert image_facts(out)["n_colours"] >= 20
    out = tmp_path / "music.pdf"
    code, _, err = run(["plot", PUNCH, "--audio", SONG, "--end", "5", "-o", out], capsys)
    assert code == 0, err
    assert out.read_bytes()[:5] == b"%PDF-"


@pytest.mark.parametrize("args, message", [
    (["plot", PUNCH, "-o", "{tmp}/x.jpg"], ".png"),
    (["plot", "{tmp}/none.bvh", "-o", "{tmp}/x.png"], "none.bvh"),
    (["plot", PUNCH, "--start", "9", "--end", "3", "-o", "{tmp}/x.png"], "start < end"),
    (["plot", PUNCH, "--vmax", "loud", "-o", "{tmp}/x.png"], "--vmax"),
    (["plot", PUNCH, "--preset", "nope", "-o", "{tmp}/x.png"], "nope"),
])
def test_plot_errors_are_one_line_and_leave_nothing(tmp_path, capsys, args, message):
    args = [str(a).replace("{tmp}", str(tmp_path)) for a in args]
    code, _, err = run(args, capsys)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_body_drawing_tells_left_from_right(tmp_path):
    # Only the wearer's left runs (vest columns 0-1 front and back, the left sleeve); then its mirror image, the
    # wearer's right. Measured on the saved images: the lit cells are exactly those, on the right side of each panel,
    # and the two drawings are mirror images about each vest panel's middle; the sleeve changes sides of the chest.
    lay = load_layout()
    panels, cells = body_layout(lay.actuators, lay)
    left = [c.column for c in cells if (c.device.startswith("Vest") and c.index % 4 < 2) or c.device == "ForearmL"]
    inten = np.zeros((240, lay.n_actuators))
    inten[:, left] = 40.0 + np.arange(len(left))          # distinct means 40..57, one scale (top 100) for both
    right_of = lay.mirror_map()
    mirrored = np.zeros_like(inten)
    mirrored[:, right_of] = inten
    drawn = {}
    for name, values in (("left", inten), ("right", mirrored)):
        track = HapticTrack(values, 60.0, lay.actuators, layout=lay.name)
        img, fig = render_png(track, tmp_path / f"{name}.png")
        ax = next(a for a in fig.axes if a.get_label() == "body")
        lit, at = set(), {}
        for c in cells:
            r, col = pixel(img, ax, c.x + 0.25 * c.w, c.y + 0.3 * c.h)   # lower left of the cell: no text there
            if np.abs(img[r, col] - 1.0).max() > 0.1:                      # not white paper
                lit.add(c.actuator)
            at[c.actuator] = pixel(img, ax, *c.center)
        drawn[name] = (lit, at, {p.device: pixel(img, ax, p.center_x, p.y)[1] for p in panels})
    lit_l, at_l, mid_l = drawn["left"]
    lit_r, at_r, mid_r = drawn["right"]
    assert lit_l == {lay.actuators[k] for k in left}
    assert lit_r == {lay.actuators[right_of[k]] for k in left}
    for aid in lit_l:
        dev = aid.rsplit("_", 1)[0]
        if dev.startswith("Vest"):
            twin = lay.actuators[right_of[lay.actuators.index(aid)]]
            assert at_l[aid][1] < mid_l[dev] < at_r[twin][1]                 # left of the middle, its twin right
            assert abs((mid_l[dev] - at_l[aid][1]) - (at_r[twin][1] - mid_r[dev])) <= 1   # mirror images
            assert at_l[aid][0] == at_r[twin][0]                               # same height
    assert max(at_l[a][1] for a in lit_l if a.startswith("ForearmL")) < mid_l["VestFront"]
    assert min(at_r[a][1] for a in lit_r if a.startswith("ForearmR")) > mid_r["VestFront"]


def test_body_drawing_of_a_real_clip_shows_each_motors_mean():
    # The punch clip, mirrored as the wearer feels it: each cell's colour and number are its motor's mean.
    track = hapmotion.render(hapmotion.load_motion(PUNCH), preset="energy")
    fig = track_figure(track)
    ax = next(a for a in fig.axes if a.get_label() == "body")
    mean = track.intensities.mean(axis=0)
    top = scale_top(float(mean.max()))
    patches = {p.get_gid(): p for p in ax.patches}
    assert set(patches) == set(track.actuators)
    cmap = plot_cmap()
    for k, aid in enumerate(track.actuators):
        want = cmap((mean[k] - 0.5 * top / 100) / (top - 0.5 * top / 100)) if mean[k] > 0 else (1, 1, 1, 1)
        np.testing.assert_allclose(patches[aid].get_facecolor(), want, atol=1e-6)
    texts = {t.get_text() for t in ax.texts}
    busiest = int(np.argmax(mean))
    assert (f"{mean[busiest]:.1f}" if mean[busiest] < 9.95 else f"{mean[busiest]:.0f}") in texts
    assert {"LEFT SHOULDER", "RIGHT SHOULDER", "wearer's LEFT", "wearer's RIGHT"} <= texts
    assert "mirrored" in ax.get_title()


@pytest.mark.parametrize("rig", ["x16+gloves+tactvisor", "pro+tactosy+gloves+tactvisor", None])
def test_no_label_of_the_body_drawing_runs_into_another(tmp_path, rig):
    """Every panel's title, subtitle and edge labels stay clear of each other and of the grids, on a rig of many
    small panels as on the body chart: measured on the laid-out figure, in pixels."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    out = tmp_path / "t.csv"
    assert main(["render", str(PUNCH), *(["--rig", rig] if rig else []), "-o", str(out)]) == 0
    fig = track_figure(hapmotion.load_track(out))
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = next(a for a in fig.axes if a.get_label() == "body")
    grids = [p.get_window_extent(renderer) for p in ax.patches]
    labels = [t for t in ax.texts if t.get_text().strip() and not any(
        g.contains(*t.get_window_extent(renderer).get_points().mean(axis=0)) for g in grids)]
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in labels]
    assert len(boxes) >= 5 * 4
    for i, (a, box_a) in enumerate(boxes):
        for b, box_b in boxes[i + 1:]:
            assert not box_a.overlaps(box_b), (a, b)
        for g in grids:
            assert not box_a.overlaps(g), (a, "a grid cell")

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
from hapmotion.viewer.plot import actuator_groups, plot_track, pool_max, row_ticks
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
    out = tmp_path / "one.png"
    plot_track(track, out, dpi=75)                  # the geometry is relative: a small figure is enough
    img = image_facts(out)["img"]
    top = np.array(plot_cmap()(1.0)[:3])             # colour of a motor at the top of the scale
    h, w = img.shape[:2]
    hit = np.linalg.norm(img - top, axis=2) < 0.04
    hit[:, int(0.9 * w):] = False                     # leave out the colour bar
    rows, cols = np.nonzero(hit)
    assert rows.size > 0, "the running motor is not drawn"
    # One actuator of 52 high, the 21st row from the top (VestBack_0 follows the 20 front motors), inside the heat
    # map's area (upper part of the figure); half of the time axis long, starting at its left end.
    height = rows.max() - rows.min() + 1
    map_rows = np.nonzero(hit.any(axis=1))[0]
    assert 3 <= height <= 0.6 * h / 52 + 3
    assert 0.2 * h < rows.mean() < 0.45 * h
    length = cols.max() - cols.min() + 1
    assert 0.35 * w < length < 0.5 * w
    assert cols.min() < 0.2 * w
    assert map_rows.size == height


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

"""The viewer page and the plot draw the rig a track was rendered for, labelled in the wearer's terms."""

from __future__ import annotations

import numpy as np

from hapmotion.layout import load_layout
from hapmotion.rig import parse_rig, rig_track
from hapmotion.track import HapticTrack
from hapmotion.viewer.bodymap import body_layout, rig_panels
from hapmotion.viewer.page import page_data

LAYOUT = load_layout()


def _rig_track(name: str) -> HapticTrack:
    rows = np.zeros((3, LAYOUT.n_actuators))
    rows[:, 0] = 70.0  # VestFront_0: the wearer's upper left chest
    return rig_track(HapticTrack(rows, 30.0, LAYOUT.actuators, LAYOUT.name), LAYOUT.with_rig(parse_rig(name)))


def test_an_air_is_drawn_as_two_panels_of_its_own_grid():
    track = _rig_track("air")
    panels = rig_panels(track.layout, track.actuators)
    assert [(p["name"], p["rows"], p["cols"], p["place"]) for p in panels] == [("VestFront", 2, 4, "front"),
                                                                                ("VestBack", 2, 4, "back")]
    assert panels[0]["left"] == "wearer's LEFT" and "TactSuit Air" in panels[0]["subtitle"]
    assert page_data([track], None)[0]["devices"] == panels  # the page draws the same panels


def test_gloves_sleeves_and_the_visor_sit_on_their_sides():
    track = _rig_track("pro+tactosy+gloves+tactvisor")
    names = [p["name"] for p in rig_panels(track.layout, track.actuators)]
    # the wearer's left-side devices first, then the chest, the right side, the back and the head
    assert names[:2] == ["ForearmL", "GloveL"] and names[2] == "VestFront"
    assert names[3:5] == ["ForearmR", "GloveR"] and names[5:] == ["VestBack", "Head"]
    panels, cells = body_layout(track.actuators, rig=track.layout)
    assert len(cells) == len(track.actuators) == 32 + 12 + 12 + 4
    hot = [c for c in cells if track.intensities[0, c.column] > 0]
    front = next(p for p in panels if p.device == "VestFront")
    assert [c.actuator for c in hot] == ["VestFront_0"] and hot[0].x < front.center_x  # drawn on the wearer's left


def test_a_body_chart_track_is_not_taken_for_a_rig():
    rows = np.zeros((2, LAYOUT.n_actuators))
    assert rig_panels(LAYOUT.name, LAYOUT.actuators) == []
    assert rig_panels("x40+tactosy-shoulders", LAYOUT.actuators) == []
    assert rig_panels("air", LAYOUT.actuators) == []  # the name of a rig, but not its columns
    assert len(body_layout(HapticTrack(rows, 30.0, LAYOUT.actuators).actuators)[1]) == 52


GLOVE_WORDS = ["thumb", "index", "middle", "ring", "little", "wrist"]


def _hands_track() -> HapticTrack:
    """What ``live`` on ``pro+gloves`` broadcasts and records: the body chart and the hand places, 64 columns, in
    the body chart's layout; the left thumb and the right wrist on."""
    ids = LAYOUT.with_rig(parse_rig("pro+gloves")).played_actuators
    assert len(ids) == 64 and ids[52:] == tuple(f"Glove{s}_{k}" for s in "LR" for k in range(6))
    rows = np.zeros((2, 64))
    rows[:, ids.index("GloveL_0")], rows[:, ids.index("GloveR_5")] = 80.0, 40.0
    return HapticTrack(rows, 30.0, ids, LAYOUT.name)


def test_the_body_chart_with_hands_draws_two_gloves_under_the_front_row():
    data = page_data([_hands_track()], None)[0]
    names = [(d["name"], d["place"]) for d in data["devices"]]
    assert names == [("ForearmL", "front"), ("VestFront", "front"), ("ForearmR", "front"), ("GloveL", "hands"),
                     ("GloveR", "hands"), ("VestBack", "back")]
    gloves = {d["name"]: d for d in data["devices"] if d["name"].startswith("Glove")}
    assert gloves["GloveL"]["title"] == "LEFT HAND" and gloves["GloveR"]["title"] == "RIGHT HAND"
    for d in gloves.values():
        assert (d["rows"], d["cols"]) == (1, 6) and d["labels"] == GLOVE_WORDS
        assert (d["left"], d["right"], d["top"]) == ("thumb", "wrist", "fingertips")
    # the body chart's panels keep their words
    assert next(d for d in data["devices"] if d["name"] == "VestFront")["left"] == "wearer's LEFT"
    # a live page has the gloves ready for a stream that brings them; its own columns stay the body chart's
    live = page_data([], None, live_url="ws://127.0.0.1:8766")[0]
    assert [d["name"] for d in live["devices"]] == [n for n, _ in names] and len(live["actuators"]) == 52


def test_a_rig_with_gloves_names_each_glove_motor():
    track = _rig_track("pro+gloves")
    panels = {p["name"]: p for p in rig_panels(track.layout, track.actuators)}
    assert panels["GloveL"]["labels"] == panels["GloveR"]["labels"] == GLOVE_WORDS
    assert panels["GloveL"]["title"] == "LEFT HAND" and "TactGlove" in panels["GloveL"]["subtitle"]
    assert "labels" not in panels["VestFront"]
    assert panels["GloveL"]["place"] == panels["GloveR"]["place"] == "hands"
    # the glove wearable's motor 0 is the thumb and motor 5 the wrist: the words follow the wearable file
    glove = parse_rig("gloves").wearables[0]
    motors = glove.device_motors("GloveL")
    assert motors[0].across == 0.0 and motors[4].across == 1.0 and motors[5].height > motors[0].height


def test_the_plot_draws_the_hands_of_a_live_recording():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    from hapmotion.viewer.bodymap import draw_body

    track = _hands_track()
    fig, ax = plt.subplots()
    try:
        cells = draw_body(ax, track.intensities[0], track.actuators, plt.get_cmap("magma_r"), Normalize(0, 100))
        assert len(cells) == 64 and {c.actuator for c in cells} == set(track.actuators)
        boxes = {p.get_gid(): p for p in ax.patches}
        white = (1.0, 1.0, 1.0, 1.0)
        assert tuple(boxes["GloveL_0"].get_facecolor()) != white and tuple(boxes["GloveR_5"].get_facecolor()) != white
        assert tuple(boxes["GloveL_1"].get_facecolor()) == white
        assert boxes["GloveL_0"].get_x() < boxes["GloveR_0"].get_x()  # the wearer's left hand on the left
        texts = [t.get_text().replace("\n", " ") for t in ax.texts]  # a title may be wrapped to fit its panel
        assert "LEFT HAND" in texts and "RIGHT HAND" in texts and "FRONT (wearer's left | right)" in texts
    finally:
        plt.close(fig)

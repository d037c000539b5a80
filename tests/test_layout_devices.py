"""The bHaptics device catalogue is the one source of motor counts and points, and the renderer layout agrees."""

from __future__ import annotations

import numpy as np

from hapmotion.bhaptics.devices import bhaptics_devices, device_type, type_for_position
from hapmotion.layout import load_layout


def test_catalogue_covers_the_devices_patterns_use():
    cat = bhaptics_devices()
    counts = {name: t.n_motors for name, t in cat.items()}
    assert counts["Tactot"] == 20 and counts["Tactosy2"] == 6 and counts["Tactosy"] == 20
    assert counts["Tactal"] == 6 and counts["TactVisor"] == 4 and counts["TactosyH"] == 3 and counts["TactosyF"] == 3
    for t in cat.values():
        assert t.points.shape == (t.cols * t.rows, 2)
        assert (t.points >= 0).all() and (t.points <= 1).all()


def test_x40_points_follow_the_bhaptics_addressing():
    pts = bhaptics_devices()["Tactot"].points
    # index = row * 4 + col, x = col / 3, y = row / 4 (row 0 at the collar)
    for i in (0, 5, 10, 19):
        r, c = divmod(i, 4)
        np.testing.assert_allclose(pts[i], (c / 3, r / 4), atol=1e-3)


def test_names_and_aliases():
    assert device_type("Vest").name == "Tactot" and device_type("tactot").name == "Tactot"
    assert device_type("Tactosy2").positions == ("ForearmL", "ForearmR")
    assert device_type("nonsense") is None
    assert type_for_position("Head").name == "Tactal" and type_for_position("Head", 4).name == "TactVisor"


def test_renderer_layout_is_made_of_catalogue_devices():
    layout = load_layout()
    for dev in layout.devices:
        t = type_for_position(dev.name, dev.size)
        assert t is not None and (t.cols, t.rows) == (dev.cols, dev.rows)
    assert layout.n_actuators == 52

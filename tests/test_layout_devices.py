"""The bHaptics device catalogue is the one source of motor counts and points, and the renderer layout agrees."""

from __future__ import annotations

import json
from importlib import resources

import numpy as np
import pytest

from hapmotion.bhaptics.devices import bhaptics_devices, device_type, type_for_position
from hapmotion.errors import InputError
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


# ------------------------------------------------------------------------------------------ bad layout files
def _bundled_layout() -> dict:
    return json.loads(resources.files("hapmotion").joinpath("data/x40_shoulders.json").read_text())


def _layout_refused(tmp_path, content, *needles):
    path = tmp_path / "layout.json"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(InputError) as info:
        load_layout(path)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg and info.value.exit_code == 2, msg
    for needle in needles:
        assert needle in msg, msg
    return msg


def test_a_copy_of_the_bundled_layout_reads_like_the_default(tmp_path):
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(_bundled_layout()))
    assert load_layout(path).actuators == load_layout().actuators


def test_deep_nesting_is_refused_by_the_json_guard(tmp_path):
    _layout_refused(tmp_path, '{"devices": ' + "[" * 100_000 + "]" * 100_000 + "}",
                    "levels of JSON nesting (limit depth; raise it with --limit depth=N), found 100001")


def test_a_huge_number_is_refused_by_the_json_guard(tmp_path):
    _layout_refused(tmp_path, '{"devices": [{"rows": 1' + "0" * 5000 + "}]}", "digits in a number (limit number_digits")


def test_rows_1e999_is_a_field_error(tmp_path):
    doc = _bundled_layout()
    text = json.dumps(doc).replace('"rows": 5', '"rows": 1e999', 1)
    assert "1e999" in text
    _layout_refused(tmp_path, text, "field devices[0]", "cannot convert float infinity to integer")


def test_a_hundred_thousand_devices_are_refused_before_any_is_read(tmp_path):
    device = _bundled_layout()["devices"][0]
    _layout_refused(tmp_path, {"devices": [device] * 100_000}, "field devices", "expected at most 4 devices",
                    "found 100000")


def test_binary_data_and_a_folder_are_refused(tmp_path):
    _layout_refused(tmp_path, b"\xff\xfe\x00[", "expected UTF-8 JSON layout text")
    with pytest.raises(InputError, match="expected a file, found a directory"):
        load_layout(tmp_path)


def test_a_layout_name_that_is_not_text_is_refused(tmp_path):
    doc = dict(_bundled_layout(), name={"a": 1})
    _layout_refused(tmp_path, doc, "field name: expected the layout's name as text, found dict")

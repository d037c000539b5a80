"""BodyModel as written in tracks and show descriptions: to_dict / from_dict."""

from __future__ import annotations

import math

import numpy as np
import pytest

import hapmotion
from hapmotion.body import BodyModel
from support.synthetic import motion_from_frames, waving


def test_to_dict_names_the_three_dimensions_in_metres():
    body = BodyModel(shoulder_width=0.4, shoulder_height=0.3, pelvis_height=-0.1)
    assert body.to_dict() == {"shoulder_width": 0.4, "shoulder_height": 0.3, "pelvis_height": -0.1}
    assert all(type(v) is float for v in body.to_dict().values())


def test_from_dict_reads_back_what_to_dict_wrote_and_ignores_other_keys():
    body = BodyModel.from_motion(motion_from_frames(waving(n=30)))
    assert BodyModel.from_dict(body.to_dict()) == body
    assert BodyModel.from_dict({**BodyModel().to_dict(), "height": 1.8}) == BodyModel()
    assert BodyModel.from_dict({"shoulder_width": 1, "shoulder_height": np.float32(0.5),
                                "pelvis_height": 0}) == BodyModel(1.0, 0.5, 0.0)


def test_a_rendered_track_records_its_body():
    motion = motion_from_frames(waving(n=30))
    track = hapmotion.render(motion)
    assert track.meta["body"] == BodyModel.from_motion(motion).to_dict()


@pytest.mark.parametrize("change, message", [
    ({"shoulder_width": None}, "body.shoulder_width: missing"),
    ({"shoulder_width": "0.4"}, "body.shoulder_width: expected metres"),
    ({"shoulder_height": True}, "body.shoulder_height: expected metres"),
    ({"pelvis_height": math.nan}, "body.pelvis_height: expected metres"),
    ({"pelvis_height": -math.inf}, "body.pelvis_height: expected metres"),
    ({"shoulder_height": 6.0}, "body.shoulder_height: expected metres"),
    ({"shoulder_width": 0.0}, "body.shoulder_width: expected a positive width"),
    ({"shoulder_width": -0.3}, "body.shoulder_width: expected a positive width"),
    ({"shoulder_height": -0.2}, "body.shoulder_height: expected the shoulders above the pelvis"),
])
def test_from_dict_refuses_what_is_not_a_body_in_one_line(change, message):
    dims = {**BodyModel().to_dict(), **change}
    dims = {k: v for k, v in dims.items() if v is not None}
    with pytest.raises(ValueError) as caught:
        BodyModel.from_dict(dims)
    assert str(caught.value).startswith(message) and "\n" not in str(caught.value)


def test_from_dict_refuses_a_non_object():
    with pytest.raises(ValueError, match="^body: expected an object"):
        BodyModel.from_dict([0.38, 0.33, -0.12])  # type: ignore[arg-type]

"""Packing of per-frame arrays for the viewer page: exact round trips, quantisation, missing points."""

import base64
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from hapmotion.viewer import packing

DTYPES = ["uint8", "int8", "uint16", "int16"]


@settings(max_examples=60, deadline=None)
@given(data=st.data(), dtype=st.sampled_from(DTYPES), delta=st.booleans())
def test_pack_decode_round_trip_is_exact(data, dtype, delta):
    shape = data.draw(hnp.array_shapes(min_dims=1, max_dims=3, min_side=1, max_side=7))
    values = data.draw(hnp.arrays(np.dtype(dtype), shape))  # full integer range: delta coding must wrap exactly
    blob = packing.pack(values, dtype, delta=delta)
    back = packing.decode_blob(blob.meta, blob.text)
    assert back.dtype == np.dtype(dtype)
    np.testing.assert_array_equal(back, values)


def test_delta_coding_and_byte_shuffle_by_hand():
    # int16 values 1000, 1003, 998 -> deltas 1000, 3, -5 -> little-endian bytes (e8 03) (03 00) (fb ff),
    # shuffled into the low-byte plane e8 03 fb then the high-byte plane 03 00 ff.
    blob = packing.pack(np.array([1000, 1003, 998], dtype=np.int16), "int16", delta=True)
    raw = zlib.decompress(base64.b64decode(blob.text))
    assert raw == bytes([0xE8, 0x03, 0xFB, 0x03, 0x00, 0xFF])
    assert blob.meta == {"dtype": "int16", "shape": [3], "delta": True, "scale": 1.0}


def test_quantise_rounds_clips_and_fills_non_finite():
    q = packing.quantise(np.array([0.4, 0.6, -3.0, 300.0, np.nan, np.inf]), 1.0, "uint8", fill=7.0)
    np.testing.assert_array_equal(q, [0, 1, 0, 255, 7, 7])
    assert q.dtype == np.uint8


def test_intensities_become_whole_player_units():
    values = np.array([[0.0, 0.49, 0.51, 99.6, 100.0, 42.5]])
    blob = packing.pack_intensities(values)
    back = packing.decode_blob(blob.meta, blob.text)
    np.testing.assert_array_equal(back, [[0, 0, 1, 100, 100, 42]])  # rint: half to even
    assert np.abs(back - values).max() <= 0.5


def test_positions_in_millimetres_with_missing_points():
    pts = np.array([[0.0, 1.2345, -0.5], [np.nan, 1.0, 0.0], [40.0, -40.0, 0.0005]])
    blob = packing.pack_positions(pts)
    back = packing.decode_blob(blob.meta, blob.text)
    np.testing.assert_array_equal(back[0], [0, 1234, -500])  # 1234.5 mm rounds half to even
    assert (back[1] == packing.MISSING_INT16).all()
    np.testing.assert_array_equal(back[2], [32767, -32767, 0])  # clipped, never the sentinel
    assert blob.meta["scale"] == 0.001 and blob.meta["delta"] is True


def test_unit_curve_keeps_its_peak_and_shape():
    v = np.array([0.0, 1.0, 2.5, 10.0, np.nan, -1.0])
    blob = packing.pack_unit(v)
    back = packing.decode_blob(blob.meta, blob.text) * blob.meta["scale"]
    assert back[3] == pytest.approx(10.0)
    np.testing.assert_allclose(back[:4], v[:4], atol=10.0 / 65535)
    assert back[4] == 0 and back[5] == 0  # NaN and negatives become 0: the page never sees NaN


def test_smooth_motion_packs_small():
    # 10 s of a smooth 60 fps trajectory: delta coding + shuffle must beat plain zlib of the raw int16 clearly.
    t = np.arange(600) / 60
    pts = np.stack([np.sin(t), 1 + 0.3 * np.cos(2 * t), 0.2 * t], axis=1)
    q = packing.quantise(pts, 0.001, "int16")
    plain = len(base64.b64encode(zlib.compress(q.tobytes(), 6)))
    assert packing.pack_positions(pts).n_bytes < 0.6 * plain

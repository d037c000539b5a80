"""Bad track files end as one-line InputErrors (exit 2) that name the file, the place and the limit; nothing large is
allocated from a small file."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest

from hapmotion.track_files import save_track
from hapmotion.errors import InputError
from hapmotion.layout import load_layout
from hapmotion.track import HapticTrack
from hapmotion.track_files import load_track
from hapmotion.limits import DEFAULT_LIMITS

TRACK_HEAD = '{"format":"hapmotion-track","fps":60,'


def _refused(path, *needles):
    with pytest.raises(InputError) as info:
        load_track(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg and info.value.exit_code == 2
    for needle in needles:
        assert needle in msg, msg
    return msg


def test_csv_with_a_huge_time_span_is_refused_with_the_rate(tmp_path):
    path = tmp_path / "span.csv"
    path.write_text("time_s,VestFront_0\n0,1\n1e12,2\n")  # one frame per 10^12 s: rate rounds to 0
    _refused(path, "column time_s", "frame rate")


def test_header_only_csv_says_so_without_warnings(tmp_path, recwarn):
    path = tmp_path / "empty.csv"
    path.write_text("time_s,VestFront_0\n")
    _refused(path, "at least one row")
    assert not [w for w in recwarn if issubclass(w.category, UserWarning)]


@pytest.mark.parametrize("ext", [".json", ".tact"])
def test_deeply_nested_json_is_refused_before_parsing(tmp_path, ext):
    path = tmp_path / f"deep{ext}"
    path.write_text("[" * 200_000 + "]" * 200_000)
    _refused(path, f"expected at most {DEFAULT_LIMITS.depth} levels of JSON nesting (limit depth; raise it with "
                   "--limit depth=N), found 200000")


@pytest.mark.parametrize("ext, text", [
    (".json", TRACK_HEAD.replace('"fps":60', '"fps":1' + "0" * 5000) + '"actuators":["VestFront_0"],"frames":[[1]]}'),
    (".tact", '{"project":{"mediaFileDuration":1' + "0" * 5000 + ',"layout":{"type":"Tactot"},"tracks":[]}}'),
], ids=["json", "tact"])
def test_huge_integers_are_refused(tmp_path, ext, text):
    path = tmp_path / f"bigint{ext}"
    path.write_text(text)
    _refused(path, "line 1: expected at most 100 digits in a number (limit number_digits; raise it with --limit "
                   "number_digits=N), found 5001")


@pytest.mark.parametrize("body, place", [
    ('"actuators":[null],"frames":[[1]]}', "field actuators"),
    ('"actuators":null,"frames":[[1]]}', "field actuators:"),
    ('"actuators":["VestFront_0"],"meta":"made by hand","frames":[[1]]}', "field meta"),
    ('"actuators":["VestFront_0"],"frames":[["1"]]}', "field frames[0]"),
    ('"actuators":["VestFront_0"],"layout":7,"frames":[[1]]}', "field layout"),
])
def test_wrong_types_in_track_json(tmp_path, body, place):
    path = tmp_path / "types.json"
    path.write_text(TRACK_HEAD + body)
    _refused(path, place)


def test_corrupt_npz_is_one_line(tmp_path):
    path = tmp_path / "bad.npz"
    path.write_bytes(b"PK\x03\x04" + b"\x00" * 200)  # a zip signature and nothing valid
    _refused(path, "BadZipFile")


def test_npz_with_a_broken_deflate_stream_is_one_line(tmp_path):
    track = HapticTrack(np.random.default_rng(0).uniform(0, 100, (50, 52)), 60.0, load_layout().actuators)
    path = tmp_path / "z.npz"
    save_track(track, path)
    raw = bytearray(path.read_bytes())
    # the first member's data starts after its 30-byte local header, name and extra field
    name_len, extra_len = int.from_bytes(raw[26:28], "little"), int.from_bytes(raw[28:30], "little")
    start = 30 + name_len + extra_len
    raw[start + 10:start + 60] = bytes(range(50))
    path.write_bytes(bytes(raw))
    _refused(path, "expected a hapmotion track NPZ")


def test_npz_declaring_a_huge_shape_is_refused_before_allocating(tmp_path):
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": (10**9, 52)})
    buf.write(b"\x00" * 64)
    path = tmp_path / "huge.npz"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("intensities.npy", buf.getvalue())
        zf.writestr("actuators.npy", b"")
    _refused(path, "declares shape (1000000000, 52)")


def test_tact_declaring_a_day_long_pattern_is_refused(tmp_path):
    """A 10 KB .tact that declares 86,000 s (fps 2000 x 86,000 s in the old format) asks for 4.3 million ticks."""
    path = tmp_path / "bomb.tact"
    path.write_text('{"project":{"mediaFileDuration":86000,"hapmotion":{"fps":2000},"layout":{"type":"Tactot"},'
                    '"tracks":[{"effects":[{"startTime":0,"offsetTime":86000000,"modes":{"VestFront":{"mode":'
                    '"DOT_MODE","dotMode":{"feedback":[{"startTime":0,"endTime":86000000,"pointList":'
                    '[{"index":1,"intensity":1}]}]}}}}]}]}}' + " " * 10_000)
    _refused(path, f"expected at most {DEFAULT_LIMITS.frames} frames (limit frames; raise it with --limit frames=N), "
                   "found 4300001")


def _npz_track(tmp_path, name="t.npz", **arrays):
    """A valid two-frame NPZ track with ``arrays`` added or replacing members (stored, so bytes can be edited)."""
    base = {"intensities": np.array([[10.0, 20.0], [30.0, 0.0]]), "actuators": np.array(["VestFront_0", "VestFront_1"]),
            "fps": np.array(50.0), "layout": np.array("x40_shoulders"), "meta_json": np.array("{}"),
            "debug_level": np.array([0.5, 1.0]), "debug_active": np.array([[1, 0], [0, 1]], dtype=np.int8)}
    base.update(arrays)
    path = tmp_path / name
    with open(path, "wb") as fh:
        np.savez(fh, **base)
    return path


def test_a_valid_npz_track_keeps_its_debug_arrays(tmp_path):
    track = load_track(_npz_track(tmp_path))
    assert track.debug["level"].tolist() == [0.5, 1.0] and track.debug["active"].shape == (2, 2)


def test_a_corrupt_npy_header_is_an_input_error_not_a_tokenizer_error(tmp_path):
    path = _npz_track(tmp_path)
    with zipfile.ZipFile(path) as zf:
        members = {name: zf.read(name) for name in zf.namelist()}
    # An unclosed bracket in the header's Python literal: numpy's header reader fails in its tokenizer (TokenError).
    members["fps.npy"] = members["fps.npy"].replace(b"'shape': ()", b"'shape': ((", 1)
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    _refused(path, "array fps: expected a readable .npy array header")


@pytest.mark.parametrize("name, value, needle", [
    ("debug_active", np.array([1, 0], dtype=np.int8), "array debug_active: expected shape (T, 2) with T = 2"),
    ("debug_dynamic_point", np.zeros((2, 2)), "array debug_dynamic_point: expected shape (T, 3)"),
    ("debug_level", np.array(["a", "b"]), "array debug_level: expected numbers, found <U1"),
    ("debug_level", np.zeros(5), "expected shape (T,) with T = 2, found (5,)"),
    ("debug_extra", np.zeros((2, 2, 2)), "array debug_extra: expected one row per frame (2)"),
    ("intensities", np.array([["a", "b"]]), "array intensities: expected numbers"),
], ids=["active-1d", "point-2-wide", "text", "wrong-length", "3d-unknown", "text-intensities"])
def test_every_debug_array_is_checked(tmp_path, name, value, needle):
    _refused(_npz_track(tmp_path, **{name: value}), needle)


def test_the_viewer_page_is_made_from_a_checked_npz(tmp_path):
    """What the viewer reads from a track: a page from a good NPZ; a bad debug array never reaches it."""
    from hapmotion.viewer.page import page_data

    data, blobs, _ = page_data([load_track(_npz_track(tmp_path))])
    assert set(data["tracks"][0]["debug"]) == {"active", "level"} and blobs


def test_an_npz_of_an_unknown_zip_version_is_a_one_line_error_in_view(tmp_path):
    """A byte edit that makes the archive claim zip version 22.8: the sniffing before ``view`` reads it and the
    reader both say so in one line (zipfile raises NotImplementedError)."""
    from hapmotion.cli import main

    path = _npz_track(tmp_path)
    data = bytearray(path.read_bytes())
    central = data.index(b"PK\x01\x02")
    data[central + 6] = 228                          # "version needed to extract" of the first member: 22.8
    path.write_bytes(bytes(data))
    assert main(["view", str(path), "-o", str(tmp_path / "page.html")]) == 2
    assert not (tmp_path / "page.html").exists()

"""Hostile and corrupt motion files: each ends in one clean error line (exit code 2), never a traceback, a hang,
a second stray line on stderr, or gigabytes of memory from a small file.

The CLI cases run ``hapmotion info`` in a subprocess whose address space is capped (``RLIMIT_AS``), so a reader
that trusted a declared size would fail with a MemoryError (an internal error, exit 1) instead of taking the
machine.
"""

from __future__ import annotations

import io
import json
import os
import pickle
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError
from hapmotion.limits import InputLimits
from support.data import MOTION
from support.motion_files import assert_input_error, kinect_document

SRC = Path(__file__).resolve().parents[1] / "src"
PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"
ADDRESS_SPACE = 1536 * 2**20  # bytes: the interpreter, numpy and numba need about 600 MB of it


def cli_info(path, *args, memory=ADDRESS_SPACE):
    """Run ``hapmotion info PATH ARGS`` in a fresh interpreter limited to ``memory`` bytes of address space;
    returns (exit code, stderr)."""
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (%d, %d)); "
            "from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))" % (memory, memory))
    env = dict(os.environ, PYTHONPATH=str(SRC), HAPMOTION_DEBUG="0")
    r = subprocess.run([sys.executable, "-c", code, "info", str(path), *map(str, args)], capture_output=True,
                       text=True, env=env, timeout=120)
    return r.returncode, r.stderr


def assert_clean_refusal(path, expected, *args):
    code, err = cli_info(path, *args)
    assert code == 2 and err.count("\n") == 1 and err.startswith("error: ") and expected in err, (code, err)
    return err


@pytest.fixture(scope="module")
def clip():
    return hapmotion.load_motion(PUNCH).slice(0, 8)


# ------------------------------------------------------------------------------------------------ Kinect JSON


def test_deeply_nested_json_is_refused_by_depth(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text('{"frames": ' + "[" * 200_000 + "]" * 200_000 + "}")
    assert_clean_refusal(path, "expected at most 64 levels of JSON nesting (limit depth; raise it with --limit "
                               "depth=N), found 200001")
    # brackets inside strings are text, not nesting
    doc = {"frames": [], "note": "[" * 500}
    path.write_text(json.dumps(doc))
    assert_input_error(path, "field frames", "expected at least one frame, found 0")


@pytest.mark.parametrize("digits", [400, 5000])
def test_huge_integers_in_json_fields(tmp_path, clip, digits):
    """Python's int() refuses 4,300+ digits (ValueError) and a float cannot hold 400 digits (OverflowError):
    both are the file's fault, refused before parsing by the number_digits limit and, with the limit raised,
    named by field."""
    doc = kinect_document(clip, second_body=False, jitter=False)
    doc["frames"][2]["timestamp_usec"] = 424242
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc).replace("424242", "9" * digits))
    assert_clean_refusal(path, f"big.json: line 1: expected at most 100 digits in a number (limit number_digits; "
                               f"raise it with --limit number_digits=N), found {digits}")
    assert_clean_refusal(path, "field frames[2].timestamp_usec: expected a number of microseconds, found the "
                               "number inf", "--limit", "number_digits=6000")
    doc = kinect_document(clip, second_body=False, jitter=False)
    doc["frames"][1]["bodies"][0]["body_id"] = 424242
    path.write_text(json.dumps(doc).replace("424242", "7" * digits))
    assert_clean_refusal(path, "field frames[1].bodies[0].body_id: expected a whole number, found the number inf",
                         "--limit", "number_digits=6000")


def test_timestamp_far_in_the_future_is_a_jump_not_a_cast_warning(tmp_path, clip):
    """One forged timestamp (1e30 us) among regular ones: the frame slots would overflow int64 (numpy prints a
    RuntimeWarning and the reader then allocated a negative size); it is refused as a jump."""
    doc = kinect_document(clip, second_body=False, jitter=False)
    doc["frames"][-1]["timestamp_usec"] = 1e30
    path = tmp_path / "jump.json"
    path.write_text(json.dumps(doc))
    assert_clean_refusal(path, f"field frames[{clip.n_frames - 1}].timestamp_usec: expected steps of about 33333 us")


# ------------------------------------------------------------------------------------------------------- BVH


def deep_bvh(depth: int) -> str:
    lines = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0", "CHANNELS 3 Xposition Yposition Zposition"]
    lines += [f"JOINT j{k}\n{{\nOFFSET 0 1 0\nCHANNELS 0" for k in range(depth)]
    lines += ["}"] * (depth + 1) + ["MOTION", "Frames: 1", "Frame Time: 0.01", "0 0 0"]
    return "\n".join(lines) + "\n"


def test_bvh_hierarchy_thousands_deep(tmp_path):
    path = tmp_path / "deep.bvh"
    path.write_text(deep_bvh(5000))
    assert_clean_refusal(path, "expected at most 64 levels of joint nesting (limit depth; raise it with --limit "
                               "depth=N), found 65")
    # the limit is the only obstacle: raised, the file parses (and then lacks the joints a render needs)
    assert_clean_refusal(path, "joints HAND_LEFT", "--limit", "depth=6000", "--limit", "joints=6000")


def test_bvh_joint_count_and_frames_limits(tmp_path):
    wide = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0", "CHANNELS 3 Xposition Yposition Zposition"]
    wide += [f"JOINT j{k}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n}}" for k in range(1200)]
    wide += ["}", "MOTION", "Frames: 1", "Frame Time: 0.01", "0 0 0"]
    path = tmp_path / "wide.bvh"
    path.write_text("\n".join(wide) + "\n")
    # the 1001st joint (Hips is the first) is j999, whose JOINT line is 6 + 5 * 999
    assert_input_error(path, "line 5001", "expected at most 1000 joints in the hierarchy (limit joints; raise it "
                       "with --limit joints=N), found 1001")
    assert_input_error(PUNCH, "line 133", "expected at most 100 frames (limit frames; raise it with --limit "
                       "frames=N), found 224", limits={"frames": 100})
    assert_input_error(PUNCH, "line 134", "expected at most 5 seconds of motion (limit duration_s",
                       limits=InputLimits(duration_s=5))
    with pytest.raises(InputError, match=r"001\.bvh: expected a file of at most 0\.1 MB \(limit file_mb; raise it "
                       r"with --limit file_mb=N\), found 0\.3 MB$"):
        hapmotion.load_motion(PUNCH, limits={"file_mb": 0.1})


# ------------------------------------------------------------------------------------------------------- NPZ


def good_npz(clip) -> bytes:
    buf = io.BytesIO()
    names = np.array(["PELVIS", "SPINE_NAVEL", "NECK", "SHOULDER_LEFT", "SHOULDER_RIGHT", "HAND_LEFT", "HAND_RIGHT"])
    pos = np.stack([clip.joint(n) for n in names], axis=1)
    np.savez_compressed(buf, positions=pos, joints=names, fps=np.float64(clip.fps))
    return buf.getvalue()


def test_corrupt_npz_archives(tmp_path, clip):
    raw = good_npz(clip)
    z = zipfile.ZipFile(io.BytesIO(raw))
    info = z.getinfo("positions.npy")
    h = info.header_offset  # local file header: 30 bytes, then the name and the extra field (lengths at 26, 28)
    start = h + 30 + int.from_bytes(raw[h + 26:h + 28], "little") + int.from_bytes(raw[h + 28:h + 30], "little")
    cases = {
        "flipped.npz": raw[:start + 20] + bytes(b ^ 0x5A for b in raw[start + 20:start + 60]) + raw[start + 60:],
        "cut.npz": raw[: len(raw) // 2],
        "header.npz": raw[:start] + b"\xff" * 8 + raw[start + 8:],
        # a stored (uncompressed) archive with one data byte changed: only the CRC tells
        "crc.npz": None,
    }
    stored = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(raw)) as src, zipfile.ZipFile(stored, "w", zipfile.ZIP_STORED) as dst:
        for item in src.infolist():
            dst.writestr(item.filename, src.read(item.filename))
    crc = bytearray(stored.getvalue())
    crc[crc.index(b"positions.npy") + 13 + 200] ^= 0x01  # a byte inside the positions data
    cases["crc.npz"] = bytes(crc)
    for name, data in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(InputError) as err:
            hapmotion.load_motion(path)
        assert str(err.value).startswith(f"{path}: ") and "\n" not in str(err.value)


def npz_member(name: str, header: dict, chunks, **others: np.ndarray) -> bytes:
    """An NPZ holding a ``.npy`` member with the given header dict and data chunks (deflated as written), and
    ``others`` as ordinary arrays."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for key, value in others.items():
            with z.open(key + ".npy", "w") as f:
                np.lib.format.write_array(f, value)
        with z.open(name + ".npy", "w", force_zip64=True) as f:
            hbuf = io.BytesIO()
            np.lib.format.write_array_header_1_0(hbuf, header)
            f.write(hbuf.getvalue())
            for c in chunks:
                f.write(c)
    return buf.getvalue()


def test_npz_header_declaring_a_huge_shape(tmp_path):
    """A 200-byte member whose header says (10, 10^12, 3): numpy would try to allocate 240 TB."""
    data = npz_member("positions", {"descr": "<f8", "fortran_order": False, "shape": (10, 10**12, 3)}, [b"\0" * 64])
    path = tmp_path / "shape.npz"
    path.write_bytes(data)
    assert_clean_refusal(path, "field positions: expected an array that fits its archive member, found a shape "
                               "(10, 1000000000000, 3) of 2.4e+14 bytes in a member of")
    data = npz_member("positions", {"descr": "<f8", "fortran_order": False, "shape": (10**12, 32, 3)}, [b"\0" * 64])
    path.write_bytes(data)
    assert_clean_refusal(path, "field positions: expected at most 500000 frames (limit frames")


def test_npz_of_compressed_zeros(tmp_path):
    """About 450 kB of deflated zeros declaring 600,000 frames (460 MB, several GB once read): refused from the
    header, before decompressing."""
    frames = 600_000
    size = frames * 32 * 3 * 8
    block = b"\0" * 2**22
    chunks = [block] * (size // len(block)) + [b"\0" * (size % len(block))]
    from hapmotion.skeleton.joints import JOINTS

    data = npz_member("positions", {"descr": "<f8", "fortran_order": False, "shape": (frames, 32, 3)}, chunks,
                      joints=np.array(JOINTS), fps=np.float64(120.0))
    assert len(data) < 1_000_000
    path = tmp_path / "zeros.npz"
    path.write_bytes(data)
    assert_clean_refusal(path, "field positions: expected at most 500000 frames (limit frames; raise it with "
                               "--limit frames=N), found 600000")


# ---------------------------------------------------------------------------------------------------- AIST++


class _Bomb:
    """Pickles as numpy's ``_reconstruct(ndarray, (3000000, 17, 3), "d")``: 1.2 GB from a short file."""

    def __reduce__(self):
        from numpy._core.multiarray import _reconstruct

        return _reconstruct, (np.ndarray, (3_000_000, 17, 3), b"d")


def test_small_pickle_declaring_millions_of_frames(tmp_path):
    data = pickle.dumps({"keypoints3d_optim": _Bomb()}, protocol=4)
    assert len(data) < 200
    path = tmp_path / "bomb.pkl"
    path.write_bytes(data)
    assert_clean_refusal(path, "an array of shape (3000000, 17, 3) declares 1.22e+09 bytes, more than the")


def test_pickle_within_its_size_but_over_the_frame_limit(tmp_path):
    path = tmp_path / "long.pkl"
    path.write_bytes(pickle.dumps({"keypoints3d_optim": np.zeros((1200, 17, 3))}))
    assert_input_error(path, "field keypoints3d_optim", "expected at most 1000 frames (limit frames",
                       limits={"frames": 1000})


def test_pickle_of_object_arrays_is_refused(tmp_path):
    path = tmp_path / "obj.pkl"
    path.write_bytes(pickle.dumps({"keypoints3d_optim": np.array([1, "a"], dtype=object)}))
    with pytest.raises(InputError, match=r"obj\.pkl: .*refusing an array of dtype object"):
        hapmotion.load_motion(path)


def test_json_that_would_parse_into_gigabytes(tmp_path):
    """9 MB of ``[],`` is 3 million 56-byte lists once parsed: refused from the first pass over the bytes, with the
    estimate and the limit to raise."""
    path = tmp_path / "lists.json"
    path.write_bytes(b'{"frames": [' + b"[]," * 3_000_000 + b"[]]}")
    with pytest.raises(InputError, match=r"lists\.json: expected at most 512 MB of parsed JSON \(3000003 lists and "
                       r"objects, up to 6000004 values\) \(limit json_mb; raise it with --limit json_mb=N\), found 600$"):
        hapmotion.load_motion(path)
    with pytest.raises(InputError, match="field frames"):  # raised, the file parses (and is not a recording)
        hapmotion.load_motion(path, limits={"json_mb": 700})

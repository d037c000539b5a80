"""AIST++ 3D keypoint annotations (``keypoints3d/*.pkl``): COCO-17 joints, centimetres, +Y up, 60 fps.

The file is a pickle of ``{"keypoints3d": (N, 17, 3) float64, "keypoints3d_optim": (N, 17, 3) float64}``; we use
``keypoints3d_optim`` (temporally optimised) when it is there. Pickles can run code when loaded, so the loader only
rebuilds plain numpy arrays, dicts and lists; anything else is refused with an :class:`InputError`.

Joint mapping (COCO-17 index -> canonical): wrists 9/10 -> WRIST_* and HAND_* (COCO has no hand point; BVH readers
use the wrist for HAND_* too), shoulders 5/6, elbows 7/8, hips 11/12, knees 13/14, ankles 15/16, nose 0, eyes 1/2,
ears 3/4. Derived (:func:`hapmotion.skeleton.derived.derive_missing`): PELVIS = mid hips, NECK = mid shoulders, SPINE_NAVEL and
SPINE_CHEST on PELVIS -> NECK at 0.38 and 0.60, HEAD = mid ears (nose where an ear is missing). Frames with NaN
keypoints (some AIST++ sequences have them) are gaps.
"""

from __future__ import annotations

import io
import os
import pickle
from typing import Any

import numpy as np

from ..errors import InputError
from ..skeleton.joints import JOINT_INDEX, N_JOINTS
from ..motion import Motion, new_motion
from ..skeleton.derived import derive_missing
from ..limits import DEFAULT_LIMITS, InputLimits, check_frames, read_bytes
from .options import ReaderOptions, skip_count
from .units import units_or_default

COCO17: tuple[str, ...] = (
    "nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder", "left_elbow",
    "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
    "right_ankle",
)
"""COCO-17 keypoint names in index order (AIST++ uses this order)."""

COCO17_TO_CANONICAL: dict[str, tuple[str, ...]] = {
    "nose": ("NOSE",), "left_eye": ("EYE_LEFT",), "right_eye": ("EYE_RIGHT",),
    "left_ear": ("EAR_LEFT",), "right_ear": ("EAR_RIGHT",),
    "left_shoulder": ("SHOULDER_LEFT",), "right_shoulder": ("SHOULDER_RIGHT",),
    "left_elbow": ("ELBOW_LEFT",), "right_elbow": ("ELBOW_RIGHT",),
    "left_wrist": ("WRIST_LEFT", "HAND_LEFT"), "right_wrist": ("WRIST_RIGHT", "HAND_RIGHT"),
    "left_hip": ("HIP_LEFT",), "right_hip": ("HIP_RIGHT",), "left_knee": ("KNEE_LEFT",), "right_knee": ("KNEE_RIGHT",),
    "left_ankle": ("ANKLE_LEFT",), "right_ankle": ("ANKLE_RIGHT",),
}

AIST_FPS = 60.0  # AIST++ annotations are 60 fps exactly (repository google/aistplusplus_dataset, factsfigures.html)
KEYS = ("keypoints3d_optim", "keypoints3d")


class _ArrayUnpickler(pickle.Unpickler):
    """Unpickler that rebuilds numpy arrays of numbers and nothing else (no arbitrary classes or functions).

    An array's data is stored inside the pickle, so no array may hold more bytes than the file: numpy's
    ``_reconstruct(ndarray, shape, dtype)`` would otherwise allocate whatever shape a 60-byte file names (a
    ``(3000000, 17, 3)`` float64 array is 1.2 GB) before anything could be checked.
    """

    _ALLOWED = {
        ("numpy.core.multiarray", "_reconstruct"), ("numpy._core.multiarray", "_reconstruct"),
        ("numpy.core.multiarray", "scalar"), ("numpy._core.multiarray", "scalar"),
        ("numpy", "ndarray"), ("numpy", "dtype"), ("collections", "OrderedDict"),
    }

    def __init__(self, data: bytes):
        super().__init__(io.BytesIO(data))
        self.budget = len(data)

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) not in self._ALLOWED:
            raise pickle.UnpicklingError(f"refusing to load '{module}.{name}' (only numpy arrays are accepted)")
        if module.startswith("numpy.core"):  # pickles written by numpy 1.x
            module = "numpy._core" + module[len("numpy.core"):]
        found = super().find_class(module, name)
        if name == "_reconstruct":
            return self._reconstruct(found)
        if name == "dtype":
            return _numeric_dtype
        return found

    def _reconstruct(self, real: Any) -> Any:
        def checked(subtype: Any, shape: Any, dtype: Any) -> Any:
            size = _declared_bytes(shape, dtype)
            if size > self.budget:
                raise pickle.UnpicklingError(f"an array of shape {tuple(shape)[:4]} declares {size:.3g} bytes, more "
                                             f"than the {self.budget}-byte file holds")
            return real(subtype, shape, dtype)

        return checked


def _numeric_dtype(*args: Any, **kwargs: Any) -> np.dtype:
    """``numpy.dtype`` limited to numbers and text: an object array would unpickle arbitrary objects."""
    dt = np.dtype(*args, **kwargs)
    if dt.kind not in "biufcSU" or dt.hasobject:
        raise pickle.UnpicklingError(f"refusing an array of dtype {dt} (only numbers are accepted)")
    return dt


def _declared_bytes(shape: Any, dtype: Any) -> float:
    """Bytes an array of ``shape`` and ``dtype`` needs (a float: a forged shape may overflow 64-bit integers)."""
    try:
        dims = [int(d) for d in (shape if isinstance(shape, (tuple, list)) else (shape,))]
        item = np.dtype(dtype.decode("latin-1") if isinstance(dtype, bytes) else dtype).itemsize
    except (TypeError, ValueError):
        raise pickle.UnpicklingError(f"an array with shape {shape!r}") from None
    if any(d < 0 for d in dims):
        raise pickle.UnpicklingError(f"an array with a negative dimension {tuple(dims)[:4]}")
    total = float(item)
    for d in dims:
        total *= d
    return total


def load_pickle(path: str, limits: InputLimits = DEFAULT_LIMITS) -> Any:
    """Unpickle ``path`` allowing only numpy arrays inside builtin containers; :class:`InputError` otherwise."""
    raw = read_bytes(path, limits)
    try:
        return _ArrayUnpickler(raw).load()
    except RecursionError:
        raise InputError(path, None, "expected an AIST++ keypoints pickle, found data nested too deeply") from None
    except MemoryError:
        raise InputError(path, None, "expected an AIST++ keypoints pickle, found data that declares more memory "
                         "than is available") from None
    except Exception as err:  # any failure of untrusted bytes is the file's fault, never a crash
        reason = " ".join(str(err).split())[:160] if str(err) else type(err).__name__
        raise InputError(path, None, f"expected an AIST++ keypoints pickle (a dict of numpy arrays), found data "
                         f"that cannot be loaded ({reason})") from None


def keypoints_from(path: str, doc: Any, limits: InputLimits = DEFAULT_LIMITS,
                   fps: float = 60.0) -> tuple[np.ndarray, str]:
    """The ``(N, 17, 3)`` keypoint array and the key it came from (its frames checked against ``limits``)."""
    if not isinstance(doc, dict):
        raise InputError(path, "field (top level)", f"expected a dict with {' or '.join(KEYS)}, found "
                         f"{type(doc).__name__}")
    key = next((k for k in KEYS if k in doc), None)
    if key is None:
        hint = " (this looks like an AIST++ SMPL motion file; its joints need the SMPL body model)" \
            if "smpl_poses" in doc else ""
        raise InputError(path, "field keypoints3d", f"expected a key {' or '.join(KEYS)}, found keys "
                         f"{', '.join(map(str, doc)) or 'none'}{hint}")
    arr = doc[key]
    if not isinstance(arr, np.ndarray) or arr.dtype.kind not in "fiu":
        raise InputError(path, f"field {key}", f"expected a numeric array, found {type(arr).__name__}")
    if arr.ndim != 3 or arr.shape[1:] != (17, 3):
        raise InputError(path, f"field {key}", f"expected shape (frames, 17, 3) (COCO-17), found {arr.shape}")
    if arr.shape[0] == 0:
        raise InputError(path, f"field {key}", "expected at least one frame, found 0")
    check_frames(path, f"field {key}", arr.shape[0], fps, limits)
    if np.isinf(arr).any():
        f = int(np.argwhere(np.isinf(arr))[0][0])
        raise InputError(path, f"field {key}, frame {f}", "expected finite keypoints (or NaN for missing), found inf")
    return np.asarray(arr, dtype=np.float64), key


def read_aist(path: str | os.PathLike[str], options: ReaderOptions = ReaderOptions()) -> Motion:
    """Read an AIST++ ``keypoints3d`` pickle into a :class:`~hapmotion.motion.Motion`.

    Defaults: centimetres, 60 fps; the ``units``/``scale`` and ``fps`` options override them, ``skip_frames``
    drops leading frames. NaN keypoints are gaps.
    """
    path = os.fspath(path)
    fps = options.fps
    kp, key = keypoints_from(path, load_pickle(path, options.limits), options.limits,
                             fps if fps is not None else AIST_FPS)
    metres, unit_text = units_or_default(options.units, options.scale, (0.01, "cm (x0.01 -> m)"))
    notes: list[str] = [f"keypoints from '{key}'"]
    skip = skip_count(options.skip_frames, kp.shape[0], path)
    if skip:
        kp = kp[skip:]
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    positions = np.full((kp.shape[0], N_JOINTS, 3), np.nan)
    source: dict[str, str] = {}
    for i, name in enumerate(COCO17):
        for canon in COCO17_TO_CANONICAL[name]:
            positions[:, JOINT_INDEX[canon]] = kp[:, i] * metres
            source[canon] = name
    derived, derived_from = derive_missing(positions)
    n_nan = int(np.isnan(kp).any(axis=2).any(axis=1).sum())
    if n_nan:
        notes.append(f"{n_nan} frame(s) with NaN keypoints (gaps, filled)")
    if fps is not None:
        notes.append(f"frame rate {fps:g} fps from the option (AIST++ is {AIST_FPS:g})")
    meta = {
        "format": "AIST++ keypoints3d pickle",
        "skeleton": "COCO-17 keypoints",
        "units": unit_text,
        "metres_per_unit": metres,
        "up_axis": "+Y (fixed by the format)",
        "source_joints": source,
        "derived_from": derived_from,
        "skipped_frames": skip or 0,
        "source_joints_available": list(COCO17),
        "notes": notes,
    }
    rate = float(fps) if fps is not None else AIST_FPS
    return new_motion(positions, rate, source=path, derived=derived, meta=meta)

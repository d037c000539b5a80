"""Joints a format lacks, computed from the joints it has (hands from wrists, pelvis from hips, ...)."""

from __future__ import annotations

from typing import Iterable, Optional

import numpy as np

from .joints import JOINT_INDEX
from .spine import CHEST_FRACTION, NAVEL_FRACTION


def missing_needed(names: Iterable[str]) -> list[str]:
    """Render joints that are neither among ``names`` (canonical joint names, or a mapping keyed by them) nor
    derivable from them by :func:`derive_missing`.

    Needed: HAND_* (or WRIST_*), SHOULDER_*, PELVIS (or both HIP_*); NECK derives from the shoulders and
    SPINE_NAVEL from PELVIS and NECK, so they follow.
    """
    have = set(names)
    out = []
    for side in ("LEFT", "RIGHT"):
        if f"HAND_{side}" not in have and f"WRIST_{side}" not in have:
            out.append(f"HAND_{side}")
    for side in ("LEFT", "RIGHT"):
        if f"SHOULDER_{side}" not in have:
            out.append(f"SHOULDER_{side}")
    if "PELVIS" not in have and not {"HIP_LEFT", "HIP_RIGHT"} <= have:
        out.append("PELVIS")
    return out


def _has(pos: np.ndarray, name: str) -> bool:
    """The joint has a finite position in some frame (checking frame 0 first: the usual answer, and cheap)."""
    joint = pos[:, JOINT_INDEX[name]]
    return bool(np.isfinite(joint[0]).all() or np.isfinite(joint).all(axis=1).any())


def derive_missing(pos: np.ndarray, only: Optional[tuple[str, ...]] = None) -> tuple[np.ndarray, dict[str, str]]:
    """Fill absent render-related joints of ``pos`` ((T, 32, 3), NaN = absent) in place from the others.

    Rules, in order (each only when the joint has no finite value in any frame and its inputs exist):
    HAND_* = WRIST_*; PELVIS = mid(HIP_LEFT, HIP_RIGHT); NECK = mid(SHOULDER_LEFT, SHOULDER_RIGHT);
    SPINE_NAVEL = PELVIS + 0.38 (NECK - PELVIS); SPINE_CHEST = PELVIS + 0.60 (NECK - PELVIS) (the fractions of
    :mod:`.spine`);
    HEAD = mid(EAR_LEFT, EAR_RIGHT), or NOSE in frames where an ear is missing. NaN inputs in a frame give NaN
    there (a gap that ``new_motion`` fills). ``only`` limits the joints derived (the table readers derive only
    the render joints, so that writing and reading a table gives back the same joints).

    Returns ``(derived, derived_from)``: ``(32,)`` bool mask and joint -> rule text.
    """
    derived = np.zeros(pos.shape[1], dtype=bool)
    how: dict[str, str] = {}
    J = JOINT_INDEX

    def put(name: str, value: np.ndarray, rule: str) -> None:
        if only is not None and name not in only:
            return
        pos[:, J[name]] = value
        derived[J[name]] = True
        how[name] = rule

    for side in ("LEFT", "RIGHT"):
        if not _has(pos, f"HAND_{side}") and _has(pos, f"WRIST_{side}"):
            put(f"HAND_{side}", pos[:, J[f"WRIST_{side}"]], f"WRIST_{side}")
    if not _has(pos, "PELVIS") and _has(pos, "HIP_LEFT") and _has(pos, "HIP_RIGHT"):
        put("PELVIS", 0.5 * (pos[:, J["HIP_LEFT"]] + pos[:, J["HIP_RIGHT"]]), "mid(HIP_LEFT, HIP_RIGHT)")
    if not _has(pos, "NECK") and _has(pos, "SHOULDER_LEFT") and _has(pos, "SHOULDER_RIGHT"):
        put("NECK", 0.5 * (pos[:, J["SHOULDER_LEFT"]] + pos[:, J["SHOULDER_RIGHT"]]),
            "mid(SHOULDER_LEFT, SHOULDER_RIGHT)")
    if _has(pos, "PELVIS") and _has(pos, "NECK"):
        pelvis, neck = pos[:, J["PELVIS"]], pos[:, J["NECK"]]
        for name, f in (("SPINE_NAVEL", NAVEL_FRACTION), ("SPINE_CHEST", CHEST_FRACTION)):
            if not _has(pos, name):
                put(name, pelvis + f * (neck - pelvis), f"PELVIS + {f:.2f} (NECK - PELVIS)")
    if not _has(pos, "HEAD"):
        ears = 0.5 * (pos[:, J["EAR_LEFT"]] + pos[:, J["EAR_RIGHT"]])
        nose = pos[:, J["NOSE"]]
        if np.isfinite(ears).all(axis=1).any():
            ok = np.isfinite(ears).all(axis=1)
            put("HEAD", np.where(ok[:, None], ears, nose), "mid(EAR_LEFT, EAR_RIGHT), else NOSE")
        elif np.isfinite(nose).all(axis=1).any():
            put("HEAD", nose, "NOSE")
    return derived, how

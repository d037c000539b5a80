"""User joint maps: which of *their* joint names is which of *our* canonical joints, for a skeleton the automatic
matching does not know.

A map is a TOML or JSON file of ``"their name" = "OUR_JOINT"`` pairs (at the top level or under a ``[joints]``
table), for example ``map.toml``::

    # hapmotion joint map: BVH joint name = canonical joint
    "lhnd" = "HAND_LEFT"
    "rhnd" = "HAND_RIGHT"
    "torso_2" = "SPINE_CHEST"

or ``{"joints": {"lhnd": "HAND_LEFT", "rhnd": "HAND_RIGHT"}}`` in JSON. Canonical names are the 32 Azure Kinect
joints (``hapmotion.skeleton.joints.JOINTS``), case-insensitive. Joints the map leaves out are matched automatically.
"""

from __future__ import annotations

import difflib
import json
import os
import tomllib
from typing import Any, Mapping

from ..errors import InputError, UsageError
from ..skeleton.joints import JOINTS, canonical

MAP_EXAMPLE = '"YourJointName" = "HAND_LEFT"'
"""One line of a map, for messages."""


def load_joint_map(source: "str | os.PathLike[str] | Mapping[str, str]") -> dict[str, str]:
    """Their joint name -> canonical joint, from a ``.toml``/``.json`` file or a mapping.

    Raises :class:`InputError` naming the file and the entry for an unreadable file, a value that is not a
    canonical joint (with the closest canonical names) or two names mapped to one joint.
    """
    if isinstance(source, Mapping):
        return _checked("joint map", dict(source))
    path = os.fspath(source)
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".toml", ".json"):
        raise UsageError(f"joint map {path}: expected a .toml or .json file, found '{ext or 'no extension'}'")
    try:
        with open(path, "rb") as f:
            raw = f.read(1_000_001)
    except FileNotFoundError:
        raise InputError(path, None, "file not found") from None
    except OSError as err:
        raise InputError(path, None, f"cannot read the joint map ({err.strerror or err})") from None
    if len(raw) > 1_000_000:
        raise InputError(path, None, "expected a joint map of at most 1 MB")
    try:
        if ext == ".toml":
            doc: Any = tomllib.loads(raw.decode("utf-8"))
        else:
            doc = json.loads(raw)
    except UnicodeDecodeError:
        raise InputError(path, None, "expected UTF-8 text") from None
    except (ValueError, RecursionError) as err:  # tomllib.TOMLDecodeError and JSONDecodeError are ValueErrors
        raise InputError(path, None, f"expected {ext[1:].upper()} pairs like {MAP_EXAMPLE} "
                         f"({str(err).splitlines()[0][:120]})") from None
    if isinstance(doc, dict) and isinstance(doc.get("joints"), dict):
        doc = doc["joints"]
    if not isinstance(doc, dict):
        raise InputError(path, None, f"expected pairs like {MAP_EXAMPLE}, found {type(doc).__name__}")
    return _checked(path, doc)


def _checked(source: str, doc: dict) -> dict[str, str]:
    out: dict[str, str] = {}
    owner: dict[str, str] = {}
    for theirs, ours in doc.items():
        where = f"entry {str(theirs)[:60]!r}"
        if not isinstance(ours, str):
            raise InputError(source, where, f"expected a canonical joint name such as \"HAND_LEFT\", found "
                             f"{type(ours).__name__}")
        try:
            canon = canonical(ours)
        except KeyError:
            close = difflib.get_close_matches(ours.strip().upper(), JOINTS, n=3, cutoff=0.5)
            hint = f" (closest: {', '.join(close)})" if close else f" (one of {', '.join(JOINTS[:8])}, ...)"
            raise InputError(source, where, f"expected a canonical joint name, found {ours[:60]!r}{hint}") from None
        if canon in owner:
            raise InputError(source, where, f"expected one joint per canonical joint, found {canon} also given to "
                             f"{owner[canon][:60]!r}")
        owner[canon] = str(theirs)
        out[str(theirs)] = canon
    return out

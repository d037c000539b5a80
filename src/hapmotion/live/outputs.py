"""Checks on the files live mode writes at stop (``record:PATH``, ``--stats-json``), made before the show starts:
a mistake must be one line before anything plays, not a lost file after the performance."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ..errors import UsageError


def check_writable(path: "str | os.PathLike[str]", what: str) -> None:
    """Raise :class:`UsageError` (naming ``what``, e.g. ``record:show.csv``) unless a file can be written at
    ``path``: it is not a folder, and a temporary file can be created (then removed) in its folder."""
    target = Path(path)
    if target.is_dir():
        raise UsageError(f"{what}: {target} is a folder, expected a file name")
    folder = target.parent
    if not folder.is_dir():
        raise UsageError(f"{what}: folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".check", dir=folder)
    except OSError as exc:
        raise UsageError(f"{what}: cannot write in folder {folder} ({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(tmp)

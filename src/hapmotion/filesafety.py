"""File safety: outputs appear whole or not at all, and a file is known to be writable before a show starts.

* :func:`atomic_path` - write to a temporary file beside the target, rename it into place when complete;
* :func:`check_writable` - fail early, in one line, when a file that will be written at the end cannot be.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import tempfile
from pathlib import Path
from typing import Iterator

from .errors import InputError, UsageError


@contextlib.contextmanager
def atomic_path(path: "str | os.PathLike[str]") -> Iterator[Path]:
    """Yield a temporary path in the target's folder; on success it replaces ``path``, on error it is removed.

    Raises :class:`InputError` when the folder does not exist or cannot be written.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(target, None, f"expected an existing folder {folder}, found none")
    tmp_path = folder / f".{target.name}.{secrets.token_hex(4)}.part"
    try:
        # a plain exclusive create, so the file gets the user's umask permissions (mkstemp would give 0600)
        with open(tmp_path, "xb"):
            pass
    except OSError as err:
        raise InputError(target, None, f"cannot write there: {err.strerror}") from None
    try:
        try:
            yield tmp_path
            os.replace(tmp_path, target)
        except OSError as err:  # disk full, target is a directory, ...: the user's to fix, one line
            raise InputError(target, None, f"cannot write: {err.strerror or err}") from None
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


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

"""Atomic file output: write to a temporary file beside the target, rename it into place when complete."""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import Iterator

from ..errors import InputError


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

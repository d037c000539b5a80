"""User-facing errors.

Every mistake a user can make with their input (a bad file, a wrong option, a live message that does not fit)
ends as one :class:`HapMotionError`. The CLI prints ``str(err)`` as a single line on stderr and exits with
``err.exit_code``; it never shows a traceback for these. Code that finds bad input raises one of the
subclasses with the file, the place (line, frame, joint, field) and what was expected, for example::

    raise InputError("bad.bvh", "line 212", "96 channel values, found 95")

which prints ``bad.bvh: line 212: expected 96 channel values, found 95``.
"""

from __future__ import annotations

import os
from typing import Optional


class HapMotionError(Exception):
    """Base class of the errors the CLI reports as one line (exit code 2 unless a subclass says otherwise)."""

    exit_code = 2

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:  # one line, always
        return " ".join(self.message.split())


class InputError(HapMotionError):
    """A file or stream the user gave cannot be used.

    Parameters
    ----------
    source:
        File path (or a stream name such as ``osc://0.0.0.0:9000``).
    place:
        Where in it: ``"line 12"``, ``"frame 40"``, ``"joint HAND_LEFT"``, ``"field frames[3].bodies"``; may be
        empty when the whole file is at fault.
    problem:
        What was expected and what was found, e.g. ``"expected 96 channel values, found 95"``.
    """

    def __init__(self, source: "str | os.PathLike[str]", place: Optional[str], problem: str):
        self.source = os.fspath(source)
        self.place = place or ""
        self.problem = problem
        parts = [self.source]
        if self.place:
            parts.append(self.place)
        parts.append(problem)
        super().__init__(": ".join(parts))


class UsageError(HapMotionError):
    """Options that do not fit together or an unknown value (a preset, a mode, an extension)."""

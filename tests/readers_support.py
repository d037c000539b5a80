"""Helpers shared by the reader tests (no tests here)."""

from __future__ import annotations

from pathlib import Path

import pytest

import hapmotion
from hapmotion.errors import InputError

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "motion"


def assert_input_error(path, place: str, problem: str, loader=hapmotion.load_motion, **options) -> str:
    """``loader(path, **options)`` raises one-line ``InputError`` "<path>: <place>: ... <problem> ..."."""
    with pytest.raises(InputError) as err:
        loader(path, **options)
    msg = str(err.value)
    assert msg.startswith(f"{path}: {place}: ") and problem in msg, msg
    assert "\n" not in msg
    return msg

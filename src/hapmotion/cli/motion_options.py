"""The reader options every command that reads motion shares, from one definition: :func:`motion_options` adds
them to a click command and :func:`read_motion` reads a file with them."""

from __future__ import annotations

import functools
import os
from typing import Any, Callable, Optional

import click

from ..motion import Motion

MOTION_OPTION_NAMES = ("units", "scale", "skip_frames", "body_id", "fps_in", "up")
"""Parameter names :func:`motion_options` adds; they arrive in the command as one dict, ``motion_opts``."""

CLI_SPELLING = {"units": "--units", "scale": "--scale", "skip_frames": "--skip-frames", "body_id": "--body-id",
                "fps": "--fps-in", "up": "--up"}
"""Reader option -> the command-line option that sets it."""


def motion_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Click decorator: add the reader options and hand them to the command as one keyword, ``motion_opts``.

    Use it under ``@click.command()`` (and with the command's other options)::

        @click.command()
        @click.argument("input")
        @motion_options
        def command(input, motion_opts):
            motion = read_motion(input, **motion_opts)

    Options: ``--units``, ``--scale``, ``--skip-frames``, ``--body-id``, ``--fps-in``, ``--up``.
    """

    @functools.wraps(f)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        kwargs["motion_opts"] = {name: kwargs.pop(name, None) for name in MOTION_OPTION_NAMES}
        return f(*args, **kwargs)

    # functools.wraps copied f's click params (a shared list); give the wrapper its own before adding ours.
    wrapper.__click_params__ = list(getattr(f, "__click_params__", []))  # type: ignore[attr-defined]
    options = [
        click.option("--units", type=click.Choice(["m", "cm", "mm", "inch", "cmu"], case_sensitive=False),
                     default=None, help="Length unit of the input file (default: from the format; for BVH detected "
                     "from the skeleton and a plausible standing height). cmu = CMU units, x0.056444."),
        click.option("--scale", type=float, default=None, metavar="M_PER_UNIT",
                     help="Metres per file unit, instead of --units."),
        click.option("--skip-frames", type=click.IntRange(min=0), default=None, metavar="N",
                     help="Drop the first N frames (default: BVH drops detected T-pose frames, others none)."),
        click.option("--body-id", type=int, default=None, metavar="ID",
                     help="Azure Kinect JSON: the body to use (default: the first body id seen)."),
        click.option("--fps-in", type=float, default=None, metavar="FPS",
                     help="Frame rate of the input (0.5 to 2000), overriding the file's (BVH Frame Time, Kinect "
                     "timestamps, ...)."),
        click.option("--up", type=click.Choice(["y", "z"], case_sensitive=False), default=None,
                     help="Up axis of the input (BVH, CSV, NPZ; default y)."),
    ]
    for option in reversed(options):  # click lists params in decoration order, bottom first
        wrapper = option(wrapper)
    return wrapper


def read_motion(path: "str | os.PathLike[str]", *, units: Optional[str] = None, scale: Optional[float] = None,
                  skip_frames: Optional[int] = None, body_id: Optional[int] = None, fps_in: Optional[float] = None,
                  up: Optional[str] = None) -> Motion:
    """``hapmotion.load_motion`` with the CLI's option names (``fps_in`` is the reader's ``fps``).

    Options left at ``None`` are not passed; one that does not apply to the format raises
    :class:`~hapmotion.errors.UsageError`, which the CLI prints as one line.
    """
    from ..motion_files import check_options, load_motion
    from ..motion_files._common import check_fps_option

    options = {"units": units, "scale": scale, "skip_frames": skip_frames, "body_id": body_id, "fps": fps_in, "up": up}
    check_options(os.fspath(path), options, spelling=CLI_SPELLING)  # errors in the words the user typed
    check_fps_option(fps_in, CLI_SPELLING["fps"])
    return load_motion(path, **options)

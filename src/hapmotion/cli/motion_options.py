"""The reader options every command that reads motion or tracks shares, from one definition: :func:`motion_options`
adds them to a click command, :func:`cli_reader_options` turns what the user typed into a
:class:`~hapmotion.motion_files.ReaderOptions`, :func:`read_motion` reads a motion file with them and
:func:`read_track` a track file with their ``--limit`` values."""

from __future__ import annotations

import functools
import os
from typing import Any, Callable, Iterable, Optional

import click

from ..limits import DEFAULT_LIMITS, InputLimits, parse_limit_assignments
from ..motion import Motion
from ..motion_files.options import ReaderOptions
from ..track import HapticTrack

MOTION_OPTION_NAMES = ("units", "scale", "skip_frames", "body_id", "fps_in", "up", "joint_map", "limits")
"""Parameter names :func:`motion_options` adds; they arrive in the command as one dict, ``motion_opts``, with
``None`` for every option not given (``limits`` too: a tuple of ``NAME=N`` texts only when given)."""

CLI_SPELLING = {"units": "--units", "scale": "--scale", "skip_frames": "--skip-frames", "body_id": "--body-id",
                "fps": "--fps-in", "up": "--up", "joint_map": "--joint-map", "limits": "--limit"}
"""Reader option -> the command-line option that sets it."""

UP_CHOICES = ("y", "z", "-y", "-z", "x", "-x")


limit_option = click.option(
    "--limit", "limits", multiple=True, metavar="NAME=N",
    help=f"Raise a size limit of the motion and track readers: {DEFAULT_LIMITS.help_text()}. Repeatable.")
"""The ``--limit NAME=N`` option alone, for commands that read tracks or patterns but no motion (``play``)."""


def motion_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Click decorator: add the reader options and hand them to the command as one keyword, ``motion_opts``.

    Use it under ``@click.command()`` (and with the command's other options)::

        @click.command()
        @click.argument("input")
        @motion_options
        def command(input, motion_opts):
            motion = read_motion(input, **motion_opts)

    Options: ``--units``, ``--scale``, ``--skip-frames``, ``--body-id``, ``--fps-in``, ``--up``, ``--joint-map``,
    ``--limit``.
    """

    @functools.wraps(f)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        opts = {name: kwargs.pop(name, None) for name in MOTION_OPTION_NAMES}
        opts["limits"] = opts["limits"] or None  # click gives () when --limit is not used: "not given"
        kwargs["motion_opts"] = opts
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
        click.option("--up", type=click.Choice(UP_CHOICES, case_sensitive=False), default=None,
                     help="Up axis of the input (BVH: detected from the motion by default; CSV, NPZ: y)."),
        click.option("--joint-map", type=click.Path(dir_okay=False), default=None, metavar="MAP.toml|MAP.json",
                     help="BVH: a file of '\"their joint\" = \"HAND_LEFT\"' lines naming joints the automatic "
                     "matching misses."),
        limit_option,
    ]
    for option in reversed(options):  # click lists params in decoration order, bottom first
        wrapper = option(wrapper)
    return wrapper


def cli_reader_options(*, units: Optional[str] = None, scale: Optional[float] = None,
                       skip_frames: Optional[int] = None, body_id: Optional[int] = None,
                       fps_in: Optional[float] = None, up: Optional[str] = None,
                       joint_map: Optional[str] = None, limits: Optional[Iterable[str]] = None) -> ReaderOptions:
    """The :class:`ReaderOptions` for what :func:`motion_options` gathered (``fps_in`` is the reader's ``fps``,
    each of ``limits`` a ``NAME=N`` text). Values are checked when a file is read, in the user's spelling."""
    return ReaderOptions(units=units, scale=scale, skip_frames=skip_frames, fps=fps_in, up=up, body_id=body_id,
                         joint_map=joint_map, limits=cli_limits(limits))


def cli_limits(limits: Optional[Iterable[str]] = None) -> InputLimits:
    """The :class:`InputLimits` for the ``--limit NAME=N`` texts the user gave (the defaults for the others)."""
    return DEFAULT_LIMITS.raised(parse_limit_assignments(list(limits or ())))


def read_motion(path: "str | os.PathLike[str]", **motion_opts: Any) -> Motion:
    """``hapmotion.load_motion`` with the options :func:`motion_options` gathered (by their CLI names).

    An option that does not apply to the format, or a bad value, raises :class:`~hapmotion.errors.UsageError`
    naming the option as the user typed it, which the CLI prints as one line. The reader's warnings (notes that
    start with "warning", such as weak evidence for the up axis) are printed on stderr, one line each, so that
    every command shows them, not only ``info``.
    """
    from ..motion_files import check_options, load_motion

    options = check_options(os.fspath(path), cli_reader_options(**motion_opts), spelling=CLI_SPELLING)
    motion = load_motion(path, options)
    for note in motion.meta.get("notes", []):
        if note.startswith("warning"):
            text = note.split(":", 1)[1].strip() if note.startswith("warning:") else note
            click.echo(f"warning: {os.fspath(path)}: {text}", err=True)
    return motion


def read_track(path: "str | os.PathLike[str]", **motion_opts: Any) -> HapticTrack:
    """``hapmotion.load_track`` within the ``--limit`` values :func:`motion_options` gathered (the other reader
    options are about motion files and do not apply to a saved track)."""
    from ..track_files import load_track

    return load_track(path, limits=cli_limits(motion_opts.get("limits")))

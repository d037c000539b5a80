"""The options commands share, from one definition: the preset, the mix rule, the cue list and the wearer's strength
and comfort limits of every command that renders (:class:`hapmotion.show.Show` holds what they choose), and the
options of the real-time sessions (``live``, ``play``)."""

from __future__ import annotations

import functools
from typing import Any, Callable, Optional

import click

from ..audio.params import MIX_RULES
from ..show.comfort import MAX_GAIN, Comfort
from ..renderer.params import DEFAULT_PRESET, PRESETS

PRESET_HELP = (f"Renderer preset: {', '.join(PRESETS)}. felt (default): calibrated for ERM vests, the wearer feels "
               "the performer move, on the mirrored side of the moving hand, more when the motion is faster and bigger; paper: the "
               "HapMotion paper's numbers; energy: energy-preserving split with the paper's intensity rule.")

preset_option = click.option("--preset", default=DEFAULT_PRESET, show_default=True, help=PRESET_HELP)

mix_rule_option = click.option(
    "--mix-rule", type=click.Choice(MIX_RULES), default=None,
    help="How music and motion mix (multimodal): duck (the music makes room where the motion is), paper (the "
         "paper's 2:3 weighted sum) or energy (weighted sum of squared intensities). Default: the preset's (paper "
         "for --preset paper, duck otherwise).")

cues_option = click.option(
    "--cues", type=click.Path(dir_okay=False), default=None, metavar="CUES",
    help="Cue list (text or JSON: time, pattern file, gain, side, devices): authored effects layered over the show "
         "(docs/playback.md).")

def split_values(values: tuple[str, ...]) -> tuple[str, ...]:
    """Repeated and comma-separated option values as one tuple."""
    return tuple(v.strip() for value in values for v in value.split(",") if v.strip())


def read_cues(path: Optional[str], motion_opts: Optional[dict] = None):
    """The ``--cues`` file as a :class:`~hapmotion.show.cues.CueList`, read within the command's ``--limit`` values
    (``None`` without ``--cues``)."""
    if path is None:
        return None
    from ..show.cues import load_cues
    from .motion_options import cli_limits

    return load_cues(path, limits=cli_limits((motion_opts or {}).get("limits")))


cue_port_option = click.option(
    "--cue-port", default=None, metavar="[HOST:]PORT",
    help="Also fire the cue list's named cues by OSC: /hapmotion/cue NAME [gain] on this UDP port (loopback unless "
         "HOST names an interface).")


def session_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Click decorator: the options of every command that runs a real-time session (``live``, ``play``): progress
    and summary (``show_stats``, ``stats_json``) and the bHaptics SDK2 credentials (``workspace_id``, ``api_key``)."""
    options = [
        click.option("--stats", "show_stats", is_flag=True, help="Print frame counts and latency every second."),
        click.option("--stats-json", type=click.Path(dir_okay=False), default=None,
                     help="Also write the final summary as JSON to this file."),
        click.option("--workspace-id", envvar="BHAPTICS_WORKSPACE_ID", default=None,
                     help="bHaptics SDK2 workspace (app) id for player-v3 [env BHAPTICS_WORKSPACE_ID]."),
        click.option("--api-key", envvar="BHAPTICS_API_KEY", default=None,
                     help="bHaptics SDK2 API key for player-v3 [env BHAPTICS_API_KEY]."),
    ]
    for option in reversed(options):
        f = option(f)
    return f


COMFORT_OPTION_NAMES = ("gain", "max_level", "max_duty", "duty_window")


def comfort_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Click decorator: the wearer's strength control and comfort limits, handed to the command as one
    :class:`~hapmotion.show.comfort.Comfort`, keyword ``comfort``."""

    @functools.wraps(f)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        gain, max_level, max_duty, window = (kwargs.pop(name) for name in COMFORT_OPTION_NAMES)
        kwargs["comfort"] = Comfort(gain=gain, max_level=max_level, max_duty=max_duty, window_s=window)
        return f(*args, **kwargs)

    # functools.wraps copied f's click params (a shared list); give the wrapper its own before adding ours.
    wrapper.__click_params__ = list(getattr(f, "__click_params__", []))  # type: ignore[attr-defined]
    options = [
        click.option("--gain", type=click.FloatRange(0.0, MAX_GAIN), default=1.0, show_default=True,
                     help="Strength: every intensity times this (like the bHaptics SDKs' intensity scale)."),
        click.option("--max-level", type=click.FloatRange(0.0, 100.0), default=100.0, show_default=True,
                     help="No motor is driven above this percent."),
        click.option("--max-duty", type=click.FloatRange(0.0, 1.0), default=1.0, show_default=True,
                     help="Each motor's average drive over --duty-window stays at or below this fraction of full "
                          "drive (1 = no limit)."),
        click.option("--duty-window", type=click.FloatRange(0.001, 3600.0), default=10.0, show_default=True,
                     metavar="SECONDS", help="Time constant of the average --max-duty watches."),
    ]
    for option in reversed(options):  # click lists params in decoration order, bottom first
        wrapper = option(wrapper)
    return wrapper

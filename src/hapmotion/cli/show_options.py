"""The options commands share, from one definition each: the show's options (every command that renders reads
them as one :class:`hapmotion.show.Show` from :func:`show_options`), the wearer's strength and comfort limits
(:func:`comfort_options`, one :class:`~hapmotion.show.comfort.Comfort`), and the options of the real-time
sessions (``live``, ``play``). Ranges come from the value objects that check them."""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Callable, Optional, Sequence

import click

from ..audio.mix import parse_mix_ratio
from ..audio.params import MIX_RULES
from ..errors import UsageError
from ..renderer.params import DEFAULT_PRESET, METHODS, PRESETS, Params
from ..show.comfort import COMFORT_RANGES, Comfort
from ..show.cues import CueList, load_cues
from ..show.settings import LENGTH_RULES, MODES, Show, check_fps
from .motion_options import cli_limits

PRESET_HELP = (f"Renderer preset: {', '.join(PRESETS)}. felt (default): calibrated for ERM vests, the wearer feels "
               "the performer move, on the mirrored side of the moving hand, more when the motion is faster and bigger; paper: the "
               "HapMotion paper's numbers; energy: energy-preserving split with the paper's intensity rule.")


def method_option(default: Optional[str] = "mst", help_suffix: str = "") -> Callable[..., Any]:
    """``--method`` (``None`` default: keep another's choice, as a seat keeps the show's)."""
    return click.option("--method", type=click.Choice(METHODS), default=default, show_default=default is not None,
                        help="Motion renderer: mst, the paper's motion salient triangle; baseline, the active hand "
                             "itself." + help_suffix)


def preset_option(default: Optional[str] = DEFAULT_PRESET, help_suffix: str = "") -> Callable[..., Any]:
    """``--preset`` (checked by :class:`Show`, which names the closest preset on a typo)."""
    return click.option("--preset", default=default, show_default=default is not None,
                        help=PRESET_HELP + help_suffix)


def check_preset(preset: Optional[str]) -> None:
    """``--preset`` checked as a show checks it (UsageError naming the option and the closest preset; None passes)."""
    if preset is not None:
        try:
            Show(preset=preset)
        except UsageError as exc:
            raise UsageError(f"--preset: {exc}") from None


mirror_option = click.option(
    "--mirror/--no-mirror", default=None,
    help="Mirror the performer left/right, as when facing them: the performer's right hand is felt on the "
         "wearer's left (default: the preset's, on). --no-mirror feels the performer's left on the wearer's left.")

mode_option = click.option(
    "--mode", type=click.Choice(MODES), default=None,
    help="Which channels: motion, audio (the music alone) or multimodal (both mixed). Default: multimodal with "
         "motion and --audio, audio with --audio alone, else motion.")

mix_rule_option = click.option(
    "--mix-rule", type=click.Choice(MIX_RULES), default=None,
    help="How music and motion mix (multimodal): duck (the music makes room where the motion is), paper (the "
         "paper's 2:3 weighted sum) or energy (weighted sum of squared intensities). Default: the preset's (paper "
         "for --preset paper, duck otherwise).")

cues_option = click.option(
    "--cues", type=click.Path(dir_okay=False), default=None, metavar="CUES",
    help="Cue list (text or JSON: time, pattern file, gain, side, devices): authored effects layered over the show "
         "(docs/playback.md).")

param_option = click.option(
    "--param", "params", multiple=True, metavar="NAME=VALUE",
    help="Override one renderer parameter (repeatable), e.g. --param release_alpha=0.2.")

layout_option = click.option(
    "--layout", "layout_file", type=click.Path(dir_okay=False, exists=True), default=None,
    help="Device layout JSON (default: X40 + two shoulder Tactosy).")

rig_option = click.option(
    "--rig", default=None, metavar="WEARABLES",
    help="The wearables played on, joined by '+': x40+tactosy-shoulders (the body chart itself), x40+tactosy, air, "
         "x16, pro, pro+tactosy, pro+gloves, ... or a wearable .json file (docs/wearables.md); player[://HOST:PORT] "
         "or player-v3[://HOST:PORT]: the devices that SDK1 or SDK2 Player reports connected [default: the "
         "layout's own devices].")

SHOW_OPTIONS: dict[str, Callable[..., Any]] = {
    "method": method_option(),
    "preset": preset_option(),
    "mirror": mirror_option,
    "param": param_option,
    "layout": layout_option,
    "rig": rig_option,
    "fps": click.option("--fps", type=float, default=None,
                        help="Render rate, frames per second (1..1000) [default: the motion's own rate; a live "
                             "stream's 60; 60 for the music alone]."),
    "audio": click.option("--audio", "audio_file", type=click.Path(dir_okay=False), default=None,
                          help="The show's music (WAV, FLAC, Ogg, MP3): its haptic channel is mixed with the motion "
                               "(multimodal) or played alone (--mode audio)."),
    "audio_offset": click.option("--audio-offset", type=float, default=0.0, show_default=True, metavar="SECONDS",
                                 help="Seconds the music starts after show time 0 (negative: the show starts that "
                                      "far into the song)."),
    "mode": mode_option,
    "mix": click.option("--mix", "mix_ratio", default="2:3", show_default=True, metavar="AUDIO:MOTION",
                        help="audio:motion weights of the multimodal mix (the paper's 2:3)."),
    "mix_rule": mix_rule_option,
    "length": click.option("--length", type=click.Choice(LENGTH_RULES), default="longer", show_default=True,
                           help="Track length with both inputs: as long as the longer one, or cut to the motion."),
    "cues": cues_option,
}
"""Every option of a :class:`Show`, in the order ``--help`` lists them; :func:`show_options` takes a subset."""

_KWARGS = {"method": "method", "preset": "preset", "mirror": "mirror", "param": "params", "layout": "layout_file",
           "rig": "rig", "fps": "fps", "audio": "audio_file", "audio_offset": "audio_offset", "mode": "mode", "mix": "mix_ratio",
           "mix_rule": "mix_rule", "length": "length", "cues": "cues"}


def show_options(*names: str, comfort: bool = True) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Click decorator: the :data:`SHOW_OPTIONS` named (all when none are), and the comfort options unless
    ``comfort`` is False, handed to the command as one validated :class:`Show`, keyword ``show``. Options a command
    does not take keep the :class:`Show` defaults. A ``--cues`` file is read within the command's ``--limit``
    values (put :func:`~hapmotion.cli.motion_options.motion_options` above this decorator)."""
    chosen = list(names or SHOW_OPTIONS)
    if "layout" in chosen and "rig" not in chosen:  # where a layout is chosen, the rig it plays on is too
        chosen.insert(chosen.index("layout") + 1, "rig")
    unknown = [n for n in chosen if n not in SHOW_OPTIONS]
    if unknown:
        raise ValueError(f"unknown show options {unknown}")

    def decorate(f: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(f)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            given = {name: kwargs.pop(_KWARGS[name]) for name in chosen}
            given["credentials"] = (kwargs.get("workspace_id"), kwargs.get("api_key"))  # --rig player-v3 asks with them
            limits = (kwargs.get("motion_opts") or {}).get("limits") or kwargs.get("limits")
            kwargs["show"] = _build_show(given, kwargs.pop("comfort", Comfort()), limits)
            return f(*args, **kwargs)

        wrapper.__click_params__ = list(getattr(f, "__click_params__", []))  # type: ignore[attr-defined]
        inner = comfort_options(wrapper) if comfort else wrapper
        for name in reversed(chosen):  # click lists params in decoration order, bottom first
            inner = SHOW_OPTIONS[name](inner)
        return inner

    return decorate


def _build_show(given: dict[str, Any], comfort: Comfort, limits: Optional[Sequence[str]]) -> Show:
    fields: dict[str, Any] = {"comfort": comfort}
    for name in ("method", "preset", "mirror", "mode", "mix_rule", "length"):
        if name in given:
            fields[name] = given[name]
    if given.get("fps") is not None:
        fields["fps"] = check_fps(given["fps"], "--fps")
    if "param" in given:
        fields["overrides"] = parse_param_overrides(given["param"])
    if "layout" in given:
        fields["layout"] = given["layout"]
    if "audio" in given:
        fields["audio"] = given["audio"]
    if "audio_offset" in given:
        fields["audio_offset_s"] = given["audio_offset"]
    if "mix" in given:
        fields["mix_ratio"] = parse_mix_ratio(given["mix"])
    if given.get("cues") is not None:
        fields["cues"] = load_cues(given["cues"], limits=cli_limits(limits))
    if given.get("audio") is None:
        music_only = [option for option, name, default in (("--mix", "mix", "2:3"), ("--mix-rule", "mix_rule", None),
                                                           ("--audio-offset", "audio_offset", 0.0))
                      if name in given and given[name] != default]
        if music_only:
            raise UsageError(f"{music_only[0]} sets how the music plays: give --audio SONG too")
    overrides = fields.get("overrides", {})
    if "mirror" in overrides and fields.get("mirror") is not None and overrides["mirror"] != fields["mirror"]:
        raise UsageError("--param mirror=... and --mirror/--no-mirror disagree: give one of them")
    check_preset(fields.get("preset"))
    show = Show(**fields)
    return with_rig(show, given.get("rig"), given.get("credentials", (None, None)))


def with_rig(show: Show, rig: Optional[str], credentials: tuple = (None, None)) -> Show:
    """``show`` played on the ``--rig`` wearables (None: as it is), combined by the preset's phantom split."""
    if rig is None:
        return show
    layout = show.load_layout()
    return show.replace(layout=layout.with_rig(rig_of(rig, layout, energy=show.params().phantom == "energy",
                                                      credentials=credentials)))


def rig_line(layout: Any) -> str:
    """What a start-up line says the rows are played on: ``--rig air``, or ``the layout's own devices (no --rig)``
    for a layout (a :class:`~hapmotion.layout.Layout`, a layout file or None) without a rig."""
    rig = getattr(layout, "rig", None)
    return f"--rig {rig.name}" if rig is not None else "the layout's own devices (no --rig)"


def undriven_line(layout: Any) -> Optional[str]:
    """One line naming the ``--rig`` wearables the body chart has no place for (a visor, feet: their motors stay at
    0 in whatever is rendered or played through the chart), or None when it reaches every wearable or there is no
    rig (docs/wearables.md, "What the show does not drive")."""
    rig = getattr(layout, "rig", None)
    gone = rig.undriven(layout) if rig is not None else ()
    if not gone:
        return None
    names = ", ".join(f"{name} ({', '.join(limbs)})" for name, limbs in gone)
    return (f"note: --rig {rig.name}: the body chart has no place for {names}, so the show leaves "
            f"{'its' if len(gone) == 1 else 'their'} motors at 0")


def rig_of(text: str, layout: Any, *, energy: bool, credentials: tuple = (None, None)) -> Any:
    """The :class:`~hapmotion.rig.Rig` a ``--rig`` value names: wearables joined by '+', or ``player[://HOST:PORT]``
    / ``player-v3[://HOST:PORT]`` (the devices that SDK1 or SDK2 Player reports connected, asked with the SDK2
    ``credentials`` ``(workspace id, API key)``; the rig is printed)."""
    from ..rig import parse_rig  # lazy: a rig's wearable files are read only when --rig is given

    if text.strip().startswith("player"):
        from ..live.player_check import rig_of_player  # lazy: asks the Player before the show

        text = rig_of_player(text.strip(), layout, workspace_id=credentials[0], api_key=credentials[1])
        click.echo(f"rig: {text} (the Player's connected devices)", err=True)
    return parse_rig(text, energy=energy)


def parse_param_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``("release_alpha=0.2", "phantom=energy")`` -> typed overrides for :class:`~hapmotion.renderer.Params`."""
    types = {f.name: f.type for f in dataclasses.fields(Params)}
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or key not in types:
            known = ", ".join(sorted(types))
            raise UsageError(f"--param {item!r}: expected NAME=VALUE with NAME one of: {known}")
        kind = types[key]
        try:
            if kind in ("bool", bool):
                if value.lower() not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError(value)
                out[key] = value.lower() in ("true", "1", "yes")
            elif kind in ("float", float):
                out[key] = float(value)
            else:
                out[key] = value
        except ValueError:
            raise UsageError(f"--param {item!r}: expected a {kind} value, found {value!r}") from None
    return out


def split_list(text: Optional[str], what: str, allowed: Sequence[str]) -> list[str]:
    """``"mst,baseline"`` -> ``["mst", "baseline"]``; UsageError for unknown or repeated names."""
    if not text:
        return []
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in allowed]
    if bad:
        raise UsageError(f"unknown {what} {', '.join(map(repr, bad))}; choose from {', '.join(allowed)}")
    if len(set(names)) != len(names):
        raise UsageError(f"{what} listed twice in {text!r}")
    return names

def split_values(values: tuple[str, ...]) -> tuple[str, ...]:
    """Repeated and comma-separated option values as one tuple."""
    return tuple(v.strip() for value in values for v in value.split(",") if v.strip())


def read_cues(path: Optional[str], limits: Optional[Sequence[str]] = None) -> Optional[CueList]:
    """The ``--cues`` file as a :class:`~hapmotion.show.cues.CueList`, read within the ``--limit NAME=N`` values
    given (``None`` without ``--cues``)."""
    return None if path is None else load_cues(path, limits=cli_limits(limits))


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
COMFORT_SPELLING = {"gain": "--gain", "max_level": "--max-level", "max_duty": "--max-duty", "window_s": "--duty-window"}
"""Each :class:`Comfort` field's option, for the one-line errors."""


def comfort_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Click decorator: the wearer's strength control and comfort limits, handed to the command as one
    :class:`~hapmotion.show.comfort.Comfort`, keyword ``comfort``."""

    @functools.wraps(f)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        gain, max_level, max_duty, window = (kwargs.pop(name) for name in COMFORT_OPTION_NAMES)
        try:
            kwargs["comfort"] = Comfort(gain=gain, max_level=max_level, max_duty=max_duty, window_s=window)
        except UsageError as exc:  # the field's name in the user's spelling: --gain, --max-level, ...
            text = str(exc)
            for field, option in COMFORT_SPELLING.items():
                text = text.replace(f"comfort {field} ", f"{option} ")
            raise UsageError(text) from None
        return f(*args, **kwargs)

    # functools.wraps copied f's click params (a shared list); give the wrapper its own before adding ours.
    wrapper.__click_params__ = list(getattr(f, "__click_params__", []))  # type: ignore[attr-defined]
    ranges = COMFORT_RANGES
    options = [
        click.option("--gain", type=click.FloatRange(*ranges["gain"]), default=1.0, show_default=True,
                     help="Strength: every intensity times this (like the bHaptics SDKs' intensity scale)."),
        click.option("--max-level", type=click.FloatRange(*ranges["max_level"]), default=100.0, show_default=True,
                     help="No motor is driven above this percent."),
        click.option("--max-duty", type=click.FloatRange(*ranges["max_duty"]), default=1.0, show_default=True,
                     help="Each motor's average drive over --duty-window stays at or below this fraction of full "
                          "drive (1 = no limit)."),
        click.option("--duty-window", type=click.FloatRange(*ranges["window_s"]), default=10.0, show_default=True,
                     metavar="SECONDS", help="Time constant of the average --max-duty watches."),
    ]
    for option in reversed(options):  # click lists params in decoration order, bottom first
        wrapper = option(wrapper)
    return wrapper

"""``hapmotion check``: is the Player there, which devices does it have, and are the motors where we think?

Two parts:

* :func:`probe_player` opens one connection to a bHaptics Player sink's address, sends what the sink sends first
  (SDK2: the auth) plus a turn-off request, and reads the Player's answer for a moment:

  - SDK1 (``/v2/feedbacks``) answers every request with a status object whose ``ConnectedPositions`` lists the
    connected devices by position name (``Vest`` for the whole X40, ``ForearmL``, ``ForearmR``, ``Head``,
    ``HandL`` ...) and ``ConnectedDeviceCount`` counts them (bHaptics' Python client reads exactly these two keys,
    github.com/bhaptics/tact-python ``bhaptics/better_haptic_player.py``; the community C# client bHapticsLib
    ``IsDeviceConnected`` looks a ``VestFront``/``VestBack`` query up as ``Vest``);
  - SDK2 (``/v3/feedback``) sends ``ServerDevices`` after the auth: a list of ``{position, deviceName, connected,
    battery, ...}`` (SDK2 position 0 the vest, 1/2 the left/right sleeve, as in the layout's ``sdk2_position``;
    :func:`hapmotion.bhaptics.sdk2.parse_server_devices` gives its sources).

* :func:`rig_of_player` asks either Player for the rig its connected devices make (``--rig player``, ``--rig
  player-v3``), and says in one line why when it cannot.

* With a rig (``--rig``), :func:`rig_pattern_steps` makes the pattern from the rig's wearable files instead, played
  straight to its motors (:meth:`hapmotion.rig.Rig.motor_layout`): every device of every wearable, gloves and
  visors too, labelled in the wearer's terms; :meth:`PlayerReport.rig` says which rig the Player's connected
  devices make.

* :func:`pattern_steps` and :func:`pattern_track` make the labelled test pattern from the layout's geometry alone
  (``Layout.positions``: x to the wearer's right, y up, z forward): for each device, all its motors, then its
  wearer's-left and wearer's-right column, then its top and bottom row (a shoulder sleeve, flat on the shoulder:
  its front and back edge). It is played like any track (:func:`hapmotion.live.playback.play`), each step's label
  printed as its first row goes out, and ends with the usual turn-off.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

import numpy as np
from websockets.asyncio.client import connect

from ..bhaptics.device_map import DeviceMap
from ..bhaptics.sdk2 import MAX_DEVICES, Sdk2Device, parse_server_devices, printable, rig_choice_of_devices, v3_stop_all
from ..errors import UsageError
from ..layout import CHART_BACK, CHART_FRONT, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT, Layout
from ..rig import Rig, choose_rig
from ..track import HapticTrack
from .kinds import build_sink
from .sinks import PlayerSdk1Sink, PlayerSdk2Sink, Sink
from .urls import parse_sink
from ..bhaptics.tick import PLAYER_TICK_FPS

CHECK_FPS = PLAYER_TICK_FPS
"""The test pattern is made on the Player's tick (50 rows per second)."""

_DEVICE_WORDS = {CHART_FRONT: "vest front", CHART_BACK: "vest back", CHART_SHOULDER_LEFT: "left shoulder sleeve",
                 CHART_SHOULDER_RIGHT: "right shoulder sleeve"}
MAX_LISTED = 20
"""Most devices (and notes) one report prints; the rest are counted in one line."""
MAX_POSITIONS = 64
"""Most ``ConnectedPositions`` an SDK1 status is read for (the Player has 10 positions)."""
_TOLERANCE_M = 0.01
"""Motors within 1 cm of a device's extreme coordinate belong to that edge's column or row."""


@dataclass(frozen=True)
class PatternStep:
    """One step of the test pattern: ``columns`` of the session row (its actuators) play together."""

    label: str
    device: str
    columns: tuple[int, ...]


def pattern_steps(layout: Layout) -> list[PatternStep]:
    """The test pattern's steps for ``layout``, in playing order (see the module docstring)."""
    positions = layout.positions()
    steps = []
    for d in layout.devices:
        cols = np.arange(d.offset, d.offset + d.size)
        p = positions[cols]
        name = f"{_DEVICE_WORDS.get(d.chart, d.name)} ({d.name})" if d.chart in _DEVICE_WORDS else d.name
        steps.append(PatternStep(f"{name}, all motors", d.name, tuple(int(c) for c in cols)))
        shoulder = d.chart in (CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT)

        def edge(axis: int, high: bool) -> tuple[int, ...]:
            values = p[:, axis]
            target = values.max() if high else values.min()
            return tuple(int(c) for c in cols[np.abs(values - target) <= _TOLERANCE_M])

        def spread(axis: int) -> bool:
            return float(np.ptp(p[:, axis])) > _TOLERANCE_M

        if spread(0):
            for high, side in ((False, "left"), (True, "right")):
                where = ""
                if shoulder:  # on a shoulder the wearer's left/right edges are the neck and arm ends
                    outer = abs(p[:, 0].max() if high else p[:, 0].min()) > abs(p[:, 0].mean())
                    where = " (over the arm)" if outer else " (nearer the neck)"
                what = "edge" if shoulder else "column"
                steps.append(PatternStep(f"{name}, wearer's {side} {what}{where}", d.name, edge(0, high)))
        if spread(1):
            steps += [PatternStep(f"{name}, top row", d.name, edge(1, True)),
                      PatternStep(f"{name}, bottom row", d.name, edge(1, False))]
        elif spread(2):
            what = "edge" if shoulder else "row"
            steps += [PatternStep(f"{name}, front {what}", d.name, edge(2, True)),
                      PatternStep(f"{name}, back {what}", d.name, edge(2, False))]
    return steps


_EDGES = {
    # limb: (low across, high across, low height, high height) in the wearer's terms
    "torso": ("wearer's left column", "wearer's right column", "top row (collar)", "bottom row"),
    "shoulder": ("front edge", "back edge", "edge nearer the neck", "edge over the arm"),
    "forearm": ("one edge (column 0)", "other edge", "row 0 (elbow end)", "last row (wrist end)"),
    "head": ("wearer's left end", "wearer's right end", "", ""),
    "foot": ("one end (motor 0)", "other end", "", ""),
    "hand": ("", "", "", ""),
}


def rig_pattern_steps(rig: Rig) -> list[PatternStep]:
    """The test pattern of a rig, on its motors (columns of ``rig.actuators``): per device of every wearable, all
    its motors, then its edges in the wearer's terms (a vest's left and right column and top and bottom row; a
    glove's thumb, little finger and wrist; a visor's left and right end)."""
    steps = []
    col = {id(m): k for k, m in enumerate(rig.motors)}
    for w, device, _, _ in rig.grids():
        motors = w.device_motors(device)
        m0 = motors[0]
        short = w.title.replace("bHaptics ", "").split(",")[0]
        where = {"torso": "back" if m0.face == "back" else "front", "head": "head"}.get(m0.limb, f"{m0.side} {m0.limb}")
        name = f"{short} {where} ({device})"
        steps.append(PatternStep(f"{name}, all motors", device, tuple(col[id(m)] for m in motors)))
        if device.startswith("Glove"):
            for idx, finger in ((0, "thumb"), (4, "little finger"), (5, "wrist")):
                steps.append(PatternStep(f"{name}, {finger}", device, (col[id(motors[idx])],)))
            continue
        words = _EDGES.get(m0.limb, ("", "", "", ""))
        for k, attr in enumerate(("across", "height")):
            values = np.array([getattr(m, attr) for m in motors])
            if np.ptp(values) <= 1e-6 or not words[2 * k]:
                continue
            for word, target in ((words[2 * k], values.min()), (words[2 * k + 1], values.max())):
                picked = tuple(col[id(m)] for m, v in zip(motors, values) if abs(v - target) <= 1e-6)
                steps.append(PatternStep(f"{name}, {word}", device, picked))
    return steps


def pattern_track(layout: Layout, steps: Sequence[PatternStep], *, step_s: float = 0.5, gap_s: float = 0.25,
               intensity: float = 60.0, lead_s: float = 0.2) -> tuple[HapticTrack, dict[int, str]]:
    """The test pattern as a track at :data:`CHECK_FPS` (``lead_s`` of silence, then each step ``step_s`` on at
    ``intensity`` 0..100 and ``gap_s`` off) and the row where each step starts -> its label."""
    on, off, lead = (max(1, int(round(s * CHECK_FPS))) for s in (step_s, gap_s, lead_s))
    rows = np.zeros((lead + len(steps) * (on + off), layout.n_actuators))
    marks = {}
    for k, step in enumerate(steps):
        start = lead + k * (on + off)
        rows[start:start + on, list(step.columns)] = intensity
        marks[start] = step.label
    track = HapticTrack(rows, CHECK_FPS, layout.actuators, layout.name, meta={"source": "test pattern"})
    return track, marks


@dataclass
class PlayerReport:
    """What a Player said about its devices.

    ``connected`` are the device names it reported as connected (SDK1 position names, or SDK2 device names);
    ``layout_devices`` maps each device of the session layout to True/False (None: the Player said nothing);
    ``sdk2_devices`` every device an SDK2 Player listed, connected or not.
    """

    sink: str
    reachable: bool
    error: str = ""
    answered: bool = False
    connected: list[str] = field(default_factory=list)
    layout_devices: dict[str, Optional[bool]] = field(default_factory=dict)
    details: list[str] = field(default_factory=list)
    sdk2_devices: Optional[list[Sdk2Device]] = None

    def lines(self) -> list[str]:
        if not self.reachable:
            return [f"{self.sink}: cannot connect ({self.error}); is the bHaptics Player running?"]
        if not self.answered:
            return [f"{self.sink}: connected, but the Player did not report its devices in time; the test pattern "
                    "plays anyway"]
        shown = self.connected[:MAX_LISTED]
        more = f" and {len(self.connected) - len(shown)} more" if len(self.connected) > len(shown) else ""
        out = [f"{self.sink}: {len(self.connected)} device(s) connected: {', '.join(shown) or 'none'}{more}"]
        out += [f"  {d}" for d in self.details]
        for device, ok in self.layout_devices.items():
            out.append(f"  {device}: " + ("connected" if ok else "NOT connected: its steps will not be felt"))
        rig, notes = self.rig_choice()
        out += [f"  {note} (a rig has one wearable per bHaptics position)" for note in notes[:MAX_LISTED]]
        if len(notes) > MAX_LISTED:
            out.append(f"  ({len(notes) - MAX_LISTED} more wearables left out)")
        if rig:
            out.append(f"  these devices make the rig {rig} (play, live and listen take it with --rig {rig})")
        else:
            out.append("  these devices make no rig hapmotion knows: name the wearables with --rig (docs/wearables.md)")
        return out

    def rig(self) -> Optional[str]:
        """The rig the connected devices make (``--rig`` text), or None: an SDK2 Player's devices by name, else by
        position (:func:`hapmotion.bhaptics.sdk2.rig_of_devices`); an SDK1 Player's by position
        (:func:`hapmotion.rig.choose_rig`). It always parses: one wearable per position."""
        return self.rig_choice()[0]

    def rig_choice(self) -> tuple[Optional[str], list[str]]:
        """:meth:`rig` and a note per wearable left out of it (its position taken by another)."""
        if not self.answered:
            return None, []
        if self.sdk2_devices is not None:
            return rig_choice_of_devices(self.sdk2_devices)
        return choose_rig((), self.connected)

    def read_sdk1_status(self, status: dict, layout: Layout) -> None:
        """Take in the Player's SDK1 status object (:func:`~hapmotion.bhaptics.sdk1.parse_v2_status`): its
        ``ConnectedPositions`` are the connected devices (the X40 is one position, ``Vest``, covering both panels).
        A status without that list leaves the report unanswered."""
        positions = status.get("ConnectedPositions")
        if not isinstance(positions, list):
            return
        self.answered = True
        self.connected = [printable(str(p)) for p in positions[:MAX_POSITIONS]]
        count = status.get("ConnectedDeviceCount")
        if isinstance(count, int) and not isinstance(count, bool) and 0 <= count < 1_000_000:
            self.details.append(f"ConnectedDeviceCount {count}")
        names = set(self.connected)
        for d in layout.devices:
            # the Player reports the X40 (both panels) as one position, "Vest"
            self.layout_devices[d.name] = d.name in names or (d.name in ("VestFront", "VestBack") and "Vest" in names)

    def read_sdk2_devices(self, devices: Any, layout: Layout) -> None:
        """Take in the Player's SDK2 ``ServerDevices`` list (:func:`~hapmotion.bhaptics.sdk2.parse_server_devices`):
        a layout device is connected when a connected device sits at its SDK2 position. Anything but a list leaves
        the report unanswered."""
        parsed = parse_server_devices(devices)
        if parsed is None:
            return
        self.answered = True
        self.sdk2_devices, skipped = parsed
        by_position: dict[int, bool] = {}
        for k, d in enumerate(self.sdk2_devices):
            if d.connected:
                self.connected.append(d.name)
            if k < MAX_LISTED:
                self.details.append(d.describe())
            if d.position is not None:
                by_position[d.position] = by_position.get(d.position, False) or d.connected
        if len(self.sdk2_devices) > MAX_LISTED:
            self.details.append(f"({len(self.sdk2_devices) - MAX_LISTED} more devices of the list not shown)")
        if skipped:
            self.details.append(f"{skipped} entr{'y' if skipped == 1 else 'ies'} of the list not understood or beyond "
                                f"its first {MAX_DEVICES} devices (skipped)")
        for dev in layout.devices:
            self.layout_devices[dev.name] = by_position.get(dev.sdk2_position, False)


def rig_of_player(spec: str, layout: Layout, timeout: float = 2.0, *, workspace_id: Optional[str] = None,
                  api_key: Optional[str] = None) -> str:
    """The rig the Player at ``spec`` says is connected, as ``--rig`` text: ``player[://HOST:PORT]`` asks the SDK1
    Player, ``player-v3[://HOST:PORT][?workspace_id=..&api_key=..]`` the SDK2 one (with ``workspace_id`` /
    ``api_key``, as its sink takes them). :class:`~hapmotion.errors.UsageError`, one line, when the Player cannot
    be asked, does not list its devices within ``timeout`` seconds, or lists none hapmotion knows."""
    try:
        ep = parse_sink(spec)
    except UsageError:
        ep = None
    if ep is None or ep.kind not in ("player", "player-v3"):
        raise UsageError(f"--rig {spec}: expected wearables joined by '+', or player[://HOST:PORT] / "
                         "player-v3[://HOST:PORT] to take the rig from the bHaptics Player's connected devices")
    sink = build_sink(ep, dmap=DeviceMap.from_layout(layout), layout_name=layout.name, fps=CHECK_FPS,
                      workspace_id=workspace_id, api_key=api_key)
    report = asyncio.run(probe_player(sink, layout, timeout))
    instead = "name the wearables instead, e.g. --rig x40+tactosy"
    if report is None or not report.reachable:
        why = report.error if report else "not a Player"
        raise UsageError(f"--rig {spec}: cannot ask the Player for its devices ({why}); is the bHaptics Player "
                         f"running? Or {instead}")
    if not report.answered:
        why = f" ({report.error})" if report.error else ""
        raise UsageError(f"--rig {spec}: the Player did not list its devices within {timeout:g} s{why}; {instead}")
    rig = report.rig()
    if rig is None:
        if report.sdk2_devices:
            listed = "; ".join(d.describe() for d in report.sdk2_devices)
        else:
            listed = ", ".join(report.connected) or "no device"
        raise UsageError(f"--rig {spec}: the Player reports no connected device hapmotion knows ({listed}); {instead}")
    return rig


async def probe_player(sink: Sink, layout: Layout, timeout: float = 2.0) -> Optional[PlayerReport]:
    """Ask the Player behind ``sink`` which devices it has (None for sinks that are not a Player)."""
    if not isinstance(sink, (PlayerSdk1Sink, PlayerSdk2Sink)):
        return None
    report = PlayerReport(sink.name, reachable=False)
    kwargs: dict[str, Any] = dict(open_timeout=timeout, close_timeout=0.5, compression=None, ping_interval=None)
    if sink.ssl is not None:
        kwargs["ssl"] = sink.ssl
    try:
        ws = await connect(sink.url, **kwargs)
    except Exception as exc:  # refused, TLS, HTTP, timeout: the Player is not there
        report.error = str(exc) or exc.__class__.__name__
        return report
    report.reachable = True
    try:
        # SDK1 answers requests only, so it gets the sink's turn-off; SDK2 lists its devices after the auth, so a
        # stop-all is enough and no dots go to positions it may not have
        off = sink.off_messages() if isinstance(sink, PlayerSdk1Sink) else [v3_stop_all()]
        for message in sink.hello_messages() + off:
            await ws.send(message)
        loop = asyncio.get_running_loop()
        end = loop.time() + timeout
        while not report.answered and loop.time() < end:
            try:
                message = await asyncio.wait_for(ws.recv(), end - loop.time())
            except asyncio.TimeoutError:
                break
            sink.on_message(message)
            if isinstance(sink, PlayerSdk1Sink) and sink.status is not None:
                report.read_sdk1_status(sink.status, layout)
            elif isinstance(sink, PlayerSdk2Sink) and "ServerDevices" in sink.server_messages:
                report.read_sdk2_devices(sink.server_messages["ServerDevices"], layout)
    except Exception as exc:  # the connection dropped while asking: report what is known
        report.error = str(exc) or exc.__class__.__name__
    finally:
        await ws.close()
    return report

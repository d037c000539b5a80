"""Build the self-contained HTML viewer page.

One file, no network at view time: the template, style and script come from ``viewer/assets/`` and are inlined; the
recording, the rendered tracks and the music are embedded as packed blobs (:mod:`hapmotion.viewer.packing`). The
page either plays what it holds or, with a live address (``live_url`` or ``?live=ws://...`` in the page URL),
shows a running ``hapmotion live`` WebSocket broadcast (message schema: docs/CONTRACTS.md).

Page data (the JSON in ``<script id="hm-data">``)::

    format, version, title, footer [str], colors [101 CSS colours], bright_from, scale_tops,
    actuators [N ids], joints [32 names], bones [[parent, child]],
    devices [{name, rows, cols, place, title, subtitle, left, right, top, bottom, labels? [a name per cell]}]
      (every device the page may draw: the script draws those whose ids its track or live stream has),
    motion: null | {fps, n_frames, joints [present joint indices], floor_y, positions blob (T, J, 3) int16 mm},
    energy_units,
    tracks: [{key, label, method, preset, mode, mirror, fps, n_frames, intensities blob (T, N) uint8,
              debug {dynamic_point, hit_point, target_point: (T, 3) int16 mm (-32768 = none), active (T,) uint8
                     bit 0 left hand bit 1 right hand, level (T,) uint8 x0.05, chart (T,) int8, distance (T,) uint16 mm,
                     triangle (T, 3) int8 joint indices, motion_energy (T,) uint16 scaled to its peak}, energy_note}],
    audio: null | {name, mime, offset_s, duration_s (track time the audio ends), waveform blob (T, 2) int8 (x 1/127)
                   on the track timeline, waveform_fps, onsets [s, track timeline], data blob (the audio file's bytes)},
    live: null | {url}
"""

from __future__ import annotations

import html
import json
import mimetypes
import re
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from .. import __version__
from ..audio.analysis import analyze_file
from ..errors import InputError, UsageError
from ..layout import CHART_NAMES, load_layout
from ..skeleton.joints import BONES, JOINTS
from ..motion import Motion
from ..track import HapticTrack
from ..filesafety import atomic_path
from . import packing
from .bodymap import BODY_ORDER, BODY_ROW, PANEL_TEXT, hand_actuators, rig_panels, with_hands
from .colors import SCALE_TOPS, bright_from, page_colors
from .curves import ENERGY_UNITS, track_motion_energy, triangle_vertices

AUDIO_MIME = {".ogg": "audio/ogg", ".oga": "audio/ogg", ".opus": "audio/ogg", ".mp3": "audio/mpeg", ".wav": "audio/wav",
              ".flac": "audio/flac", ".m4a": "audio/mp4", ".aac": "audio/aac", ".webm": "audio/webm"}


@dataclass
class AudioPart:
    """The music of a page: the file's bytes (played by the browser) and its analysis (drawn on the timeline).

    Times follow :class:`hapmotion.audio.analysis.AudioAnalysis`: audio time ``a`` plays at track time ``a + offset_s``;
    ``waveform`` is ``(T, 2)`` min/max of the mono mix per frame (-1..1) at ``waveform_fps`` on the track timeline;
    ``onsets`` are seconds on the track timeline; ``duration_s`` is the track time at which the audio ends.
    """

    path: Path
    data: bytes
    mime: str
    waveform: np.ndarray
    waveform_fps: float
    onsets: np.ndarray
    offset_s: float
    duration_s: float
    name: str = ""


def load_audio_part(path: "str | os.PathLike[str]", *, fps: float = 60.0, offset_s: float = 0.0,
                    until_s: "float | None" = None) -> AudioPart:
    """Read and analyse an audio file for the page (analysis by :func:`hapmotion.audio.analyze_file`).

    ``until_s`` (track time, seconds) ends the music there on the page, when the show was rendered shorter than
    the music (length rule ``motion``): the page then lasts as long as the haptics, and the waveform and onsets
    stop with it."""
    p = Path(path)
    an = analyze_file(p, fps=fps, offset_s=offset_s)
    try:
        data = p.read_bytes()
    except OSError as err:
        raise InputError(p, None, f"cannot read the audio file ({err.strerror})") from None
    mime = AUDIO_MIME.get(p.suffix.lower()) or mimetypes.guess_type(p.name)[0] or "application/octet-stream"
    waveform = np.asarray(an.waveform, dtype=np.float64)
    onsets = np.asarray(an.onset_times, dtype=np.float64)
    end = float(an.duration_s)
    if until_s is not None and until_s < end:
        end = max(0.0, float(until_s))
        waveform = waveform[:int(np.ceil(end * an.fps))]
        onsets = onsets[onsets < end]
    return AudioPart(path=p, data=data, mime=mime, waveform=waveform, waveform_fps=float(an.fps), onsets=onsets,
                     offset_s=float(offset_s), duration_s=end, name=p.name)


@dataclass
class PageInfo:
    """What was written: the page's size and what it holds (for the CLI's summary line and the benchmark)."""

    path: Path
    n_bytes: int
    n_tracks: int
    n_frames: int
    duration_s: float
    blob_bytes: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------- data assembly
def _name_parts(track: HapticTrack) -> list[str]:
    """Method, preset and (unless plain motion) mode of a track, as far as its meta says."""
    parts = [str(track.meta.get(k)) for k in ("method", "preset") if track.meta.get(k)]
    mode = track.meta.get("mode")
    if mode and mode != "motion":
        parts.append(str(mode))
    return parts


def track_key(track: HapticTrack) -> str:
    """Short id of a track for the page's switch and its ``?track=`` URL option, e.g. ``mst-paper``."""
    return "-".join(_name_parts(track)) or "track"


def track_label(track: HapticTrack) -> str:
    """What the page's switch shows, e.g. ``mst · paper · multimodal``."""
    return " \u00b7 ".join(_name_parts(track)) or "track"


def _device_panels(track: HapticTrack) -> list[dict]:
    """Grid and labels of each device the page may draw, in body order (the script draws those its track or live
    stream has). With the body chart come its hand places as two gloves (a rig with gloves: a recording of it, or a
    live stream, which may come to any page by ``?live=``)."""
    panels = rig_panels(track.layout, track.actuators)
    if panels:  # rendered on a rig: its wearables, as their files place them
        return panels
    try:
        layout = load_layout() if track.layout in ("x40_shoulders", "", None) else load_layout(track.layout)
    except (InputError, OSError):
        layout = None
    out = []
    ids, body = tuple(track.actuators), tuple(layout.actuators) if layout is not None else ()
    if layout is not None and ids[:len(body)] == body and ids[len(body):] in ((), hand_actuators()):
        # In body order (bodymap.BODY_ORDER), each with the group it joins on the page ("front" row or "back").
        for d in sorted(layout.devices, key=lambda d: BODY_ORDER.index(d.chart)):
            text = PANEL_TEXT.get(CHART_NAMES[d.chart], {})
            out.append(dict(name=d.name, rows=d.rows, cols=d.cols, place=BODY_ROW[d.chart],
                            **{k: text.get(k, "") for k in ("title", "subtitle", "left", "right", "top", "bottom")}))
            if not text:
                out[-1]["title"] = d.name
        return with_hands(out)
    # A layout the package does not know: one row per device, ids as given.
    for name in track.devices():
        n = len(track.device_columns(name))
        out.append(dict(name=name, rows=1, cols=n, title=name, subtitle="", left="", right="", top="", bottom=""))
    return out


class _Blobs:
    """Collects blobs, numbering their ``<script>`` ids."""

    def __init__(self) -> None:
        self.items: list[tuple[str, packing.Blob]] = []
        self.sizes: dict[str, int] = {}

    def add(self, name: str, blob: packing.Blob) -> dict:
        bid = f"hm-blob-{len(self.items)}"
        self.items.append((bid, blob))
        self.sizes[name] = self.sizes.get(name, 0) + blob.n_bytes
        return dict(blob.meta, id=bid)


def _track_data(track: HapticTrack, motion: Motion | None, blobs: _Blobs) -> dict:
    n = track.n_frames
    dbg = track.debug or {}
    debug: dict[str, dict] = {}
    for key in ("dynamic_point", "hit_point", "target_point"):
        pts = dbg.get(key)
        if pts is not None and np.shape(pts) == (n, 3):
            debug[key] = blobs.add(key, packing.pack_positions(pts))
    active = dbg.get("active")
    if active is not None and len(active) == n:
        act = np.asarray(active).astype(bool)
        debug["active"] = blobs.add("active", packing.pack(act[:, 0] * 1 + act[:, 1] * 2, "uint8"))
        if motion is not None and track.meta.get("method", "mst") == "mst" and motion.n_frames >= 1:
            debug["triangle"] = blobs.add("triangle", packing.pack(triangle_vertices(act, motion), "int8"))
    # key: (step of one stored integer, stored type, value of a non-finite entry)
    for key, (step, dtype, fill) in {"level": (0.05, "uint8", 0.0), "chart": (1.0, "int8", -1.0),
                                     "distance": (0.001, "uint16", 0.0)}.items():
        values = dbg.get(key)
        if values is not None and len(values) == n:
            stored = packing.quantise(values, step, dtype, fill=fill)
            debug[key] = blobs.add(key, packing.pack(stored, dtype, scale=step))
    energy, why = track_motion_energy(track)
    if energy is not None:
        debug["motion_energy"] = blobs.add("motion_energy", packing.pack_unit(energy))
    mirror = track.meta.get("mirror")
    return dict(key=track_key(track), label=track_label(track), method=track.meta.get("method"),
                preset=track.meta.get("preset"), mode=track.meta.get("mode"),
                mirror=None if mirror is None else bool(mirror), fps=track.fps, n_frames=n,
                intensities=blobs.add("intensities", packing.pack_intensities(track.intensities)), debug=debug,
                energy_note=None if energy is not None else why)


def _motion_data(motion: Motion, blobs: _Blobs) -> dict:
    present = np.flatnonzero(motion.present)
    pos = motion.positions[:, present, :]
    lowest = np.nanmin(pos[:, :, 1], axis=1)
    floor = float(np.nanpercentile(lowest, 1)) if np.isfinite(lowest).any() else 0.0
    return dict(fps=motion.fps, n_frames=motion.n_frames, joints=[int(j) for j in present], floor_y=round(floor, 3),
                positions=blobs.add("skeleton", packing.pack_positions(pos)))


def _audio_data(audio: AudioPart, blobs: _Blobs) -> dict:
    wave = packing.quantise(np.clip(audio.waveform, -1.0, 1.0), 1.0 / 127.0, "int8")
    raw = np.frombuffer(audio.data, dtype=np.uint8)
    return dict(name=audio.name, mime=audio.mime, offset_s=audio.offset_s, duration_s=audio.duration_s,
                waveform=blobs.add("waveform", packing.pack(wave, "int8", scale=1.0 / 127.0)),
                waveform_fps=audio.waveform_fps, onsets=[round(float(t), 4) for t in audio.onsets if np.isfinite(t)],
                data=blobs.add("audio", packing.pack(raw, "uint8", level=1)))


def page_data(
    tracks: Sequence[HapticTrack],
    motion: Motion | None = None,
    *,
    audio: AudioPart | None = None,
    live_url: str | None = None,
    title: str = "",
    footer: Iterable[str] = (),
) -> tuple[dict, list[tuple[str, packing.Blob]], dict]:
    """The page's JSON data, its blobs ``[(element id, Blob)]`` and the packed size of each kind of data.

    Parameters
    ----------
    tracks:
        Tracks to show (same actuators); the page offers a switch when there are several. May be empty with
        ``live_url``.
    motion:
        The recording the tracks were rendered from (skeleton, triangle); ``None`` for a saved track.
    audio:
        Music to embed, play and draw (:func:`load_audio_part`).
    live_url:
        ``ws://`` address of a ``hapmotion live`` broadcast: the page opens in live mode.
    title, footer:
        Text shown on the page (footer lines: sources, credits).
    """
    if not tracks and not live_url:
        raise UsageError("a viewer page needs at least one track or a live address")
    ref = tracks[0] if tracks else None
    for t in tracks[1:]:
        if tuple(t.actuators) != tuple(ref.actuators):
            raise UsageError("all tracks of one page must use the same actuators")
    keys = [track_key(t) for t in tracks]
    if len(set(keys)) != len(keys):
        raise UsageError(f"two tracks of the page would have the same name: {', '.join(keys)}")
    if ref is None:
        layout = load_layout()
        ref = HapticTrack(np.zeros((0, layout.n_actuators)), 60.0, layout.actuators, layout=layout.name)
    blobs = _Blobs()
    colors = page_colors()
    data = dict(
        format="hapmotion-viewer", version=1, generator=f"hapmotion {__version__}", title=title, footer=list(footer),
        colors=colors, bright_from=bright_from(colors), scale_tops=list(SCALE_TOPS),
        actuators=list(ref.actuators), joints=list(JOINTS),
        bones=[list(b) for b in BONES], devices=_device_panels(ref),
        motion=_motion_data(motion, blobs) if motion is not None else None, energy_units=ENERGY_UNITS,
        tracks=[_track_data(t, motion, blobs) for t in tracks],
        audio=_audio_data(audio, blobs) if audio is not None else None,
        live=dict(url=live_url) if live_url else None,
    )
    return data, blobs.items, blobs.sizes


def _asset(name: str) -> str:
    return resources.files("hapmotion.viewer").joinpath("assets", name).read_text(encoding="utf-8")


def _script_json(data: dict) -> str:
    """JSON safe inside ``<script>``: no ``</`` or ``<!--`` can end the element early."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def build_page(tracks: Sequence[HapticTrack], motion: Motion | None = None, **options) -> tuple[list[str], dict]:
    """The page as a list of text pieces (joined, they are the HTML; kept apart to spare copies of large pages),
    and the packed size of each kind of data in bytes. ``options`` are those of :func:`page_data`."""
    data, blobs, sizes = page_data(tracks, motion, **options)
    template = _asset("viewer.html")
    fills = {
        "@@TITLE@@": [html.escape((data["title"] + " - " if data["title"] else "") + "hapmotion viewer")],
        "@@CSS@@": [_asset("viewer.css")],
        "@@DATA@@": [_script_json(data)],
        "@@BLOBS@@": [piece for bid, blob in blobs
                      for piece in (f'<script type="application/octet-stream" id="{bid}">', blob.text, "</script>\n")],
        "@@JS@@": [_asset("viewer.js")],
    }
    pieces: list[str] = []
    rest = template
    while True:
        at = [(rest.find(m), m) for m in fills if m in rest]
        if not at:
            pieces.append(rest)
            break
        pos, marker = min(at)
        pieces.append(rest[:pos])
        pieces.extend(fills[marker])
        rest = rest[pos + len(marker):]
    return pieces, sizes


def write_page(path: "str | os.PathLike[str]", tracks: Sequence[HapticTrack], motion: Motion | None = None,
               **options) -> PageInfo:
    """Write the viewer page atomically (temporary file in the same folder, then rename).

    ``options`` are those of :func:`page_data`: ``audio`` (:class:`AudioPart`), ``live_url``, ``title``, ``footer``.
    """
    out = Path(path)
    pieces, sizes = build_page(tracks, motion, **options)
    # Every fact is worked out before the write, so a failure leaves no page at all (not a page and an error).
    audio = options.get("audio")
    n_frames = max([t.n_frames for t in tracks] + [motion.n_frames if motion is not None else 0])
    # audio.duration_s is already the track time at which the music ends (offset included): add nothing to it.
    duration = max([t.duration for t in tracks] + [motion.duration if motion is not None else 0.0]
                   + [audio.duration_s if audio is not None else 0.0])
    with atomic_path(out) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            for piece in pieces:
                fh.write(piece)
        n_bytes = tmp.stat().st_size
    return PageInfo(path=out, n_bytes=n_bytes, n_tracks=len(tracks), n_frames=n_frames,
                    duration_s=float(duration), blob_bytes=sizes)


_DATA_RE = re.compile(r'<script type="application/json" id="hm-data">(.*?)</script>', re.S)
_BLOB_RE = re.compile(r'<script type="application/octet-stream" id="(hm-blob-\d+)">(.*?)</script>', re.S)


def read_page(path: "str | os.PathLike[str]") -> tuple[dict, dict[str, np.ndarray]]:
    """The data of a page written by :func:`write_page`: its JSON and every blob decoded to its stored integers
    (keyed by element id; multiply by the blob's ``scale`` for physical values). For tests and tools."""
    text = Path(path).read_text(encoding="utf-8")
    m = _DATA_RE.search(text)
    if m is None:
        raise InputError(path, None, "expected a hapmotion viewer page, found no page data")
    data = json.loads(m.group(1))
    metas: dict[str, dict] = {}

    def collect(node) -> None:
        if isinstance(node, dict):
            if "id" in node and "dtype" in node:
                metas[node["id"]] = node
            for v in node.values():
                collect(v)
        elif isinstance(node, list):
            for v in node:
                collect(v)

    collect(data)
    blobs = {bid: packing.decode_blob(metas[bid], body) for bid, body in _BLOB_RE.findall(text) if bid in metas}
    return data, blobs

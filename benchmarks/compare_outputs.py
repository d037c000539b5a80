"""Before/after comparison of every rendered array: capture them at one commit, compare two captures.

::

    PYTHONPATH=src python benchmarks/compare_outputs.py capture OUT.npz [--quick]
    PYTHONPATH=src python benchmarks/compare_outputs.py compare A.npz B.npz

``capture`` renders the bundled clips (examples/60_12_scaled.bvh and examples/gBR_sBM_cAll_d04_mBR0_ch03.pkl with
examples/vibe_ace.ogg) and one clip of ../shared/data (motion/dataset-2_wave-both-hands_normal_001.bvh with
audio/lets_go_fishin.ogg) through every entry point and stores each array under a descriptive key:

* ``offline/...``: :func:`offline_track` for every method x preset x mode x mix rule (the rule only where music
  plays), plus a cue list, a non-neutral comfort (gain 0.8, max duty 0.5) and both, per method x mode; and the music
  alone (no motion) per preset x rule. Per track: ``intensities``, ``fps``, ``actuators`` and every
  ``debug/<name>`` array.
* ``live/...``: :func:`live_rows`, the same shows through the live engine for the clips of ``LIVE_CLIPS``: every
  method x mode x preset (x mix rule with music; the music alone once, it has no renderer), plus cues + comfort per
  method x mode. ``rows`` are the rows of kind ``"frame"`` the engine emitted (in emission order) and
  ``t`` their show times.
* ``seat/...``: :func:`seat_rows`, one audience seat (a real nats-server) playing a motion-only show and a
  multimodal show (the latter with a seat comfort), ``rows``/``t`` of kind ``"frame"`` as the seat's sink got them
  (after the seat's stage).
* ``play/...``: :func:`play_rows`, ``hapmotion.live.playback.play`` of a saved track, of a bHaptics Designer
  pattern and of that pattern with a cue list, ``rows``/``t`` of kind ``"frame"``.

What is compared, and how it is made deterministic
--------------------------------------------------
Live, seat and play runs are subject to timing (newest-wins slots, late wake-ups, stall fades). The capture never
compares wall-clock facts and never compares fade/turn-off rows (kind ``"fade"``/``"off"``, made by the stall
watchdog on its own clock): only the rendered rows (kind ``"frame"``) and their show times.

* live and play: the source is a *lockstep* source: frame ``k`` (show time ``k / fps``) is submitted only after the
  engine delivered frame ``k - 1`` to the recording sink, so every frame is rendered exactly once, in order, as
  fast as the machine goes (``render_cap`` raised so the engine's flood guard never holds a frame; ``stall`` set to a
  minute so a slow machine can never fade the show to "off", which would reset the renderer). The replay source
  of ``live`` and the clock source of ``live --mode audio`` and ``play`` are swapped for lockstep versions of the
  same classes (same show times, same body model and frame rate as the real ones).
* seat: the venue publishes with a lockstep replay paced at real time (the seat's media clock expects live
  pace); the seat runs unchanged (its own media clock, delay, stale check). The run counts only if the seat
  rendered every published frame exactly once and in order (show times ``k / fps`` for ``k = 0..N-1``); otherwise it
  is run again (up to 4 times) and the capture fails if no run is complete. With every frame rendered, the seat's
  rows depend on nothing but the show.

``compare`` checks the key sets and ``np.array_equal`` on every key (same shape and dtype required, except the
width of string arrays; NaN equals NaN in float arrays), prints one line per difference with the max abs difference and
ends with ``N arrays identical, M differ, K missing``; exit status 1 on any difference.

The package API is called only from the functions of the first section (one per entry point); adapt those after a
restructuring, the rest of the script stays as it is.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Iterator, Optional

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "src" / "hapmotion" / "examples"
SHARED = ROOT.parent / "shared" / "data"  # ../shared beside the checkout, as CI has it

# A show is described here by a plain dict (the "spec"): method, preset, mode, audio, mix_rule, cues (path or None),
# comfort ((gain, max_duty) or None). Only the adapters below turn it into package objects.

# ==================================================================================================== API adapters
# Everything that touches hapmotion lives in this section.

LIVE_STALL_MS = 60_000.0   # a slow machine never fades a lockstep show to "off" (which resets the renderer)
RENDER_CAP = 1e6           # the engine's flood guard never holds back a lockstep frame


def api_choices() -> dict[str, tuple]:
    """The renderer methods, presets, study-2 modes and mix rules, and the default preset."""
    from hapmotion.audio.params import MIX_RULES
    from hapmotion.renderer.params import DEFAULT_PRESET, METHODS, PRESETS
    from hapmotion.show import MODES

    return {"methods": tuple(METHODS), "presets": tuple(PRESETS), "modes": tuple(MODES),
            "rules": tuple(MIX_RULES), "default_preset": (DEFAULT_PRESET,)}


def load_motion(path: Path, first: int = 0, stop: Optional[int] = None) -> Any:
    """A recording (``hapmotion.load_motion``), optionally frames ``first:stop`` (``Motion.slice``)."""
    import hapmotion

    motion = hapmotion.load_motion(path)
    if first or stop is not None:
        motion = motion.slice(first, motion.n_frames if stop is None else stop)
    return motion


def make_show(spec: dict[str, Any]) -> Any:
    """``hapmotion.show.Show`` of a spec."""
    from hapmotion.show.comfort import Comfort
    from hapmotion.show.cues import load_cues
    from hapmotion.show import Show

    comfort = Comfort() if spec.get("comfort") is None else Comfort(gain=spec["comfort"][0],
                                                                    max_duty=spec["comfort"][1])
    cues = load_cues(spec["cues"]) if spec.get("cues") else None
    return Show(method=spec.get("method", "mst"), preset=spec["preset"], mode=spec.get("mode"),
                audio=spec.get("audio"), mix_rule=spec.get("mix_rule"), comfort=comfort, cues=cues)


def offline_track(show: dict[str, Any], motion: Any) -> dict[str, np.ndarray]:
    """``hapmotion.show.render_show(Show, motion)`` (``motion`` None: the music alone) as arrays: ``intensities``,
    ``fps``, ``actuators`` and ``debug/<name>``."""
    from hapmotion.show import render_show

    track = render_show(make_show(show), motion)
    out = {"intensities": np.asarray(track.intensities), "fps": np.asarray(float(track.fps)),
           "actuators": np.asarray([str(a) for a in track.actuators])}
    for name, arr in track.debug.items():
        out[f"debug/{name}"] = np.asarray(arr)
    return out


def save_track_file(show: dict[str, Any], motion: Any, path: Path) -> Path:
    """Render offline and save with ``hapmotion.track_files.save_track`` (the file ``play`` reads back)."""
    from hapmotion.show import render_show
    from hapmotion.track_files import save_track

    save_track(render_show(make_show(show), motion), path)
    return path


def _recording_sink() -> Any:
    """A ``hapmotion.live.sinks.Sink`` keeping every frame offered (no slot, nothing skipped); ``tick`` is set when a
    rendered frame arrives."""
    from hapmotion.live.sinks import Sink

    class RecordingSink(Sink):
        def __init__(self, *_: Any):
            super().__init__("compare-outputs")
            self.frames: list[tuple[float, np.ndarray, str]] = []
            self.rendered = 0
            self.tick = asyncio.Event()

        def offer(self, frame: Any) -> None:
            self.frames.append((float(frame.t), np.array(frame.row, dtype=np.float64), frame.kind))
            if frame.kind == "frame":
                self.rendered += 1
                self.tick.set()

        async def run(self) -> None:
            await asyncio.Event().wait()

        def result(self) -> dict[str, np.ndarray]:
            got = [(t, r) for t, r, k in self.frames if k == "frame"]
            return {"t": np.array([t for t, _ in got], dtype=np.float64),
                    "rows": np.array([r for _, r in got], dtype=np.float64).reshape(len(got), -1)}

    return RecordingSink()


async def _submit_and_wait(engine: Any, sink: Any, frame: Any) -> None:
    """Hand ``frame`` to the engine, then wait until the engine delivered a rendered row to ``sink`` (or counted
    the frame as empty/late: then it is not rendered in any run either)."""
    before, dropped = sink.rendered, (engine.stats.empty, engine.stats.late)
    engine.submit(frame)
    deadline = time.perf_counter() + 30.0
    while sink.rendered == before and (engine.stats.empty, engine.stats.late) == dropped:
        if time.perf_counter() > deadline:
            raise RuntimeError("the engine did not render a lockstep frame within 30 s")
        try:
            await asyncio.wait_for(sink.tick.wait(), 0.05)
        except asyncio.TimeoutError:
            pass
        sink.tick.clear()


def _lockstep_replay(motion: Any, sink: Any, *, pace: bool = False, go: Optional[asyncio.Event] = None) -> Any:
    """A ``ReplaySource`` (so ``live`` takes the recording's rate and body model from it) that submits frame ``k``
    (seq ``k``, show time ``k / fps``, as the real replay stamps it) once frame ``k - 1`` was delivered; ``pace``:
    also not before ``k / fps`` seconds after the start (a live pace for an audience); ``go``: starts when set."""
    from hapmotion.live import ReplaySource, SkeletonFrame

    class LockstepReplay(ReplaySource):
        async def run(self) -> None:
            if go is not None:
                await go.wait()
            m = self.motion
            start = time.perf_counter()
            for i in range(m.n_frames):
                if pace:
                    await asyncio.sleep(max(0.0, start + i / m.fps - time.perf_counter()))
                await _submit_and_wait(self.engine, sink, SkeletonFrame(
                    m.positions[i].copy(), i, i / m.fps, time.perf_counter(), show_t=i / m.fps))

    return LockstepReplay(motion, path="compare-outputs")


def _lockstep_ticks(base: Any, sink: Any) -> Any:
    """A subclass of a tick source (``ClockSource(fps, duration_s, ...)``, ``TrackSource(n_rows, fps, ...)``) whose
    ``run`` submits tick ``k`` (show time ``k / fps``) once tick ``k - 1`` was delivered."""
    from hapmotion.live import SkeletonFrame

    class Lockstep(base):  # type: ignore[misc, valid-type]
        async def run(self) -> None:
            n = self.n if hasattr(self, "n") else max(1, int(round(self.duration_s * self.fps)))
            for i in range(n):
                await _submit_and_wait(self.engine, sink, SkeletonFrame(
                    np.zeros((0, 3)), i, i / self.fps, time.perf_counter(), show_t=i / self.fps))

    return Lockstep


def live_rows(show: dict[str, Any], motion: Any) -> dict[str, np.ndarray]:
    """``hapmotion.live.live(source, [sink], show=Show)`` with a lockstep replay of ``motion`` (mode audio: the
    session's clock source, swapped for a lockstep one); the rendered rows and their show times."""
    from unittest import mock

    import hapmotion.live.session as session
    from hapmotion.live import live

    sink = _recording_sink()
    s = make_show(show)

    async def run() -> None:
        if s.mode == "audio":
            with mock.patch.object(session, "ClockSource", _lockstep_ticks(session.ClockSource, sink)):
                await live(s, None, [sink], handle_signals=False, stall_ms=LIVE_STALL_MS, render_cap=RENDER_CAP)
        else:
            await live(s, _lockstep_replay(motion, sink), [sink], handle_signals=False, stall_ms=LIVE_STALL_MS,
                       render_cap=RENDER_CAP)

    asyncio.run(run())
    return sink.result()


def play_rows(path: Path, cues: Optional[Path] = None) -> dict[str, np.ndarray]:
    """``hapmotion.live.playback.play(path, [sink], cues=...)`` with the track source swapped for a lockstep one;
    the rendered rows and their show times."""
    from unittest import mock

    import hapmotion.live.playback as playback
    from hapmotion.show import Show

    sink = _recording_sink()

    async def run() -> None:
        with mock.patch.object(playback, "TrackSource", _lockstep_ticks(playback.TrackSource, sink)):
            await playback.play(path, [sink], show=Show(cues=cues), handle_signals=False,
                                stall_s=LIVE_STALL_MS / 1000.0, render_cap=RENDER_CAP)

    asyncio.run(run())
    return sink.result()


def make_seat(spec: dict[str, Any]) -> Any:
    """``hapmotion.audience.Seat`` of a spec (``delay_s``, and the comfort fields ``gain``, ``max_duty``)."""
    from hapmotion.audience import Seat
    from hapmotion.show.comfort import Comfort

    comfort = {k: v for k, v in spec.items() if k in ("gain", "max_duty")}
    return Seat(delay_s=spec.get("delay_s", 0.0), comfort=Comfort(**comfort))


@contextlib.contextmanager
def nats_server() -> Iterator[str]:
    """A real ``nats-server -js`` on a free loopback port (``hapmotion.audience.server.LocalNatsServer``, as
    tests/conftest.py starts it); yields ``nats://127.0.0.1:PORT``."""
    from hapmotion.audience.server import LocalNatsServer

    with LocalNatsServer() as server:
        yield server.url


def seat_rows(server: str, name: str, show: dict[str, Any], motion: Any, seat: dict[str, Any],
              attempts: int = 4) -> dict[str, np.ndarray]:
    """The venue publishes ``show`` (``live(..., ["nats://.../NAME"])``, a lockstep replay at live pace) and one
    seat (``hapmotion.audience.listen(url, [sink], seat=Seat(**seat))``) renders it; the seat's rendered rows and
    show times. Run again until the seat rendered every frame once, in order (see the module docstring)."""
    from hapmotion.audience import PublisherSecurity, SeatSecurity, listen, publishing
    from hapmotion.live import live

    s = make_show(show)
    n, fps = motion.n_frames, motion.fps

    async def once(attempt: int) -> dict[str, np.ndarray]:
        show_name = f"{name}-{attempt}"
        url = f"{server}/{show_name}"
        venue_sink, seat_sink = _recording_sink(), _recording_sink()
        go = asyncio.Event()
        venue_ready: asyncio.Future = asyncio.get_running_loop().create_future()
        with publishing(PublisherSecurity(unsigned=True)):  # a rehearsal: the rows do not depend on signing
            venue = asyncio.create_task(live(
                s, _lockstep_replay(motion, venue_sink, pace=True, go=go), [url, venue_sink],
                handle_signals=False, on_ready=lambda e: venue_ready.done() or venue_ready.set_result(e)))
        seat_task = None
        try:
            await asyncio.wait({venue, venue_ready}, timeout=20, return_when=asyncio.FIRST_COMPLETED)
            if venue.done():
                venue.result()
            seat_ready = asyncio.Event()
            seat_task = asyncio.create_task(listen(url, [lambda dmap, f: seat_sink], seat=make_seat(seat),
                                                   handle_signals=False, on_ready=lambda e: seat_ready.set(),
                                                   security=SeatSecurity(unsigned=True)))
            await asyncio.wait_for(seat_ready.wait(), 20)
            await asyncio.sleep(0.2)
            go.set()
            await asyncio.wait_for(venue, 120)
            deadline = time.perf_counter() + 5.0 + seat.get("delay_s", 0.0)
            while seat_sink.rendered < n and time.perf_counter() < deadline:
                await asyncio.sleep(0.02)
        finally:
            for task in (venue, seat_task):
                if task is not None and not task.done():
                    task.cancel()
                    await asyncio.gather(task, return_exceptions=True)
        return seat_sink.result()

    got: dict[str, np.ndarray] = {}
    for attempt in range(1, attempts + 1):
        got = asyncio.run(once(attempt))
        ks = np.rint(got["t"] * fps).astype(int).tolist()
        if ks == list(range(n)):
            return got
        print(f"  seat {name}: attempt {attempt} rendered {len(ks)} of {n} frames in order; running again",
              file=sys.stderr)
    raise RuntimeError(f"seat {name}: no complete run in {attempts} attempts")


# ==================================================================================================== the capture
# From here on: no package API, only the adapters above.

CLIPS = {  # name -> (motion file, song, frames for live, frames for the seat)
    "bvh60_12": (EXAMPLES / "60_12_scaled.bvh", EXAMPLES / "vibe_ace.ogg"),
    "aist_gBR": (EXAMPLES / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", EXAMPLES / "vibe_ace.ogg"),
    "wave2": (SHARED / "motion" / "dataset-2_wave-both-hands_normal_001.bvh", SHARED / "audio" / "lets_go_fishin.ogg"),
}
LIVE_CLIPS = ("aist_gBR", "wave2")
SEAT_CLIP = ("wave2", 0, 90)  # 3 s at 30 fps, played at live pace
SONGS = {"vibe_ace": EXAMPLES / "vibe_ace.ogg", "lets_go_fishin": SHARED / "audio" / "lets_go_fishin.ogg"}
HEARTBEAT = SHARED / "tact" / "FeedbackFiles_Vest_Heartbeat.tact"
COMFORT = (0.8, 0.5)  # gain, max duty


def write_cue_file(folder: Path) -> Path:
    """A small cue list: a vest pattern with a gain, one side-swapped, one limited to the back (absolute paths)."""
    tact = SHARED / "tact"
    path = folder / "compare.cues"
    path.write_text("# time pattern options\n"
                    f"0.5 {HEARTBEAT} gain=0.8 name=heart\n"
                    f"1.25 {tact / 'FeedbackFiles_Vest_Shockwave.tact'} gain=1.5 side=swap\n"
                    f"2.0 {tact / 'FeedbackFiles_Vest_Rumble.tact'} devices=VestBack\n"
                    f"2.5 {tact / 'bom_FeedbackFiles_Tactosy2_Pistal_L.tact'} gain=2 side=swap\n")
    return path


def spec(**kw: Any) -> dict[str, Any]:
    return {"method": "mst", "preset": kw.pop("preset"), "mode": None, "audio": None, "mix_rule": None,
            "cues": None, "comfort": None, **kw}


def key_of(entry: str, clip: str, s: dict[str, Any]) -> str:
    parts = [entry, clip, s["method"] if s.get("mode") != "audio" or entry == "offline" else "-",
             s["preset"], s["mode"] or "auto", s["mix_rule"] or "default" if s["mode"] != "motion" else "-"]
    if s["cues"]:
        parts.append("cues")
    if s["comfort"]:
        parts.append(f"comfort{s['comfort'][0]:g}x{s['comfort'][1]:g}")
    return "/".join(parts)


def offline_specs(song: Path, cues: Path) -> list[dict[str, Any]]:
    c = api_choices()
    out = []
    for method in c["methods"]:
        for preset in c["presets"]:
            for mode in c["modes"]:
                rules = c["rules"] if mode != "motion" else (None,)
                for rule in rules:
                    out.append(spec(method=method, preset=preset, mode=mode, mix_rule=rule,
                                    audio=song if mode != "motion" else None))
        for mode in c["modes"]:
            for extra in ({"cues": cues}, {"comfort": COMFORT}, {"cues": cues, "comfort": COMFORT}):
                out.append(spec(method=method, preset=c["default_preset"][0], mode=mode,
                                audio=song if mode != "motion" else None, **extra))
    return out


def live_specs(song: Path, cues: Path) -> list[dict[str, Any]]:
    """Every method x mode x preset (x rule where music plays), the music alone once per preset x rule (it has no
    renderer), and cues + comfort per method x mode."""
    c = api_choices()
    out = []
    for method in c["methods"]:
        for mode in c["modes"]:
            if mode == "audio" and method != c["methods"][0]:
                continue  # the music alone has no renderer: one run per preset/rule
            for preset in c["presets"]:
                for rule in (c["rules"] if mode != "motion" else (None,)):
                    out.append(spec(method=method, preset=preset, mode=mode, mix_rule=rule,
                                    audio=song if mode != "motion" else None))
            out.append(spec(method=method, preset=c["default_preset"][0], mode=mode,
                            audio=song if mode != "motion" else None, cues=cues, comfort=COMFORT))
    return out


def capture(out: Path, quick: bool = False) -> None:
    arrays: dict[str, np.ndarray] = {}
    counts: dict[str, int] = {}
    times: dict[str, float] = {}

    def put(prefix: str, values: dict[str, np.ndarray]) -> None:
        for k, v in values.items():
            key = f"{prefix}/{k}"
            assert key not in arrays, key
            arrays[key] = v
        entry = prefix.split("/", 1)[0]
        counts[entry] = counts.get(entry, 0) + len(values)

    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="compare-outputs-") as tmp:
        folder = Path(tmp)
        cues = write_cue_file(folder)
        motions = {name: load_motion(path) for name, (path, _) in CLIPS.items()}

        t0 = time.perf_counter()
        for clip, (_, song) in CLIPS.items():
            specs = offline_specs(song, cues)
            for s in specs[:8] if quick else specs:
                put(key_of("offline", clip, s), offline_track(s, motions[clip]))
        c = api_choices()
        for song_name, song in SONGS.items():
            for preset in c["presets"]:
                for rule in c["rules"]:
                    s = spec(preset=preset, mode="audio", audio=song, mix_rule=rule)
                    put(key_of("offline", f"music-{song_name}", s), offline_track(s, None))
            s = spec(preset=c["default_preset"][0], mode="audio", audio=song, cues=cues, comfort=COMFORT)
            put(key_of("offline", f"music-{song_name}", s), offline_track(s, None))
        times["offline"] = time.perf_counter() - t0
        print(f"offline: {counts.get('offline', 0)} arrays in {times['offline']:.1f} s", file=sys.stderr)

        t0 = time.perf_counter()
        for clip in LIVE_CLIPS:
            _, song = CLIPS[clip]
            specs = live_specs(song, cues)
            for s in specs[:3] if quick else specs:
                put(key_of("live", clip, s), live_rows(s, motions[clip]))
        times["live"] = time.perf_counter() - t0
        print(f"live: {counts.get('live', 0)} arrays in {times['live']:.1f} s", file=sys.stderr)

        t0 = time.perf_counter()
        clip, first, stop = SEAT_CLIP
        seat_motion = load_motion(CLIPS[clip][0], first, stop)
        song = CLIPS[clip][1]
        default = c["default_preset"][0]
        with nats_server() as server:
            put(f"seat/{clip}/motion-show/seat-default",
                seat_rows(server, "cmp-motion", spec(preset=default, mode="motion"), seat_motion, {"delay_s": 0.1}))
            put(f"seat/{clip}/multimodal-show/seat-gain0.8-duty0.5",
                seat_rows(server, "cmp-multimodal", spec(preset=default, mode="multimodal", audio=song),
                          seat_motion, {"delay_s": 0.1, "gain": COMFORT[0], "max_duty": COMFORT[1]}))
        times["seat"] = time.perf_counter() - t0
        print(f"seat: {counts.get('seat', 0)} arrays in {times['seat']:.1f} s", file=sys.stderr)

        t0 = time.perf_counter()
        saved = save_track_file(spec(preset=default, mode="multimodal", audio=CLIPS["wave2"][1]),
                                seat_motion, folder / "saved_track.npz")
        put("play/saved_track_npz", play_rows(saved))
        put("play/tact_heartbeat", play_rows(HEARTBEAT))
        put("play/tact_heartbeat/cues", play_rows(HEARTBEAT, cues=cues))
        put("play/saved_track_npz/cues", play_rows(saved, cues=cues))
        times["play"] = time.perf_counter() - t0
        print(f"play: {counts.get('play', 0)} arrays in {times['play']:.1f} s", file=sys.stderr)

    np.savez_compressed(out, **arrays)
    total = time.perf_counter() - t_all
    print(f"captured {len(arrays)} arrays to {out} in {total:.1f} s: "
          + ", ".join(f"{k} {v}" for k, v in counts.items()))


# ==================================================================================================== the comparison
def compare(a_path: Path, b_path: Path) -> int:
    with np.load(a_path, allow_pickle=False) as fa, np.load(b_path, allow_pickle=False) as fb:
        a_keys, b_keys = set(fa.files), set(fb.files)
        identical = differ = 0
        missing = sorted(a_keys ^ b_keys)
        for key in missing:
            where = b_path if key in a_keys else a_path
            print(f"MISSING {key}: not in {where}")
        for key in sorted(a_keys & b_keys):
            a, b = fa[key], fb[key]
            same_dtype = a.dtype == b.dtype or (a.dtype.kind == b.dtype.kind == "U")
            if same_dtype and a.shape == b.shape and (
                    np.array_equal(a, b, equal_nan=True) if a.dtype.kind in "fc" else np.array_equal(a, b)):
                identical += 1
                continue
            differ += 1
            if a.shape != b.shape:
                print(f"DIFF {key}: shape {a.shape} vs {b.shape} (dtype {a.dtype} vs {b.dtype})")
            elif a.dtype.kind in "biuf" and b.dtype.kind in "biuf":
                d = np.abs(a.astype(np.float64) - b.astype(np.float64))
                both_nan = np.isnan(a.astype(np.float64)) & np.isnan(b.astype(np.float64))
                d = np.where(both_nan, 0.0, d)
                n_bad = int(np.count_nonzero(d != 0) + np.count_nonzero(np.isnan(d)))
                print(f"DIFF {key}: max abs difference {np.nanmax(d) if np.isfinite(d).any() else float('nan'):.6g}"
                      f" ({n_bad} of {a.size} values differ; dtype {a.dtype} vs {b.dtype})")
            else:
                n_bad = int(np.count_nonzero(a != b)) if a.dtype == b.dtype else a.size
                print(f"DIFF {key}: {n_bad} of {a.size} values differ (dtype {a.dtype} vs {b.dtype})")
    print(f"{identical} arrays identical, {differ} differ, {len(missing)} missing")
    return 1 if differ or missing else 0


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    cap = sub.add_parser("capture", help="render every array and store them in OUT.npz")
    cap.add_argument("out", type=Path)
    cap.add_argument("--quick", action="store_true", help="a few shows per entry point (checking the script)")
    cmp_ = sub.add_parser("compare", help="compare two captures; exit 1 on any difference")
    cmp_.add_argument("a", type=Path)
    cmp_.add_argument("b", type=Path)
    args = ap.parse_args(argv)
    if args.command == "capture":
        capture(args.out, quick=args.quick)
        return 0
    return compare(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())

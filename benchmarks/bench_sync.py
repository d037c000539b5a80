"""Harness of audio-synchronised seats (``hapmotion listen ... --sync audio``): does the vest follow what the viewer
hears? Not a timed test: figures are printed beside their targets.

``python -m benchmarks.bench_sync [--songs N] [--seconds S] [--seed K]``

For each song (the shared real songs, then synthetic songs drawn from ``--seed``), a local ``nats-server`` carries a
recorded show (the dance recording dataset-1_dance-short_normal_001.bvh replayed with the song, published by the
``nats://`` sink with its music reference, as ``hapmotion live --sink nats://...`` does) to seats started with the
default sync options before the show starts (an audience waiting for the concert), each reading what its viewer
hears through the raw pipe input (``--audio-input raw:PATH``, an OS pipe this harness writes in real time from the
moment the seat opens it: silence, then the song from its start when the music reaches the viewer, or from the
moment the harness knows the venue's clock if that is later). What each viewer hears is built from the publisher's
own media clock:

* **stream**: a low-quality Ogg Vorbis copy of the song (libsndfile's encoder at its lowest quality), the way a
  stream sounds through a loopback; a delay drawn from 0.3-3.0 s, a clock drift of +-0.1 %, blocks arriving with up
  to 20 ms of jitter, and a 1 s jump of the delay (a re-buffer or a skip) half way;
* **noisy**: the same plus room noise (pink noise and mains hum) at 10 dB SNR: a microphone in a room;
* **silence**, **speech** (a speech-like signal with room noise) and **other song** (a different song, same codec):
  no lock may happen;
* **speech over** the music: the stream copy with a speech-like signal as loud as the music (0 dB) mixed over it:
  the seat may lock at the right delay or stay searching, never lock at a wrong one.

Reported: the skew between the heard music and the vest (the local time each frame reached the seat's sinks minus
the time its media time was heard), p50 and p95 of its size, from 5 s after the music reached the seat (frames
within 3 s after the jump left out: the re-lock time covers them); time to lock after the music reached the seat;
time to re-lock after the jump (locked again within 40 ms of the truth); false locks (a lock, or a jump followed,
more than 60 ms from the truth outside the 3 s after the jump, or any lock on the no-music seats); the median and
the worst lock and re-lock over all runs (``--seed`` draws other delays and synthetic songs); the sync worker's CPU
(the thread that reads, analyses and matches the audio) and the event loop's CPU checking and storing the reference
messages; how far behind real time the pipe writers ran at worst, and how many seats found their audio delivered
slower than real time (a writer that cannot keep up hands the seat audio later than its viewer "heard" it, which
the seat would rightly place later: the harness's error, not the seat's). All seats and the publisher share this
process and this machine's cores with other work (a loaded machine), as the load average printed says.

Figures of the last runs (docs/audience.md, "Measured", has the table and the loads): with the chroma in the reference
(three runs of the defaults, load average 0.7-2.5): lock median 2.7 s, worst 3.2-4.1 s; re-lock median 1.8 s, worst
2.1-2.6 s; no false lock; sync CPU 2.9-4.5 % of a core per seat (1.7-2.8 % without the chroma, interleaved). Before
it, with every vote weighed by
the band levels as heard as well, two runs of the defaults (lock median 2.5 s, worst 3.0-4.1 s; re-lock median
2.1 s, worst 2.7-2.9 s) and one of ``--seed 7`` (lock median 2.2 s, worst 3.3 s; re-lock median 2.2 s, worst 2.8
s), no false lock. Before that, five runs of the defaults
(two with the trace on) and three of ``--seed 7`` before the fix below: the defaults, lock median 2.7 s, worst 3.3-4.5 s; re-lock median 2.1-2.2 s, worst
2.6-3.0 s (synthetic-2026's noisy copy, whose rhythm repeats every 2.59 s: the aliases of its jump lie at like
distances, and the loudness heard since the jump decides among them, 2.3-3.0 s; 3.2-4.5 s before that tie-break);
``--seed 7``, lock median 2.1-2.2 s, worst 3.2-3.3 s, re-lock median 2.1-2.3 s, worst 2.9 s (synthetic-7's noisy
copy, 3.1-3.6 s before); two false locks, both synthetic-2027's noisy copy moving one bar off 40 s in, where
the show's reference had ended while the stream played on and the tie-break weighed the bars before it (since
fixed: the tie-break needs the held delay's reference whole). After the fix, one run of each: the defaults re-lock
median 2.0 s, worst 2.9 s, lock worst 4.8 s; ``--seed 7`` median 2.1 s, worst 3.0 s (synthetic-7's noisy copy), lock worst 3.3 s; no false lock. Before the prior of the delay held,
vibe_ace's re-locks (its music loops a 3.7 s stretch) took 7-11 s; now 2.1-2.6 s.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import soundfile as sf

import hapmotion
from hapmotion.audience import PublisherSecurity, Seat, SeatSecurity, listen, publishing
from hapmotion.audience.seat_sync import SyncSettings
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.wire import decode_frame, subject
from hapmotion.live import ReplaySource, live
from hapmotion.show import Show

from tests.support.data import AUDIO, MOTION
from tests.support.live_fakes import PlayTimes

from . import sync_scenes as scenes

SONGS = [AUDIO / "vibe_ace.ogg", AUDIO / "lets_go_fishin.ogg"]
DANCE = MOTION / "dataset-1_dance-short_normal_001.bvh"
SR = scenes.SR
BLOCK = 441  # 20 ms at 22.05 kHz
TARGETS = {"skew_stream": 0.040, "skew_noisy": 0.060, "lock": 5.0, "relock": 3.0, "cpu": 0.15}
TARGETED = ("stream", "noisy")
"""The viewers held to the skew, lock and re-lock targets; the others (silence, speech, another song, speech as loud
as the right music) are held to no false lock: speech over the music may lock at the right delay or not at all."""




@dataclass
class Viewer:
    """What one seat's viewer hears: the signal as a function of the media time heard at each local time.

    The writer feeds the seat from before the show starts: silence until the harness knows the venue's live edge
    (``t0``, set once), then the viewer's signal; music that follows the media clock starts at media time 0, so a
    seat hears silence and then the song start, as a viewer waiting for the concert does."""

    name: str
    source: np.ndarray          # (n,) at SR, indexed by media time (or not: the no-music signals)
    follows_media: bool
    noise_db: float | None = None
    delay: float = 1.0
    drift: float = 0.0
    jump: float = 0.0
    jump_at: float = 30.0       # seconds after the music reaches the viewer
    over: np.ndarray | None = None  # (n,) a signal mixed over the music, as loud as the music (0 dB)
    taps: PlayTimes = field(default_factory=PlayTimes)
    sync: object = None
    t0: float | None = None     # local time from which the signal (not silence) is written
    edge: float = 0.0           # venue: media m plays at local m + edge
    listening: bool = False     # the seat has opened its audio input (the writer writes from then on)
    music_rms: float = 0.1
    noise: np.ndarray = field(default_factory=lambda: np.zeros(0))
    late: float = 0.0           # how far behind its real-time schedule the writer wrote a block at worst, seconds

    @property
    def music_start(self) -> float:
        """Local time the viewer hears media time 0 (the seat's music starts at the later of this and ``t0``)."""
        return self.edge + self.delay

    @property
    def jump_time(self) -> float:
        return self.music_start + self.jump_at

    def media_at(self, tau: np.ndarray) -> np.ndarray:
        m = (tau - self.edge - self.delay) * (1.0 + self.drift)
        return np.where(tau >= self.jump_time, m - self.jump, m)

    def heard_time(self, m: np.ndarray, tau_play: np.ndarray) -> np.ndarray:
        """Local time the viewer heard media time ``m`` (the segment of the frame's own play time)."""
        after = tau_play >= self.jump_time
        return np.where(after, (m + self.jump), m) / (1.0 + self.drift) + self.edge + self.delay

    def offset_truth(self, tau: float) -> float:
        """Local minus media time of what is heard at ``tau``."""
        return float(tau - self.media_at(np.array([tau]))[0])

    def prepare(self, seconds: float, seed: int) -> None:
        """Room noise for the whole run (indexed by the writer's sample count) and the music's level."""
        music = self.source[self.source != 0.0]
        self.music_rms = float(np.sqrt(np.mean(music * music))) if music.size else 1e-3
        if self.noise_db is not None:
            self.noise = scenes.room_noise(seed, int((seconds + 30.0) * SR)) * self.music_rms / 10 ** (self.noise_db / 20)
        if self.over is not None:
            o = np.resize(self.over, int((seconds + 30.0) * SR))
            self.over = o * self.music_rms / max(1e-9, float(np.sqrt(np.mean(o * o))))

    def block(self, k: int, tau: np.ndarray) -> np.ndarray:
        """Samples ``k .. k + len(tau)`` of the writer, heard at local times ``tau``."""
        if self.t0 is None:
            x = np.zeros(tau.size)
        elif self.follows_media:
            x = scenes.heard(self.source, self.media_at(tau)) * (tau >= self.t0)
        else:
            x = np.take(self.source, np.arange(k, k + tau.size), mode="wrap") * (tau >= self.t0)
        if self.over is not None and self.t0 is not None:
            x = x + np.take(self.over, np.arange(k, k + tau.size), mode="wrap") * (tau >= self.t0)
        if self.noise.size:
            x = x + np.take(self.noise, np.arange(k, k + tau.size), mode="wrap")
        return x.astype(np.float32)


def writer(fd: int, v: Viewer, start: float, rng: np.random.Generator, stop: threading.Event) -> None:
    """Write what ``v`` hears to the pipe in real time from ``start``, each 20 ms block up to 20 ms late
    (jitter). Blocks before the seat opened its input are not written (a pipe would hold them and hand them to the
    seat late, all at once); from then on every block is written, waiting for the seat if it must (a dropped block
    would shift every later sample's time). A writer behind its schedule hands the seat audio later than the viewer
    heard it (the harness, not the seat, would then be wrong): the worst lateness is reported."""
    with os.fdopen(fd, "wb", buffering=0) as f:
        k = 0
        while not stop.is_set():
            due = start + (k + BLOCK) / SR + rng.uniform(0.0, 0.020)
            wait = due - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
            try:
                if v.listening:
                    f.write(v.block(k, start + (k + np.arange(BLOCK)) / SR).tobytes())
                    if v.t0 is not None:
                        v.late = max(v.late, time.perf_counter() - max(due, v.t0))
            except BrokenPipeError:
                return
            k += BLOCK


async def media_edge(url: str, show: str, seconds: float = 0.25) -> float:
    """The venue's live edge as a subscriber sees it: the smallest arrival minus media time over ``seconds``."""
    import nats

    nc = await nats.connect(url)
    best = [np.inf]

    async def on(msg) -> None:
        wf = decode_frame(msg.data, 52)
        best[0] = min(best[0], time.perf_counter() - wf.media_t)

    await nc.subscribe(subject(show, "frame"), cb=on)
    await asyncio.sleep(seconds)
    await nc.close()
    return best[0]


async def run_song(server: LocalNatsServer, song: Path, seconds: float, seed: int, other: np.ndarray) -> list[Viewer]:
    rng = np.random.default_rng(seed)
    music, sr = sf.read(song, dtype="float64", always_2d=True)
    music = music.mean(axis=1)
    if sr != SR:
        raise SystemExit(f"{song}: expected {SR} Hz")
    coded = scenes.codec_copy(music)
    name = f"sync{seed}"
    url = f"{server.url}/{name}"
    viewers = []
    for kind in ("stream", "noisy"):
        delay = float(rng.uniform(0.3, 3.0))
        jump = 1.0 if (delay < 1.3 or rng.random() < 0.5) else -1.0
        viewers.append(Viewer(kind, coded, True, 10.0 if kind == "noisy" else None, delay=delay,
                              drift=float(rng.choice([-1e-3, 1e-3])), jump=jump, jump_at=seconds / 2))
    viewers.append(Viewer("silence", np.zeros(SR), False))
    viewers.append(Viewer("speech", scenes.speech_like(seed, 20.0), False, 10.0))
    viewers.append(Viewer("other song", scenes.codec_copy(other), True, delay=1.0))
    viewers.append(Viewer("speech over", coded, True, delay=float(rng.uniform(0.3, 3.0)),
                          over=scenes.speech_like(seed + 1, 20.0)))
    for i, v in enumerate(viewers):
        v.prepare(seconds, seed + i)
    show = Show(audio=song)
    stop = threading.Event()
    seats, threads = [], []
    start = time.perf_counter() + 0.5
    for i, v in enumerate(viewers):  # the viewers are there before the show starts, as an audience is
        r, w = os.pipe()
        sync = SyncSettings(input=f"raw:/dev/fd/{r}?rate={SR}&channels=1&format=f32")
        sessions: list = []
        seats.append((asyncio.create_task(listen(url, [lambda d, f, t=v.taps: t], seat=Seat(), sync=sync,
                                                 security=SeatSecurity(unsigned=True), handle_signals=False,
                                                 sessions=sessions)), sessions, v, r))
        threads.append(threading.Thread(target=writer, args=(w, v, start, np.random.default_rng(seed + 100 + i),
                                                             stop), daemon=True))
    for th in threads:
        th.start()
    await asyncio.sleep(1.0)
    with publishing(PublisherSecurity(unsigned=True)):
        motion = hapmotion.load_motion(DANCE)
        source = ReplaySource(motion)
        ready = asyncio.get_running_loop().create_future()
        venue = asyncio.create_task(live(show, source, [url], handle_signals=False,
                                         on_ready=lambda e: ready.done() or ready.set_result(e)))
        await asyncio.wait({venue, ready}, return_when=asyncio.FIRST_COMPLETED)
        if venue.done():
            venue.result()
    edge = await media_edge(server.url, name)
    for _ in range(100):
        for _, sessions, v, _ in seats:
            v.listening = bool(sessions) and getattr(sessions[-1][1], "sync", None) is not None
        if all(v.listening for v in viewers):
            break
        await asyncio.sleep(0.02)
    t0 = time.perf_counter()
    for v in viewers:
        v.edge = edge
        v.t0 = t0  # set last: the writers read it
    await asyncio.sleep(seconds + 1.0 + max(0.0, max(v.music_start for v in viewers) - t0))
    for task, sessions, v, r in seats:
        if sessions:
            v.sync = sessions[-1][1].sync
    stop.set()
    for task, _, _, r in seats:
        task.cancel()
    await asyncio.gather(*(s[0] for s in seats), return_exceptions=True)
    for _, _, _, r in seats:
        os.close(r)
    venue.cancel()
    await asyncio.gather(venue, return_exceptions=True)
    return viewers


@dataclass
class Figures:
    skew: np.ndarray
    lock_s: float
    relock_s: float
    false_locks: int
    cpu: float
    loop_cpu: float


def figures(v: Viewer, seconds: float) -> Figures:
    sync = v.sync
    history = list(sync.estimates) if sync is not None else []
    music_start = max(v.music_start, v.t0)  # the seat hears music from here on
    jump_t = v.jump_time if v.jump else np.inf
    lock_s = relock_s = np.inf
    false_locks = jumps = 0
    was_locked = False
    last_state = None
    for at, est, state in history:
        locked = state.state == "locked" and state.offset_s is not None
        changed = (state.state, state.jumps, state.locks) != last_state
        last_state = (state.state, state.jumps, state.locks)
        if os.environ.get("BENCH_SYNC_DEBUG") and v.follows_media and (at - music_start < 8 or 0 <= at - jump_t < 8
                                                                       or changed):
            print(f"  {v.name} {at - music_start:6.2f} {state.state:9s} {state.jumps} "
                  f"{'' if state.offset_s is None else f'{(state.offset_s - v.offset_truth(at)) * 1000:7.1f}'} "
                  f"{'' if est is None else f'err {(est.offset_s - v.offset_truth(at)) * 1000:7.1f} ms score {est.score:.2f} margin {est.margin:.2f}'}")
        if not v.follows_media or v.name == "other song":
            false_locks += int(locked and not was_locked)
            was_locked = locked
            continue
        err = abs(state.offset_s - v.offset_truth(at)) if locked else np.inf
        moved = locked and (not was_locked or state.jumps != jumps)  # a lock, or a jump the seat followed
        if moved and err > 0.060 and not (jump_t <= at < jump_t + 3.0):
            false_locks += 1
        was_locked, jumps = locked, state.jumps
        if err <= 0.040:
            if at < jump_t and lock_s == np.inf:
                lock_s = at - music_start
            if at >= jump_t and relock_s == np.inf:
                relock_s = at - jump_t
    frames = np.array(v.taps.frames) if v.taps.frames else np.zeros((0, 2))
    skew = np.zeros(0)
    if v.name in TARGETED and frames.size:
        tau, m = frames[:, 0], frames[:, 1]
        keep = (tau >= music_start + 5.0) & ~((tau >= jump_t) & (tau < jump_t + 3.0))
        skew = tau[keep] - v.heard_time(m[keep], tau[keep])
    cpu = sync.cpu_s / seconds if sync is not None else 0.0
    loop_cpu = sync.loop_cpu_s / seconds if sync is not None else 0.0
    return Figures(skew, lock_s, relock_s, false_locks, cpu, loop_cpu)


def fmt_ms(x: float) -> str:
    return "never" if not np.isfinite(x) else f"{x * 1000:.0f} ms"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--songs", type=int, default=4, help="songs: the 2 real ones, then synthetic (default 4)")
    ap.add_argument("--seconds", type=float, default=40.0, help="seconds of show per song (default 40)")
    ap.add_argument("--seed", type=int, default=2026, help="seed of the delays, drifts and synthetic songs")
    args = ap.parse_args(argv)
    print(f"bench_sync: load average {os.getloadavg()[0]:.1f} at the start, {os.cpu_count()} cores")
    rows = []
    with tempfile.TemporaryDirectory() as tmp, LocalNatsServer() as server:
        songs = list(SONGS)
        for k in range(max(0, args.songs - len(SONGS))):
            path = Path(tmp) / f"synthetic-{args.seed + k}.wav"
            sf.write(path, scenes.synth_song(args.seed + k, args.seconds + 5.0), SR)
            songs.append(path)
        for i, song in enumerate(songs[:args.songs]):
            other_path = songs[(i + 1) % len(songs)]
            other, _ = sf.read(other_path, dtype="float64")
            other = other if other.ndim == 1 else other.mean(axis=1)
            viewers = asyncio.run(run_song(server, song, args.seconds, args.seed + 10 * i, other))
            for v in viewers:
                rows.append((song.name, v, figures(v, args.seconds)))
    print(f"\n{'song':24s} {'viewer':11s} {'delay':>7s} {'jump':>5s} {'skew p50':>9s} {'skew p95':>9s} "
          f"{'target':>7s} {'lock':>8s} {'re-lock':>8s} {'false':>5s} {'sync CPU':>9s} {'loop CPU':>9s}")
    ok = True
    for name, v, f in rows:
        target = TARGETS["skew_noisy"] if v.name == "noisy" else TARGETS["skew_stream"]
        music = v.name in TARGETED
        p50 = float(np.percentile(np.abs(f.skew), 50)) if f.skew.size else np.inf
        p95 = float(np.percentile(np.abs(f.skew), 95)) if f.skew.size else np.inf
        good = f.false_locks == 0 and f.cpu + f.loop_cpu <= TARGETS["cpu"]
        if music:
            good &= p95 <= target and f.lock_s <= TARGETS["lock"] and f.relock_s <= TARGETS["relock"]
        ok &= good
        delay = f"{v.delay * 1000:6.0f}ms" if v.name in TARGETED + ("speech over",) else "      -"
        lock = "-" if not v.follows_media or v.name == "other song" else (
            f"{f.lock_s:.1f} s" if np.isfinite(f.lock_s) else "never")
        relock = (f"{f.relock_s:.1f} s" if np.isfinite(f.relock_s) else "never") if music else "-"
        print(f"{name[:24]:24s} {v.name:11s} {delay} {v.jump if music else 0:+5.1f} "
              f"{fmt_ms(p50) if music else '-':>9s} {fmt_ms(p95) if music else '-':>9s} "
              f"{fmt_ms(target) if music else '-':>7s} {lock:>8s} {relock:>8s} "
              f"{f.false_locks:5d} {f.cpu * 100:8.1f}% {f.loop_cpu * 100:8.2f}% {'ok' if good else 'MISSED'}")
    locks = np.array([f.lock_s for _, v, f in rows if v.name in TARGETED])
    relocks = np.array([f.relock_s for _, v, f in rows if v.name in TARGETED])
    print(f"\nover {locks.size} runs: lock median {np.median(locks):.1f} s, worst {locks.max():.1f} s "
          f"(target {TARGETS['lock']:g} s); re-lock median {np.median(relocks):.1f} s, worst {relocks.max():.1f} s "
          f"(target {TARGETS['relock']:g} s); false locks {sum(f.false_locks for _, _, f in rows)} (target 0); "
          f"speech over the music locked (at the right delay) in "
          f"{sum(np.isfinite(f.lock_s) for _, v, f in rows if v.name == 'speech over')} of "
          f"{sum(v.name == 'speech over' for _, v, _ in rows)}")
    print(f"targets: skew p95 <= 40 ms (stream copy), <= 60 ms (noisy copy), from 5 s after the music reached the "
          f"seat; lock within {TARGETS['lock']:g} s of that; re-lock within {TARGETS['relock']:g} s of a 1 s jump; "
          f"no false lock; sync CPU (the worker thread) + loop CPU (checking and storing the reference on the event "
          f"loop) <= {TARGETS['cpu'] * 100:g} % of a core per seat")
    late = max(v.late for _, v, _ in rows)
    slow = sum(bool(v.sync is not None and v.sync.faults.get("slow_input")) for _, v, _ in rows)
    print(f"harness: the pipe writers ran at most {late * 1000:.0f} ms behind real time; seats that found their "
          f"audio slower than real time: {slow}")
    print(f"load average {os.getloadavg()[0]:.1f} at the end; all seats and the publisher in this one process")
    print("all targets met" if ok else "SOME TARGETS MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())

"""Fuzz every file reader with mutated inputs; count internal errors, hangs, stray stderr lines and peak memory.

Run: ``PYTHONPATH=src python -m benchmarks.fuzz_inputs [--count 3000] [--seed 1] [--keep DIR]``.

Readers covered, each the way a user reaches it:

- motion files (BVH, Azure Kinect JSON, AIST++ pickle, CSV and NPZ tables) through ``hapmotion info FILE``
  (the CLI entry point, so exit codes are the user's: 0 read, 2 a one-line error, 1 an internal error);
- track files (.csv, .json, .npz, .tact) through ``hapmotion.load_track``;
- audio (WAV, FLAC, Ogg Vorbis, MP3) through ``hapmotion.audio.analyze_file``;
- device layouts (``--layout FILE``) through ``hapmotion.layout.load_layout``;
- cue lists (``--cues FILE``, text and JSON) through ``hapmotion.show.cues.load_cues`` and then the work the cues
  cause: every cue laid on a one-minute timeline at 50 fps (``cue_layer``), as ``render --cues`` does;
- the viewer's input path: ``hapmotion view TRACK -o page.html`` on saved tracks (an NPZ with the renderer's
  debug arrays, stored so that byte edits reach its array headers, and JSON, CSV and .tact tracks), through the CLI
  entry point like motion files.

Seeds are real files (the recordings, bHaptics patterns and music in ``../shared/data``, cut short where long)
and files written by hapmotion itself (tables, tracks, synthetic skeletons named the MakeHuman, Mixamo and Perfume
ways, generated audio). Each mutant comes from one seed by a random mix of byte flips, truncation, inserted or
repeated chunks, and, for text, token-aware edits (a number replaced by a 5,000-digit integer, ``nan``, ``1e308``,
``-1``, ...; deep bracket nesting; a header line repeated or deleted). A few hand-made hostile files are added:
deeply nested JSON, a forged pickle shape, an NPZ of deflated zeros, a hierarchy thousands of joints deep, layouts
with ``rows: 1e999`` or 100,000 devices, 100 cues of a one-hour pattern, an NPZ with a corrupt array header.

Every file runs in its own process, forked from a parent that has imported hapmotion and warmed its compiled
parsers (a fresh interpreter per file would cost a second each). The parent waits at most ``--timeout`` seconds
(30) and reads the child's peak resident memory from ``wait4``; the child's address space is capped at
``--cap-gb`` (3 GB) so a memory bomb cannot take the shared machine (it then fails with a MemoryError, which
counts as an internal error and shows in the peak). Targets, printed beside the figures: 0 internal errors, 0
hangs, 0 stray stderr lines, peak memory under 1 GB.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import pickle
import re
import resource
import shutil
import signal
import sys
import tempfile
import time
import traceback
import zipfile
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

import hapmotion
from hapmotion.errors import HapMotionError
from hapmotion.motion_files import save_motion_table
from hapmotion.track_files import save_track
from tests.support.data import SHARED_DATA as SHARED

TARGET_PEAK_MB = 1000.0

# ------------------------------------------------------------------------------------------------------ seeds


def cut_bvh(text: str, frames: int) -> str:
    """The BVH with only its first ``frames`` frames (a real hierarchy, a short motion)."""
    head, motion = text.split("MOTION", 1)
    rows = motion.strip("\n").split("\n")
    data = [r for r in rows[2:] if r.strip()][:frames]
    return head + "MOTION\n" + f"Frames: {len(data)}\n" + rows[1] + "\n" + "\n".join(data) + "\n"


def make_seeds(folder: Path) -> dict[str, list[Path]]:
    """Seed files per reader kind (:data:`SHARE`)."""
    import soundfile as sf

    from tests.support.motion_files import SCHEMES, kinect_document, synthetic_bvh

    seeds: dict[str, list[Path]] = defaultdict(list)

    def put(kind: str, name: str, data: "bytes | str") -> None:
        path = folder / name
        path.write_bytes(data.encode() if isinstance(data, str) else data)
        seeds[kind].append(path)

    motion_dir = SHARED / "motion"
    put("motion", "cmu.bvh", cut_bvh((motion_dir / "01_01.bvh").read_text(), 120))
    put("motion", "daz.bvh", cut_bvh((motion_dir / "60_12_scaled.bvh").read_text(), 120))
    put("motion", "bandai.bvh", cut_bvh((motion_dir / "dataset-1_punch_normal_001.bvh").read_text(), 90))
    for scheme in ("MakeHuman", "Mixamo", "Perfume"):
        put("motion", f"{scheme.lower()}.bvh", synthetic_bvh(SCHEMES[scheme], frames=40))
    aist = pickle.loads((motion_dir / "gBR_sBM_cAll_d04_mBR0_ch03.pkl").read_bytes())
    put("motion", "aist.pkl", pickle.dumps({k: v[:120] for k, v in aist.items()}))
    clip = hapmotion.load_motion(motion_dir / "dataset-1_punch_normal_001.bvh").slice(0, 40)
    put("motion", "kinect.json", json.dumps(kinect_document(clip)))
    save_motion_table(clip, folder / "table.csv")
    seeds["motion"].append(folder / "table.csv")
    save_motion_table(clip, folder / "table.npz")
    seeds["motion"].append(folder / "table.npz")
    pos = np.stack([clip.joint(n) for n in ("PELVIS", "SPINE_NAVEL", "NECK", "SHOULDER_LEFT", "SHOULDER_RIGHT",
                                            "HAND_LEFT", "HAND_RIGHT")], axis=1)
    buf = io.BytesIO()  # stored, not deflated: byte edits then reach the .npy headers
    np.savez(buf, positions=pos, joints=np.array(["PELVIS", "SPINE_NAVEL", "NECK", "SHOULDER_LEFT",
                                                  "SHOULDER_RIGHT", "HAND_LEFT", "HAND_RIGHT"]), fps=np.float64(30))
    put("motion", "stored.npz", buf.getvalue())

    track = hapmotion.render(clip)
    for ext in (".csv", ".json", ".npz", ".tact"):
        path = folder / f"track{ext}"
        save_track(track, path)
        seeds["track"].append(path)
    for tact in sorted((SHARED / "tact").glob("*.tact"))[:3]:
        put("track", tact.name, tact.read_bytes())

    from importlib import resources

    layout_text = resources.files("hapmotion").joinpath("data/x40_shoulders.json").read_text()
    put("layout", "x40_shoulders.json", layout_text)
    put("layout", "compact.json", json.dumps(json.loads(layout_text), separators=(",", ":")))

    # Cue lists name their patterns by absolute path, so that a mutant elsewhere still finds them.
    patterns = [folder / "track.csv", folder / "track.npz", *sorted(folder.glob("*.tact"))]
    lines = [f"{1.5 * k:g} {p} gain={0.5 + 0.25 * (k % 3):g}" + (" side=swap" if k % 2 else "") + "\n"
             for k, p in enumerate(patterns)]
    put("cues", "show.cues", "# time pattern options\n" + "".join(lines) + f"30 {patterns[0]} devices=VestFront\n")
    put("cues", "show.json", json.dumps({"cues": [{"time": 2.0 * k, "pattern": str(p), "gain": 1.0, "name": f"c{k}"}
                                                  for k, p in enumerate(patterns)]}, indent=1))

    stored = io.BytesIO()  # the rendered track with its debug arrays, stored: byte edits reach the .npy headers
    np.savez(stored, intensities=track.intensities, times=track.times, actuators=np.array(track.actuators),
             fps=np.array(track.fps), layout=np.array(track.layout), meta_json=np.array(json.dumps({})),
             **{f"debug_{k}": np.asarray(v) for k, v in track.debug.items()})
    put("view", "view_stored.npz", stored.getvalue())
    for ext in (".npz", ".json", ".csv", ".tact"):
        seeds["view"].append(folder / f"track{ext}")

    sr = 22050
    t = np.arange(int(1.5 * sr)) / sr
    signal_ = 0.3 * np.sin(2 * np.pi * 220 * t) * (1 + np.sign(np.sin(2 * np.pi * 2 * t))) / 2
    for ext, fmt, subtype in ((".wav", "WAV", "PCM_16"), (".flac", "FLAC", None), (".ogg", "OGG", "VORBIS"),
                              (".mp3", "MP3", None), (".wav", "WAV", "FLOAT")):
        path = folder / f"tone_{subtype or fmt}{ext}".lower()
        sf.write(path, np.stack([signal_, signal_[::-1]], axis=1), sr, format=fmt, subtype=subtype)
        seeds["audio"].append(path)
    return seeds


def hostile_files(folder: Path) -> list[tuple[str, Path]]:
    """Hand-made files of the classes known to break readers (kind, path)."""
    from numpy._core.multiarray import _reconstruct

    out = []

    def put(kind: str, name: str, data: bytes) -> None:
        path = folder / name
        path.write_bytes(data)
        out.append((kind, path))

    put("motion", "deep.json", b'{"frames": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    put("track", "deep_track.json", b'{"actuators": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    put("track", "deep.tact", b'{"project": ' + b"{\"a\":" * 50_000 + b"1" + b"}" * 50_000 + b"}")
    put("motion", "bigint.json", b'{"frames": [{"timestamp_usec": ' + b"9" * 5000 + b', "bodies": []}]}')
    put("track", "bigint_track.json", b'{"fps": ' + b"9" * 5000 + b', "actuators": []}')

    class Bomb:
        def __reduce__(self):
            return _reconstruct, (np.ndarray, (3_000_000, 17, 3), b"d")

    put("motion", "bomb.pkl", pickle.dumps({"keypoints3d_optim": Bomb()}, protocol=4))
    depth = 5000
    lines = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0", "CHANNELS 3 Xposition Yposition Zposition"]
    lines += [f"JOINT j{k}\n{{\nOFFSET 0 1 0\nCHANNELS 0" for k in range(depth)]
    lines += ["}"] * (depth + 1) + ["MOTION", "Frames: 1", "Frame Time: 0.01", "0 0 0"]
    put("motion", "deep.bvh", ("\n".join(lines) + "\n").encode())
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        with z.open("positions.npy", "w", force_zip64=True) as f:
            header = io.BytesIO()
            np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                          "shape": (600_000, 32, 3)})
            f.write(header.getvalue())
            block = b"\0" * 2**22
            for _ in range(600_000 * 32 * 3 * 8 // len(block)):
                f.write(block)
    put("motion", "zeros.npz", buf.getvalue())
    for ext in (".csv", ".npz", ".tact", ".json"):
        put("track", "empty_track" + ext, b"")
    put("track", "header_only.csv", b"time_s,a1\n")

    from importlib import resources

    layout = json.loads(resources.files("hapmotion").joinpath("data/x40_shoulders.json").read_text())
    put("layout", "deep_layout.json", b'{"devices": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    put("layout", "rows_1e999.json", json.dumps(layout).replace('"rows": 5', '"rows": 1e999', 1).encode())
    put("layout", "many_devices.json", json.dumps({"devices": [layout["devices"][0]] * 100_000}).encode())
    put("layout", "bigint_layout.json", b'{"devices": [{"rows": 1' + b"0" * 5000 + b"}]}")

    hour = np.zeros((180_000, 2))
    hour[::50, 0] = 50.0
    save_track(hapmotion.HapticTrack(hour, 50.0, ("VestFront_0", "VestBack_0")), folder / "hour.npz")
    put("cues", "hour_x100.json", json.dumps({"cues": [{"time": k, "pattern": str(folder / "hour.npz")}
                                                       for k in range(100)]}).encode())
    put("cues", "deep_cues.json", b'{"cues": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    put("cues", "many_cues.cues", "".join(f"{k % 60} {folder / 'hour.npz'}\n" for k in range(20_000)).encode())

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:  # an unclosed bracket in an array header: numpy's tokenizer fails
        for name, value in (("intensities", np.full((2, 2), 10.0)), ("actuators", np.array(["VestFront_0", "VestBack_0"])),
                            ("fps", np.array(50.0))):
            npy = io.BytesIO()
            np.lib.format.write_array(npy, value)
            z.writestr(f"{name}.npy", npy.getvalue().replace(b"'shape': ()", b"'shape': ((", 1))
    put("view", "bad_header.npz", buf.getvalue())
    return out


# -------------------------------------------------------------------------------------------------- mutations

_NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
_REPLACEMENTS = [b"9" * 5000, b"1" + b"0" * 400, b"nan", b"NaN", b"inf", b"-inf", b"1e308", b"-1e308", b"1e-320",
                 b"-1", b"0", b"", b"99999999999", b"0.0", b"-0", b"1e999", b"\"x\"", b"null", b"true", b"[]", b"{}"]


def mutate(data: bytes, rng: np.random.Generator, text: bool) -> bytes:
    """One to three random edits of ``data``."""
    b = bytearray(data)
    for _ in range(int(rng.integers(1, 4))):
        op = int(rng.integers(0, 9 if text else 5))
        n = len(b)
        if n == 0:
            b += bytes(rng.integers(0, 256, size=16, dtype=np.uint8))
            continue
        if op == 0:  # flip a few bytes
            for i in rng.integers(0, n, size=int(rng.integers(1, 20))):
                b[i] = int(rng.integers(0, 256))
        elif op == 1:  # truncate
            del b[int(rng.integers(0, n)):]
        elif op == 2:  # insert random bytes
            i = int(rng.integers(0, n))
            b[i:i] = bytes(rng.integers(0, 256, size=int(rng.integers(1, 64)), dtype=np.uint8))
        elif op == 3:  # repeat a chunk
            i = int(rng.integers(0, n))
            j = min(n, i + int(rng.integers(1, 4096)))
            b[i:i] = b[i:j] * int(rng.integers(2, 50))
        elif op == 4:  # zero a run
            i = int(rng.integers(0, n))
            b[i:i + int(rng.integers(1, 256))] = b"\0" * len(b[i:i + 256])
        elif op == 5:  # replace a number token
            found = list(_NUMBER.finditer(bytes(b[:200_000])))
            if found:
                m = found[int(rng.integers(0, len(found)))]
                b[m.start():m.end()] = _REPLACEMENTS[int(rng.integers(0, len(_REPLACEMENTS)))]
        elif op == 6:  # deep nesting
            i = int(rng.integers(0, n))
            d = int(rng.choice([100, 3000, 100_000]))
            b[i:i] = b"[" * d + b"]" * d if rng.random() < 0.5 else b"{" * d
        elif op == 7:  # repeat or delete a line
            lines = bytes(b).split(b"\n")
            k = int(rng.integers(0, len(lines)))
            if rng.random() < 0.5:
                lines[k:k + 1] = [lines[k]] * int(rng.integers(2, 2000))
            else:
                del lines[k]
            b = bytearray(b"\n".join(lines))
        else:  # swap two lines
            lines = bytes(b).split(b"\n")
            i, j = rng.integers(0, len(lines), size=2)
            lines[i], lines[j] = lines[j], lines[i]
            b = bytearray(b"\n".join(lines))
    return bytes(b)


TEXT = {".bvh", ".json", ".csv", ".tact", ".cues"}
SHARE = {"motion": 0.35, "track": 0.2, "audio": 0.15, "layout": 0.1, "cues": 0.1, "view": 0.1}
"""Fraction of the mutated files per reader kind."""


def write_inputs(work: Path, count: int, seed: int) -> None:
    """Seeds, hostile files and ``count`` mutants under ``work``; the list of runs in ``work/jobs.tsv``."""
    (work / "seeds").mkdir()
    seeds = make_seeds(work / "seeds")
    rng = np.random.default_rng(seed)
    jobs = [(kind, path, "hostile") for kind, path in hostile_files(work)]
    jobs += [(kind, path, "seed") for kind, paths in seeds.items() for path in paths]  # each must read
    mutants = work / "mutants"
    mutants.mkdir()
    for kind, fraction in SHARE.items():
        for k in range(int(round(count * fraction))):
            source = seeds[kind][k % len(seeds[kind])]
            data = mutate(source.read_bytes(), rng, source.suffix in TEXT)
            path = mutants / f"{kind}_{k:05d}_{source.stem}{source.suffix}"
            path.write_bytes(data)
            jobs.append((kind, path, source.name))
    (work / "jobs.tsv").write_text("".join(f"{k}\t{p}\t{o}\n" for k, p, o in jobs))

# ------------------------------------------------------------------------------------------------------ running


CUE_SHOW_S, CUE_FPS = 60.0, 50.0
"""The timeline a fuzzed cue list is laid on (seconds, frames per second)."""


def read_input(kind: str, path: str) -> None:
    """The reader of ``kind`` on ``path``, as a library user reaches it (the CLI kinds are run by :func:`child`)."""
    if kind == "track":
        hapmotion.load_track(path)
    elif kind == "audio":
        from hapmotion.audio import analyze_file

        analyze_file(path)
    elif kind == "layout":
        from hapmotion.layout import load_layout

        load_layout(path)
    elif kind == "cues":
        from hapmotion.layout import load_layout
        from hapmotion.show.cues import cue_layer, load_cues

        layout = load_layout()
        cue_layer(load_cues(path), fps=CUE_FPS, n_frames=int(CUE_SHOW_S * CUE_FPS), actuators=layout.actuators,
                  mirror_map=layout.mirror_map())
    else:
        raise ValueError(kind)


def child(kind: str, path: str, out_fd: int, cap_bytes: int) -> None:
    """Run one reader in this forked process and exit: 0 read, 2 a one-line user error, 1 anything else."""
    resource.setrlimit(resource.RLIMIT_AS, (cap_bytes, cap_bytes))
    os.dup2(out_fd, 2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    sys.stdout = open(1, "w", closefd=False)
    sys.stderr = open(2, "w", closefd=False)
    code = 1
    try:
        if kind in ("motion", "view"):
            from hapmotion.cli import main

            if kind == "motion":
                code = main(["info", path])
            else:
                page = Path(tempfile.mkdtemp(prefix="fuzz-view-")) / "page.html"
                try:
                    code = main(["view", path, "-o", str(page)])
                finally:
                    shutil.rmtree(page.parent, ignore_errors=True)
        else:
            try:
                read_input(kind, path)
                code = 0
            except HapMotionError as err:
                print(f"error: {err}", file=sys.stderr)
                code = 2
    except BaseException:  # noqa: BLE001 - everything else is what we are counting
        traceback.print_exc()
        code = 1
    sys.stderr.flush()
    os._exit(code)


def run_one(kind: str, path: Path, timeout: float, cap_bytes: int) -> dict:
    """Fork, run the reader, wait; the result: exit code (None for a hang), peak RSS in MB, stderr text, seconds."""
    with tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            try:
                child(kind, str(path), err.fileno(), cap_bytes)
            finally:
                os._exit(1)
        status, usage = 0, None
        while True:
            done, status, usage = os.wait4(pid, os.WNOHANG)
            if done:
                break
            if time.perf_counter() - start > timeout:
                os.kill(pid, signal.SIGKILL)
                _, status, usage = os.wait4(pid, 0)
                return {"code": None, "peak_mb": usage.ru_maxrss / 1024, "stderr": "", "s": timeout}
            time.sleep(0.002)
        err.seek(0)
        text = err.read(20_000).decode("utf-8", "replace")
    code = os.waitstatus_to_exitcode(status)
    return {"code": code, "peak_mb": usage.ru_maxrss / 1024, "stderr": text, "s": time.perf_counter() - start}


def classify(result: dict) -> str:
    """read / clean error / internal error / hang / stray stderr lines (anything on stderr but the one error line,
    or the reader's own "warning:" and "note:" lines)."""
    code = result["code"]
    lines = [ln for ln in result["stderr"].splitlines() if ln.strip() and not ln.startswith(("warning: ", "note: "))]
    if code is None:
        return "hang"
    if code == 2:
        return "clean error" if len(lines) == 1 else "stray stderr lines"
    if code == 0:
        return "read" if not lines else "stray stderr lines"
    return "internal error"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=3000, help="mutated files (default 3000)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=30.0, help="seconds before a run counts as a hang")
    parser.add_argument("--cap-gb", type=float, default=3.0, help="address-space cap of each run")
    parser.add_argument("--keep", type=Path, default=None, help="copy failing inputs to this folder")
    args = parser.parse_args()

    work = Path(tempfile.mkdtemp(prefix="hapmotion-fuzz-"))
    try:
        # The files are made in a forked child, so that what making them costs (a render, a 460 MB deflate) does not
        # stay in the parent's memory, which every run starts from.
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            try:
                write_inputs(work, args.count, args.seed)
                os._exit(0)
            except BaseException:  # noqa: BLE001
                traceback.print_exc()
                os._exit(1)
        if os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) != 0:
            raise SystemExit("making the inputs failed")
        jobs = [tuple(line.split("\t")) for line in (work / "jobs.tsv").read_text().splitlines()]
        jobs = [(kind, Path(path), origin) for kind, path, origin in jobs]
        # Warm every compiled kernel once in the parent (numba's BVH parser, the audio analysis), so that no child
        # compiles or loads them from the cache: the children inherit them.
        from hapmotion.audio import analyze_file

        hapmotion.load_motion(work / "seeds" / "bandai.bvh")
        hapmotion.load_track(work / "seeds" / "track.csv")
        analyze_file(work / "seeds" / "tone_pcm_16.wav")
        read_input("cues", str(work / "seeds" / "show.cues"))
        from hapmotion.cli import main as cli_main

        with open(os.devnull, "w") as quiet:  # the viewer's page code, imported once for every child
            saved, sys.stdout = sys.stdout, quiet
            try:
                cli_main(["view", str(work / "seeds" / "track.npz"), "-o", str(work / "warm.html")])
            finally:
                sys.stdout = saved
        baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        cap = int(args.cap_gb * 2**30)
        counts: dict[str, Counter] = defaultdict(Counter)
        worst: dict[str, list] = defaultdict(list)
        seconds: Counter = Counter()
        peaks: dict[str, float] = defaultdict(float)
        peak = (0.0, "")
        t0 = time.perf_counter()
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        seeds_failed = []
        for i, (kind, path, origin) in enumerate(jobs):
            r = run_one(kind, path, args.timeout, cap)
            c = classify(r)
            if origin == "seed" and c != "read":
                seeds_failed.append(f"{kind} {path.name}: {c}: {r['stderr'].strip()[-200:]}")
            counts[kind][c] += 1
            seconds[kind] += r["s"]
            peaks[kind] = max(peaks[kind], r["peak_mb"])
            if r["peak_mb"] > peak[0]:
                peak = (r["peak_mb"], f"{path.name} ({c})")
            if c not in ("read", "clean error"):
                last = [ln for ln in r["stderr"].splitlines() if ln.strip()][-1:] or ["(no output)"]
                worst[kind].append((c, path.name, origin, last[0][:200]))
                if args.keep:
                    args.keep.mkdir(parents=True, exist_ok=True)
                    shutil.copy(path, args.keep / path.name)
            if (i + 1) % 500 == 0:
                print(f"  {i + 1}/{len(jobs)} files, {time.perf_counter() - t0:.0f} s", flush=True)
        wall = time.perf_counter() - t0
        cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (cpu1.ru_utime + cpu1.ru_stime) - (cpu0.ru_utime + cpu0.ru_stime)

        total = Counter()
        for c in counts.values():
            total.update(c)
        n_hostile = sum(1 for _, _, o in jobs if o == "hostile")
        n_seeds = sum(1 for _, _, o in jobs if o == "seed")
        print(f"\nfuzz_inputs: {len(jobs)} files ({n_hostile} hand-made hostile, {n_seeds} unmutated seeds), "
              f"seed {args.seed}, "
              f"{wall:.0f} s wall, {cpu:.0f} s CPU in the runs; parent RSS {baseline:.0f} MB (each run starts "
              "from it)")
        print(f"{'reader':8s} {'files':>6s} {'read':>6s} {'clean':>6s} {'internal':>9s} {'hangs':>6s} "
              f"{'stray':>6s} {'s/file':>7s} {'peak MB':>8s}")
        for kind in SHARE:
            c = counts[kind]
            n = sum(c.values())
            print(f"{kind:8s} {n:6d} {c['read']:6d} {c['clean error']:6d} {c['internal error']:9d} "
                  f"{c['hang']:6d} {c['stray stderr lines']:6d} {seconds[kind] / max(1, n):7.3f} "
                  f"{peaks[kind]:8.0f}")
        print(f"\ninternal errors (exit 1 / tracebacks): {total['internal error']:5d}   target 0")
        print(f"hangs over {args.timeout:g} s:                   {total['hang']:5d}   target 0")
        print(f"stray stderr lines:                     {total['stray stderr lines']:5d}   target 0")
        print(f"unmutated seeds not read:               {len(seeds_failed):5d}   target 0 (of {n_seeds})")
        for line in seeds_failed:
            print(f"  {line}")
        print(f"peak memory of a run:                   {peak[0]:5.0f} MB   target < {TARGET_PEAK_MB:.0f} MB "
              f"({peak[1]})")
        for kind, items in worst.items():
            print(f"\n{kind}: {len(items)} failing inputs; by kind and last stderr line:")
            seen = Counter((c, re.sub(r"/\S+", "PATH", line)) for c, _, _, line in items)
            for (c, line), n in seen.most_common(15):
                print(f"  {n:4d} x {c}: {line}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()

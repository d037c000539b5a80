"""Viewer page size and speed for a one-hour recording.

Builds a synthetic one-hour 60 fps recording (all 32 joints, smooth multi-frequency arm and body motion plus 1 mm
sensor jitter, travelling on the floor), renders it with the real renderer (mst, paper), writes the viewer page and
opens it in headless Chromium (Debian's /usr/bin/chromium via Playwright). Prints each figure beside its target.

    python -m benchmarks.bench_viewer [--minutes 60] [--fps 60] [--keep out.html]

Figures:
- page size (MB) and its largest parts;
- page build time (packing + writing; rendering is reported apart);
- time to interactive: from navigation start to the viewer's ready flag (page parsed, every blob decoded, controls
  working), median of 3 loads; also the wall-clock time seen by the test driver; then the first animation frame,
  which draws the whole hour's actuator map, total intensity and energy lanes once;
- playback smoothness while playing at 1x for 5 s: per-frame work (ms) median / p95 and the gap between
  animation frames (ms) p95 (16.7 ms = every display frame at 60 Hz);
- seek latency: click on the timeline to the new frame on screen, median of 5.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

TARGETS = {
    "size_mb": 40.0,
    "build_s": 10.0,
    "tti_s": 3.0,
    "first_draw_ms": 500.0,
    "draw_p95_ms": 8.0,
    "gap_p95_ms": 20.0,
    "seek_ms": 100.0,
}

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def synthetic_motion(minutes: float, fps: float, seed: int = 1):
    """A performer on all 32 Kinect joints: rest pose plus sums of sinusoids (0.1-2.5 Hz) per joint, stronger on
    the arms, a slow walk around the stage, and 1 mm Gaussian jitter (Azure Kinect-like noise)."""
    from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS
    from hapmotion.motion import new_motion

    rest = {
        "PELVIS": (0, 1.0, 0), "SPINE_NAVEL": (0, 1.15, 0), "SPINE_CHEST": (0, 1.35, 0), "NECK": (0, 1.55, 0),
        "CLAVICLE_LEFT": (0.05, 1.5, 0), "SHOULDER_LEFT": (0.2, 1.48, 0), "ELBOW_LEFT": (0.25, 1.2, 0),
        "WRIST_LEFT": (0.28, 0.95, 0.05), "HAND_LEFT": (0.29, 0.88, 0.06), "HANDTIP_LEFT": (0.3, 0.8, 0.07),
        "THUMB_LEFT": (0.27, 0.86, 0.1), "HIP_LEFT": (0.1, 0.95, 0), "KNEE_LEFT": (0.11, 0.52, 0.02),
        "ANKLE_LEFT": (0.12, 0.08, 0), "FOOT_LEFT": (0.12, 0.02, 0.12), "HEAD": (0, 1.7, 0.02),
        "NOSE": (0, 1.68, 0.11), "EYE_LEFT": (0.03, 1.72, 0.09), "EAR_LEFT": (0.07, 1.7, 0.0),
    }
    base = np.zeros((len(JOINTS), 3))
    for name, v in rest.items():
        base[JOINT_INDEX[name]] = v
        if name.endswith("_LEFT"):
            base[JOINT_INDEX[name[:-5] + "_RIGHT"]] = (-v[0], v[1], v[2])
    n = int(round(minutes * 60 * fps))
    t = np.arange(n) / fps
    rng = np.random.default_rng(seed)
    pos = np.empty((n, len(JOINTS), 3))
    arm = {"ELBOW": 0.15, "WRIST": 0.3, "HAND": 0.35, "HANDTIP": 0.37, "THUMB": 0.34}
    for j, name in enumerate(JOINTS):
        part = name.split("_")[0]
        amp = arm.get(part, 0.02)
        for k in range(3):
            f = rng.uniform(0.1, 2.5, 3)
            ph = rng.uniform(0, 2 * np.pi, 3)
            pos[:, j, k] = base[j, k] + (amp / 3) * np.sin(2 * np.pi * f[:, None] * t + ph[:, None]).sum(axis=0)
    walk = np.stack([1.5 * np.sin(2 * np.pi * t / 97), np.zeros(n), 1.0 * np.sin(2 * np.pi * t / 61)], axis=1)
    pos += walk[:, None, :]
    pos += rng.normal(0.0, 0.001, pos.shape)
    return new_motion(pos, fps, source="synthetic one-hour recording")


def measure_browser(page_path: Path) -> dict:
    from playwright.sync_api import sync_playwright

    out: dict = {}
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            ttis, walls = [], []
            for _ in range(3):
                page = browser.new_page(viewport={"width": 1400, "height": 900})
                errors: list[str] = []
                page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
                page.on("pageerror", lambda e: errors.append(str(e)))
                t0 = time.perf_counter()
                page.goto(page_path.as_uri(), timeout=120_000)
                page.wait_for_function("window.hapmotionViewer && window.hapmotionViewer.state().ready",
                                       timeout=120_000, polling=20)
                walls.append(time.perf_counter() - t0)
                st = page.evaluate("window.hapmotionViewer.state()")
                ttis.append(st["stats"]["loadMs"] / 1000.0)
                page.wait_for_function("window.hapmotionViewer.state().stats.firstDrawMs !== null", polling=20)
                first = page.evaluate("window.hapmotionViewer.state().stats.firstDrawMs")
                if errors:
                    raise RuntimeError(f"console errors: {errors[:3]}")
                last = page
                out["heap_mb"] = page.evaluate("performance.memory ? performance.memory.usedJSHeapSize / 1e6 : null")
                if len(ttis) < 3:
                    page.close()
            out["tti_s"] = statistics.median(ttis)
            out["first_draw_ms"] = first
            out["tti_wall_s"] = statistics.median(walls)
            page = last
            page.click("#play")
            time.sleep(5.0)
            st = page.evaluate("window.hapmotionViewer.state()")
            out["draw_median_ms"] = st["stats"]["drawMsMedian"]
            out["draw_p95_ms"] = st["stats"]["drawMsP95"]
            out["gap_p95_ms"] = st["stats"]["frameGapMsP95"]
            out["played_s"] = st["time"]
            page.click("#play")
            box = page.locator("#timeline-head").bounding_box()
            seeks = []
            for frac in (0.2, 0.8, 0.5, 0.35, 0.65):
                before = page.evaluate("window.hapmotionViewer.state().frame")
                x = box["x"] + 92 + frac * (box["width"] - 96)
                t0 = time.perf_counter()
                page.mouse.click(x, box["y"] + 40)
                page.wait_for_function(f"window.hapmotionViewer.state().frame !== {before}", polling=5)
                seeks.append((time.perf_counter() - t0) * 1000)
            out["seek_ms"] = statistics.median(seeks)
        finally:
            browser.close()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--keep", type=Path, default=None, help="also keep the page at this path")
    args = ap.parse_args(argv)

    import hapmotion
    from hapmotion.viewer import write_page

    t0 = time.perf_counter()
    motion = synthetic_motion(args.minutes, args.fps)
    t_motion = time.perf_counter() - t0
    t0 = time.perf_counter()
    track = hapmotion.render(motion, method="mst", preset="paper")
    t_render = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or Path(tmp) / "one_hour.html"
        t0 = time.perf_counter()
        info = write_page(path, [track], motion, title="synthetic one-hour recording")
        t_build = time.perf_counter() - t0
        browser = measure_browser(path)

    size_mb = info.n_bytes / 1e6
    print(f"recording: {motion.n_frames} frames at {args.fps:g} fps ({args.minutes:g} min), 32 joints, 52 actuators; "
          f"made in {t_motion:.1f} s, rendered in {t_render:.1f} s (mst, paper)")
    parts = sorted(info.blob_bytes.items(), key=lambda kv: -kv[1])[:5]
    print("largest parts (MB of base64): " + ", ".join(f"{k} {v / 1e6:.2f}" for k, v in parts))
    rows = [
        ("page size", f"{size_mb:.1f} MB", f"<= {TARGETS['size_mb']:g} MB", size_mb <= TARGETS["size_mb"]),
        ("page build (pack + write)", f"{t_build:.1f} s", f"<= {TARGETS['build_s']:g} s",
         t_build <= TARGETS["build_s"]),
        ("time to interactive (in page)", f"{browser['tti_s']:.2f} s", f"<= {TARGETS['tti_s']:g} s",
         browser["tti_s"] <= TARGETS["tti_s"]),
        ("time to interactive (driver wall clock)", f"{browser['tti_wall_s']:.2f} s", "-", True),
        ("first frame (whole-hour timeline drawn)", f"{browser['first_draw_ms']:.0f} ms",
         f"<= {TARGETS['first_draw_ms']:g} ms", browser["first_draw_ms"] <= TARGETS["first_draw_ms"]),
        ("frame work while playing, median", f"{browser['draw_median_ms']:.1f} ms", "-", True),
        ("frame work while playing, p95", f"{browser['draw_p95_ms']:.1f} ms", f"<= {TARGETS['draw_p95_ms']:g} ms",
         browser["draw_p95_ms"] <= TARGETS["draw_p95_ms"]),
        ("gap between animation frames, p95", f"{browser['gap_p95_ms']:.1f} ms", f"<= {TARGETS['gap_p95_ms']:g} ms",
         browser["gap_p95_ms"] <= TARGETS["gap_p95_ms"]),
        ("seek (click to new frame)", f"{browser['seek_ms']:.0f} ms", f"<= {TARGETS['seek_ms']:g} ms",
         browser["seek_ms"] <= TARGETS["seek_ms"]),
        ("JS heap after load", f"{browser['heap_mb']:.0f} MB" if browser.get("heap_mb") else "n/a", "-", True),
    ]
    width = max(len(r[0]) for r in rows)
    for name, value, target, ok in rows:
        print(f"{name:<{width}}  {value:>10}  target {target:<10} {'ok' if ok else 'MISSED'}")
    return 0 if all(r[3] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

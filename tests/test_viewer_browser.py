"""The viewer page in a real browser: headless Chromium (Debian package, /usr/bin/chromium) driven by Playwright.

A page made from a real clip with its music plays without console errors, its actuator colours change with time
and, at seeked frames, show exactly the track's numbers; a live page shows what a WebSocket broadcast sends, blanks
the vest when the stream stalls or stops. Screenshots go to test-artifacts/ (gitignored).
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from hapmotion.track_files import save_track
import hapmotion
from hapmotion.cli import main
from hapmotion.skeleton.joints import BONES, JOINTS
from hapmotion.viewer import write_page
from hapmotion.show import Show, render_variants
from hapmotion.viewer.page import read_page
from support.data import SHARED_DATA

pytestmark = pytest.mark.browser

SALSA = SHARED_DATA / "motion" / "60_12_scaled.bvh"          # CMU subject 60 salsa, 120 fps, 14 s
SONG = SHARED_DATA / "audio" / "vibe_ace.ogg"                # "Vibe Ace", Kevin MacLeod, CC BY 3.0
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
STATE = "window.hapmotionViewer.state()"


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture()
def page(browser):
    pg = browser.new_page(viewport={"width": 1400, "height": 900})
    pg.errors = []  # console errors and uncaught exceptions seen by the page
    pg.on("console", lambda m: pg.errors.append(m.text) if m.type == "error" else None)
    pg.on("pageerror", lambda e: pg.errors.append(str(e)))
    yield pg
    pg.close()


@pytest.fixture(scope="module")
def show(tmp_path_factory):
    """The salsa clip with its music, mst and baseline, as the wearer feels it (motion and music mixed 2:3)."""
    motion = hapmotion.load_motion(SALSA)
    tracks = render_variants(Show(audio=SONG), motion, ["mst", "baseline"], ["paper"], ["multimodal"])
    from hapmotion.viewer.page import load_audio_part

    path = tmp_path_factory.mktemp("viewer") / "salsa.html"
    write_page(path, tracks, motion, audio=load_audio_part(SONG, fps=motion.fps), title="60_12_scaled.bvh",
               footer=["music: Vibe Ace, Kevin MacLeod, CC BY 3.0"])
    return path, motion, tracks


def open_ready(pg, url: str):
    pg.goto(url)
    pg.wait_for_function("window.hapmotionViewer && window.hapmotionViewer.state().ready", timeout=30_000)
    return pg.evaluate(STATE)


def dom_cells(pg) -> dict:
    """Per actuator id: its data-intensity, data-color and computed background colour."""
    return pg.evaluate("""() => Object.fromEntries([...document.querySelectorAll('.act[data-id]')].map(e =>
        [e.dataset.id,
         [Number(e.dataset.intensity), Number(e.dataset.color || 0), getComputedStyle(e).backgroundColor]]))""")


def css_rgb(hex_colour: str) -> str:
    return "rgb({}, {}, {})".format(*(int(hex_colour[k:k + 2], 16) for k in (1, 3, 5)))


def check_frame_shown(pg, track, colours, frame=None):
    """The page shows exactly ``track``'s row at its current frame: numbers, attributes and colours."""
    st = pg.evaluate(STATE)
    f = st["frame"] if frame is None else frame
    assert st["frame"] == f
    expected = np.rint(track.intensities[f])
    shown = np.array(st["intensities"])
    np.testing.assert_array_equal(shown, expected)
    assert np.abs(shown - track.intensities[f]).max() <= 0.5
    cells = dom_cells(pg)
    top = st["scaleTop"]
    for col, aid in enumerate(track.actuators):
        value, k, bg = cells[aid]
        want_k = 0 if expected[col] <= 0 else int(min(100, max(1, round(expected[col] * 100 / top))))
        assert value == expected[col], aid
        assert k == want_k, aid
        assert bg == css_rgb(colours[want_k]), aid
    return st


def test_recorded_show_plays_and_matches_the_track(page, show):
    path, motion, tracks = show
    data, _ = read_page(path)
    st = open_ready(page, path.as_uri())
    assert st["mode"] == "file" and st["error"] is None
    assert st["tracks"] == ["mst-paper-multimodal", "baseline-paper-multimodal"]
    assert st["frame"] == 0 and st["shown"]["joints"] == int(motion.present.sum())
    assert st["shown"]["triangle"] and st["shown"]["dynamicPoint"]

    # Play: time runs with the music, and the vest changes.
    page.click("#play")
    seen, colours_seen = set(), set()
    for _ in range(8):
        time.sleep(0.25)
        st = page.evaluate(STATE)
        seen.add(tuple(st["intensities"]))
        colours_seen.add(tuple(sorted((k, v[1]) for k, v in dom_cells(page).items())))
    assert st["playing"] and st["time"] > 1.0
    assert st["audio"]["playing"] and abs(st["audio"]["time"] - st["time"]) < 0.25
    assert len(seen) >= 4 and len(colours_seen) >= 4
    page.click("#play")  # pause
    assert not page.evaluate(STATE)["playing"]

    # Seek by clicking the timeline where the mst track is busiest, then step one frame with the keyboard.
    mst = tracks[0]
    busiest = int(np.argmax(mst.intensities[: motion.n_frames].sum(axis=1)))
    duration = page.evaluate(STATE)["duration"]
    box = page.locator("#timeline-head").bounding_box()
    x = box["x"] + 92 + ((busiest + 0.5) / mst.fps / duration) * (box["width"] - 96)
    page.mouse.click(x, box["y"] + 60)
    page.wait_for_function(f"{STATE}.frame !== 0")
    st = check_frame_shown(page, mst, data["colors"])
    assert abs(st["frame"] - busiest) <= 10 and sum(st["intensities"]) > 0
    page.keyboard.press("ArrowRight")
    page.wait_for_function(f"{STATE}.frame === {st['frame'] + 1}")
    check_frame_shown(page, mst, data["colors"], frame=st["frame"] + 1)

    # The method switch shows the baseline's numbers for the same moment.
    page.select_option("#track-select", index=1)
    page.wait_for_function(f"{STATE}.track === 'baseline-paper-multimodal'")
    check_frame_shown(page, tracks[1], data["colors"], frame=st["frame"] + 1)
    page.select_option("#track-select", index=0)

    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "viewer_file.png"))
    assert page.errors == []


def test_deep_link_seeks_to_an_exact_frame(page, show):
    path, motion, tracks = show
    data, _ = read_page(path)
    open_ready(page, path.as_uri() + "?track=baseline-paper-multimodal#t=5.0")
    st = check_frame_shown(page, tracks[1], data["colors"], frame=600)   # 5.0 s at 120 fps
    assert st["track"] == "baseline-paper-multimodal" and st["motionFrame"] == 600
    # Full 0..100 scale: same numbers, other colours.
    page.select_option("#scale-pick", "100")
    page.wait_for_function(f"{STATE}.scaleTop === 100")
    check_frame_shown(page, tracks[1], data["colors"], frame=600)
    assert page.errors == []


# ---------------------------------------------------------------------------------------------------- live mode
class Broadcast:
    """A tiny `hapmotion live`-style WebSocket broadcast (schema in docs/CONTRACTS.md), run in a thread.

    Each client gets hello, three distinct frames, one malformed frame, then the last frame repeated at 20 Hz
    (a steady stream) while not paused; ``stop`` sends the stop message.
    """

    def __init__(self, skeleton):
        self.skeleton = skeleton
        self.paused = threading.Event()
        self.stopped = threading.Event()
        self.frames = [self.frame(k) for k in range(3)]
        self.port = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        assert self._ready.wait(10)

    def frame(self, k: int) -> dict:
        return {"type": "frame", "seq": k, "t": k / 60,
                "intensities": [float((i * 7 + k * 13) % 101) for i in range(52)], "skeleton": self.skeleton,
                "dynamic_point": [0.1, 1.2, 0.3 + 0.01 * k], "hit_point": [0.05, 1.25, 0.12],
                "active": [1, k % 2], "level": 6.0}

    async def handler(self, ws):
        layout = hapmotion.load_layout()
        await ws.send(json.dumps({"type": "hello", "version": 1, "fps": 60.0, "actuators": list(layout.actuators),
                                  "joints": list(JOINTS), "bones": [list(b) for b in BONES], "layout": layout.name,
                                  "render": {"method": "mst", "preset": "paper", "mirror": True}}))
        for fr in self.frames:
            await ws.send(json.dumps(fr))
            await asyncio.sleep(0.02)
        await ws.send(json.dumps(dict(self.frames[-1], seq=3, intensities=[1.0] * 51)))  # wrong length: skipped
        seq = 4
        while not self.stopped.is_set():
            if not self.paused.is_set():
                await ws.send(json.dumps(dict(self.frames[-1], seq=seq, t=seq / 60)))
                seq += 1
            await asyncio.sleep(0.05)
        await ws.send(json.dumps({"type": "stop"}))
        await ws.wait_closed()

    def _run(self):
        from websockets.asyncio.server import serve

        async def go():
            async with serve(self.handler, "127.0.0.1", 0) as server:
                self.port = server.sockets[0].getsockname()[1]
                self._ready.set()
                while not self.done:
                    await asyncio.sleep(0.05)

        self.done = False
        asyncio.run(go())

    def close(self):
        self.stopped.set()
        self.done = True
        self._thread.join(5)


@pytest.fixture()
def broadcast():
    motion = hapmotion.load_motion(SALSA)
    frame = motion.positions[300]
    skeleton = [p.round(4).tolist() if np.isfinite(p).all() else None for p in frame]
    b = Broadcast(skeleton)
    yield b
    b.close()


def test_live_page_shows_the_broadcast(page, broadcast, tmp_path, capsys):
    url = f"ws://127.0.0.1:{broadcast.port}"
    path = tmp_path / "live.html"
    assert main(["view", "--live", url, "-o", str(path)]) == 0
    capsys.readouterr()
    data, _ = read_page(path)
    st = open_ready(page, path.as_uri())
    assert st["mode"] == "live"
    page.wait_for_function(f"{STATE}.frame >= 6", timeout=10_000)   # shown frame's seq (repeats of the last frame)
    st = page.evaluate(STATE)
    assert st["live"]["connected"] and st["live"]["hello"] and st["live"]["skipped"] == 1
    last = broadcast.frames[-1]
    assert st["intensities"] == last["intensities"]
    cells = dom_cells(page)
    for aid, v in zip(st["actuators"], last["intensities"]):
        assert cells[aid][0] == v
        assert cells[aid][2] == css_rgb(data["colors"][cells[aid][1]])
    n_joints = sum(p is not None for p in broadcast.skeleton)
    # the hello says the show runs MST, so the triangle is drawn: the last frame has only the left hand active,
    # so it is (left hand, right shoulder, J_T)
    assert st["shown"] == {"joints": n_joints, "triangle": True, "dynamicPoint": True, "hitPoint": True}
    assert st["active"] == [1, 0] and st["level"] == 6.0
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "viewer_live.png"))

    # The stream stalls: the vest goes blank. It resumes: the frames come back. It stops: blank for good.
    broadcast.paused.set()
    page.wait_for_function(f"{STATE}.live.stalled", timeout=5_000)
    assert set(page.evaluate(STATE)["intensities"]) == {0}
    assert {v[0] for v in dom_cells(page).values()} == {0}
    broadcast.paused.clear()
    page.wait_for_function(f"!{STATE}.live.stalled", timeout=5_000)
    page.wait_for_function(f"{STATE}.intensities.some(v => v > 0)", timeout=5_000)
    broadcast.stopped.set()
    page.wait_for_function(f"{STATE}.live.stopped", timeout=5_000)
    page.wait_for_function(f"{STATE}.intensities.every(v => v === 0)", timeout=5_000)
    assert {v[0] for v in dom_cells(page).values()} == {0}
    assert page.errors == []


def test_recorded_page_switches_to_live_by_query(page, broadcast, show):
    path, _, _ = show
    st = open_ready(page, path.as_uri() + f"?live=ws://127.0.0.1:{broadcast.port}")
    assert st["mode"] == "live"
    page.wait_for_function(f"{STATE}.frame >= 4", timeout=10_000)
    st = page.evaluate(STATE)
    assert st["intensities"] == broadcast.frames[-1]["intensities"] and st["live"]["frames"] >= 4
    assert page.errors == []


def test_saved_track_page_without_motion(page, tmp_path, capsys):
    # A track read back from CSV has no skeleton and no debug data: the vest and the timeline still work.
    motion = hapmotion.load_motion(SALSA)
    saved = tmp_path / "salsa.csv"
    save_track(hapmotion.render(motion, preset="energy"), saved)
    out = tmp_path / "saved.html"
    assert main(["view", str(saved), "-o", str(out)]) == 0
    assert "no dynamic point" in capsys.readouterr().err
    track = hapmotion.load_track(saved)
    data, _ = read_page(out)
    st = open_ready(page, out.as_uri() + "#t=3.0")
    assert st["shown"] == {"joints": 0, "triangle": False, "dynamicPoint": False, "hitPoint": False}
    check_frame_shown(page, track, data["colors"], frame=360)
    assert page.errors == []


# ---------------------------------------------------------------------------------------------------- screen fit
# Everything a user reads: each panel's title, subtitle and edge labels (the sleeves' "front", "back", "neck side",
# "arm side" among them) as the boxes of their text, each actuator cell with its index and value, the stats under
# the vest, the colour bar, the stage's buttons, legend and hint. Boxes are viewport CSS pixels [x, y, w, h].
LAYOUT_BOXES = """() => {
  const box = (r) => [r.left, r.top, r.width, r.height];
  const text = (el) => { const r = document.createRange(); r.selectNodeContents(el); return box(r.getBoundingClientRect()); };
  const out = { labels: [], cells: [], stats: [], controls: [], cellText: [] };
  for (const p of document.querySelectorAll('#vest .panel')) {
    const dev = p.dataset.device;
    for (const el of p.querySelectorAll('.ptitle, .edge')) {
      const own = [...el.childNodes].filter((n) => n.nodeType === 3 && n.textContent.trim());
      for (const n of own) { const r = document.createRange(); r.selectNodeContents(n);
        out.labels.push([dev + ': ' + n.textContent.trim(), box(r.getBoundingClientRect())]); }
      for (const s of el.querySelectorAll('small')) if (s.textContent.trim()) out.labels.push([dev + ': ' + s.textContent.trim(), text(s)]);
    }
    for (const c of p.querySelectorAll('.act')) {
      out.cells.push([c.dataset.id, box(c.getBoundingClientRect())]);
      const v = c.querySelector('.val');
      if (v.textContent) out.cellText.push([c.dataset.id, text(c.querySelector('.idx')), text(v), box(c.getBoundingClientRect())]);
    }
  }
  for (const el of document.querySelectorAll('#readout dt, #readout dd')) out.stats.push(['stats: ' + el.textContent, text(el)]);
  out.controls.push(['colour bar', box(document.getElementById('colorbar').getBoundingClientRect())]);
  for (const el of document.querySelectorAll('#stage .overlay-top, #stage .legend3d, #stage .hint')) out.controls.push(['stage: ' + el.className, box(el.getBoundingClientRect())]);
  out.stacked = document.getElementById('vest').classList.contains('stacked');
  out.side = box(document.getElementById('side').getBoundingClientRect());
  out.sideScroll = [document.getElementById('side').scrollWidth, document.getElementById('side').clientWidth,
                    document.getElementById('side').scrollHeight, document.getElementById('side').clientHeight];
  out.page = [document.documentElement.scrollWidth, document.documentElement.scrollHeight, innerWidth, innerHeight];
  return out;
}"""


def _overlap(a, b, tol=0.5) -> bool:
    return (min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]) > tol) and (min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]) > tol)


def _inside(a, outer, tol=0.5) -> bool:
    return (a[0] >= outer[0] - tol and a[1] >= outer[1] - tol and a[0] + a[2] <= outer[0] + outer[2] + tol
            and a[1] + a[3] <= outer[1] + outer[3] + tol)


def check_screen_fit(pg, width, height):
    """Every label, cell, stat and control is on screen, inside its panel, with no two overlapping; returns the
    boxes."""
    b = pg.evaluate(LAYOUT_BOXES)
    sw, sh, iw, ih = b["page"]
    assert (sw, sh) == (iw, ih) == (width, height), f"the page scrolls: {sw}x{sh} in a {iw}x{ih} window"
    assert b["sideScroll"][0] <= b["sideScroll"][1] and b["sideScroll"][2] <= b["sideScroll"][3], \
        f"the vest panel scrolls (hides part of itself): {b['sideScroll']}"
    screen = [0, 0, width, height]
    vest_side = b["labels"] + b["cells"] + b["stats"] + b["controls"][:1]
    for name, r in vest_side:
        assert r[2] > 0 and r[3] > 0, f"{name} is not drawn"
        assert _inside(r, screen), f"{name} {r} is outside the {width}x{height} window"
        assert _inside(r, b["side"]), f"{name} {r} is outside the vest panel {b['side']}"
    for name, r in b["controls"][1:]:
        assert _inside(r, screen), f"{name} {r} is outside the window"
    items = [(n, r) for n, r in vest_side if not n.startswith("stats")] + b["controls"][1:]
    items += [("stats", [min(r[0] for _, r in b["stats"]), min(r[1] for _, r in b["stats"]),
                         max(r[0] + r[2] for _, r in b["stats"]) - min(r[0] for _, r in b["stats"]),
                         max(r[1] + r[3] for _, r in b["stats"]) - min(r[1] for _, r in b["stats"])])]
    for i, (n1, r1) in enumerate(items):
        for n2, r2 in items[i + 1:]:
            assert not _overlap(r1, r2), f"{n1} {r1} overlaps {n2} {r2}"
    stats = b["stats"]
    for i, (n1, r1) in enumerate(stats):
        for n2, r2 in stats[i + 1:]:
            assert not _overlap(r1, r2), f"{n1} {r1} overlaps {n2} {r2}"
    for aid, idx, val, cell in b["cellText"]:
        assert not _overlap(idx, val), f"{aid}: index {idx} overlaps the value {val}"
        assert _inside(idx, cell) and _inside(val, cell), f"{aid}: its text leaves the cell {cell}"
    labels = pg.evaluate(STATE)["timelineLabels"]
    assert {"vest front", "vest back", "L shoulder", "R shoulder", "total intensity", "audio"} <= {x["text"] for x in labels}
    for i, x in enumerate(labels):
        r1 = [x["x"], x["y"], x["w"], x["h"]]
        assert _inside(r1, screen), f"timeline label {x['text']} {r1} is outside the window"
        for y in labels[i + 1:]:
            assert not _overlap(r1, [y["x"], y["y"], y["w"], y["h"]]), f"timeline labels {x['text']} and {y['text']} overlap"
    return b


@pytest.mark.parametrize("width,height", [(1280, 720), (1280, 800), (1366, 768), (1400, 900), (1920, 1080)])
def test_page_fits_a_laptop_and_a_monitor_screen(browser, show, width, height):
    path, motion, tracks = show
    mst = tracks[0]
    pg = browser.new_page(viewport={"width": width, "height": height})
    errors = []
    pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    pg.on("pageerror", lambda e: errors.append(str(e)))
    try:
        # While the recording plays with intensities showing.
        open_ready(pg, path.as_uri())
        pg.click("#play")
        pg.wait_for_function(f"{STATE}.time > 1.0 && {STATE}.intensities.some(v => v > 0)", timeout=15_000)
        b = check_screen_fit(pg, width, height)
        assert b["cellText"], "no actuator shows a value"
        side_while_playing = b["side"]
        pg.click("#play")
        # At the frame where the sleeves run hardest while the ray hits a shoulder: values in the sleeve cells and
        # the longest stat ("performer-right shoulder").
        sleeves = [k for k, a in enumerate(mst.actuators) if a.startswith("Forearm")]
        chart = np.asarray(mst.debug["chart"])[: mst.n_frames]
        score = np.where(np.isin(chart, [2, 3]), mst.intensities[:, sleeves].max(axis=1), -1)
        f = int(np.argmax(score))
        assert score[f] >= 1
        pg.goto("about:blank")   # a new load: changing only the #t= of the open page would not reload it
        open_ready(pg, path.as_uri() + f"#t={(f + 0.5) / mst.fps:.6f}")
        st = pg.evaluate(STATE)
        assert st["frame"] == f and max(st["intensities"][k] for k in sleeves) >= 1
        b = check_screen_fit(pg, width, height)
        assert b["side"] == side_while_playing, "the vest panel changed size with the values shown"
        shown = {aid for aid, *_ in b["cellText"]}
        assert any(a.startswith("Forearm") for a in shown), shown
        assert {"ForearmL: LEFT SHOULDER", "ForearmL: front", "ForearmL: back", "ForearmL: neck side",
                "ForearmL: arm side", "ForearmR: RIGHT SHOULDER", "ForearmR: back"} <= {n for n, _ in b["labels"]}
        assert any("shoulder" in n for n, _ in b["stats"])
        # The body as the wearer feels it: left sleeve, chest, right sleeve from left to right, the sleeves at the
        # top of the chest; the back beside the right sleeve (laptop) or under the chest (tall window).
        cells = dict(b["cells"])
        x_of = lambda dev: np.mean([r[0] for k, r in cells.items() if k.startswith(dev + "_")])
        assert x_of("ForearmL") < x_of("VestFront") < x_of("ForearmR")
        assert cells["ForearmL_0"][1] < cells["VestFront_8"][1] and cells["ForearmR_0"][1] < cells["VestFront_8"][1]
        assert cells["VestFront_0"][0] < cells["VestFront_3"][0] and cells["VestBack_0"][0] < cells["VestBack_3"][0]
        if b["stacked"]:
            assert cells["VestBack_0"][1] > cells["VestFront_19"][1]
        else:
            assert cells["VestBack_0"][0] > cells["ForearmR_2"][0]
        # A 1080-line monitor has the height to put the back under the front; a 720-line laptop does not.
        assert b["stacked"] == (height == 1080)
        ARTIFACTS.mkdir(exist_ok=True)
        pg.screenshot(path=str(ARTIFACTS / f"viewer_{width}x{height}.png"))
        assert errors == []
    finally:
        pg.close()

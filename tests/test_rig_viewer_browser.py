"""The viewer page in a real browser (headless Chromium, as tests/test_viewer_browser.py) draws the rig that was
rendered: a live stream of a rig with gloves (the body chart's 52 places and the 12 hand places) shows two gloves at
the wearer's sides, each finger and the wrist named and lit with the stream's numbers; a page of a track rendered on
a rig shows that rig's wearables."""

from __future__ import annotations

import asyncio
import threading

import numpy as np
import pytest
from test_viewer_browser import ARTIFACTS, STATE, browser, dom_cells, open_ready, page  # noqa: F401 (fixtures)

from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.cli import main
from hapmotion.layout import load_layout
from hapmotion.live.wire.broadcast import broadcast_frame, broadcast_hello
from hapmotion.rig import parse_rig, rig_track
from hapmotion.track import HapticTrack
from hapmotion.viewer import write_page

pytestmark = pytest.mark.browser

LAYOUT = load_layout()
WORDS = ["thumb", "index", "middle", "ring", "little", "wrist"]


class RigBroadcast:
    """A ``hapmotion live`` broadcast of a show on ``rig``, with the session's own encoders: the hello names the
    columns the live session's broadcast sink gets (:class:`DeviceMap` of the layout on the rig), then frames of
    ``rows``, repeated until closed."""

    def __init__(self, rig: str, rows: list[np.ndarray]):
        dmap = DeviceMap.from_layout(LAYOUT.with_rig(parse_rig(rig)))
        self.actuators = dmap.actuators
        self.hello = broadcast_hello(60.0, dmap.actuators, LAYOUT.name, {"method": "mst", "preset": "felt"})
        self.rows = rows
        self.port = None
        self.done = threading.Event()
        ready = threading.Event()

        async def handler(ws):
            await ws.send(self.hello)
            seq = 0
            while not self.done.is_set():
                await ws.send(broadcast_frame(seq, seq / 60, self.rows[seq % len(self.rows)], None, None))
                seq += 1
                await asyncio.sleep(0.03)

        async def serve_until_done():
            from websockets.asyncio.server import serve

            async with serve(handler, "127.0.0.1", 0) as server:
                self.port = server.sockets[0].getsockname()[1]
                ready.set()
                while not self.done.is_set():
                    await asyncio.sleep(0.05)

        self._thread = threading.Thread(target=lambda: asyncio.run(serve_until_done()), daemon=True)
        self._thread.start()
        assert ready.wait(10)

    def close(self):
        self.done.set()
        self._thread.join(5)


def _boxes(pg) -> dict:
    """Per drawn panel (its device): its left and right edge on the screen, CSS pixels."""
    return pg.evaluate("""() => Object.fromEntries([...document.querySelectorAll('.panel[data-device]')].map(e => {
        const r = e.getBoundingClientRect(); return [e.dataset.device, [r.left, r.right, r.top]]; }))""")


def test_a_live_glove_rig_is_drawn_with_both_gloves_named(page, tmp_path, capsys):
    rows = np.zeros((1, 64))
    ids = DeviceMap.from_layout(LAYOUT.with_rig(parse_rig("pro+gloves"))).actuators
    rows[0, ids.index("GloveL_0")] = 80.0     # the left thumb
    rows[0, ids.index("GloveR_5")] = 35.0     # the right wrist
    rows[0, ids.index("VestFront_0")] = 50.0  # the chest, wearer's upper left
    stream = RigBroadcast("pro+gloves", [rows[0]])
    try:
        path = tmp_path / "live.html"
        assert main(["view", "--live", f"ws://127.0.0.1:{stream.port}", "-o", str(path)]) == 0
        capsys.readouterr()
        open_ready(page, path.as_uri())
        page.wait_for_function(f"{STATE}.live.frames >= 3", timeout=10_000)
        st = page.evaluate(STATE)
        assert st["actuators"] == list(ids) and len(ids) == 64
        assert st["intensities"] == rows[0].tolist()
        cells = dom_cells(page)
        assert set(cells) == set(ids)  # every column drawn, none left out and none extra
        assert cells["GloveL_0"][0] == 80 and cells["GloveR_5"][0] == 35 and cells["VestFront_0"][0] == 50
        assert all(cells[a][0] == 0 for a in ids if a not in ("GloveL_0", "GloveR_5", "VestFront_0"))
        named = page.evaluate("""() => [...document.querySelectorAll('.act[data-label]')].map(e =>
            [e.dataset.id, e.dataset.label, e.querySelector('.lab').textContent, e.title])""")
        assert [(i, lab) for i, lab, _, _ in named] == [(f"Glove{s}_{k}", WORDS[k]) for s in "LR" for k in range(6)]
        assert all(lab == text and f"({lab})" in title for _, lab, text, title in named)
        titles = page.evaluate("""() => Object.fromEntries([...document.querySelectorAll('.panel[data-device]')]
            .map(e => [e.dataset.device, e.querySelector('.ptitle').firstChild.textContent]))""")
        assert titles["GloveL"] == "LEFT HAND" and titles["GloveR"] == "RIGHT HAND"
        # the chest between the shoulders, the wearer's left on the left; the gloves in a row of their own, the left
        # hand on the left; every panel whole inside the vest area (nothing cut off at its edges)
        box = _boxes(page)
        assert box["ForearmL"][1] <= box["VestFront"][0] and box["VestFront"][1] <= box["ForearmR"][0]
        assert box["GloveL"][1] <= box["GloveR"][0] and box["GloveL"][2] == box["GloveR"][2]
        area = page.evaluate("(() => { const r = document.getElementById('vest').getBoundingClientRect(); "
                             "return [r.left, r.right]; })()")
        assert all(area[0] - 1 <= left and right <= area[1] + 1 for left, right, _ in box.values()), (box, area)
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "viewer_live_gloves.png"))
        assert page.errors == []
    finally:
        stream.close()


def test_a_live_rig_without_gloves_draws_no_glove(page, tmp_path, capsys):
    """``live --rig air`` broadcasts the body chart: the page draws its four panels and no glove."""
    row = np.arange(52, dtype=float)
    stream = RigBroadcast("air", [row])
    try:
        assert len(stream.actuators) == 52
        path = tmp_path / "live.html"
        assert main(["view", "--live", f"ws://127.0.0.1:{stream.port}", "-o", str(path)]) == 0
        capsys.readouterr()
        open_ready(page, path.as_uri())
        page.wait_for_function(f"{STATE}.live.frames >= 2", timeout=10_000)
        assert sorted(_boxes(page)) == ["ForearmL", "ForearmR", "VestBack", "VestFront"]
        assert page.evaluate(STATE)["intensities"] == row.tolist()
        assert page.errors == []
    finally:
        stream.close()


def test_a_track_rendered_on_a_glove_rig_is_drawn_as_that_rig(page, tmp_path):
    rows = np.zeros((3, LAYOUT.n_actuators))
    rows[:, 0] = 70.0  # VestFront_0 on the body chart
    hands = np.zeros((3, 12))
    hands[:, 4] = 90.0  # the left little finger
    chart = HapticTrack(np.hstack([rows, hands]), 30.0, LAYOUT.with_rig(parse_rig("pro+gloves")).played_actuators,
                        LAYOUT.name)
    track = rig_track(chart, LAYOUT.with_rig(parse_rig("pro+gloves")))
    assert track.layout == "pro+gloves" and len(track.actuators) == 32 + 12
    path = tmp_path / "rig.html"
    write_page(path, [track], None)
    st = open_ready(page, path.as_uri())
    np.testing.assert_array_equal(st["intensities"], np.rint(track.intensities[0]))
    cells = dom_cells(page)
    assert set(cells) == set(track.actuators)
    assert cells["GloveL_4"][0] == 90 and cells["GloveR_4"][0] == 0
    label = page.evaluate("document.querySelector('.act[data-id=\"GloveL_4\"]').dataset.label")
    assert label == "little"
    assert sorted(_boxes(page)) == ["GloveL", "GloveR", "VestBack", "VestFront"]
    assert page.errors == []

"""A publisher restarted with another frame format, and a seat after its show ended, each against a real
nats-server."""

from __future__ import annotations

import asyncio
import logging
import time

import hapmotion
import pytest
from support.audience import REHEARSAL, Tap, start_seat, stop
from support.bounded import run_within
from support.live_fakes import BVH, wait_for

from hapmotion.audience import Seat, listen
from hapmotion.audience.compact import frame_encoder
from hapmotion.audience.connection import connect, description_bucket
from hapmotion.audience.publisher import describe_show
from hapmotion.audience.wire import encode_event, subject
from hapmotion.body.model import BodyModel
from hapmotion.layout import load_layout
from hapmotion.show import OutputStage, Show


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 120)


def description(motion, epoch: int, **frames):
    s, layout = Show(), load_layout()
    return describe_show("changing", show=s, stage=OutputStage.for_show(s, "motion", layout=layout, fps=motion.fps),
                         layout=layout, body=BodyModel.from_motion(motion), stall_ms=250.0, mirror=True,
                         epoch=epoch, **frames)


def test_frames_of_a_new_format_before_its_description_are_format_changing_not_malformed(nats_server, motion,
                                                                                          live_log):
    full, compact = description(motion, 1), description(motion, 2, frames="compact")
    assert (full.frame_version, compact.frame_version) == (1, 2)
    encode = frame_encoder(compact.frame_version, compact.frame_joints)

    async def scenario():
        tap = Tap()
        nc = await connect(nats_server.url, name="venue")
        kv = await description_bucket(nc)
        await kv.put("changing", full.to_json())
        task, sessions = await start_seat(f"{nats_server.url}/changing", [lambda d, f: tap], Seat())
        engine = sessions[0][0]
        # the restarted publisher's compact frames arrive before its description is stored
        for k in range(20):
            await nc.publish(subject("changing", "frame"),
                             encode(compact.epoch, k, k / motion.fps, time.time(), motion.positions[k], None))
        await nc.flush()
        await asyncio.sleep(0.5)
        counts = dict(engine.faults.counts)
        played_before = len(tap.rendered())
        await nc.close()
        await stop(task)
        return counts, played_before

    counts, played_before = run_within(scenario(), 30)
    assert counts.get("format_changing", 0) == 20 and counts.get("malformed", 0) == 0, counts
    assert played_before == 0                      # never decoded with the full frames' decoder
    text = " ".join(r.getMessage() for r in live_log)
    assert "malformed" not in text and "format is changing" in text, text
    assert not [r for r in live_log if r.levelno >= logging.WARNING and "format" in r.getMessage()]


def test_a_seats_recording_stops_when_the_show_ends_and_the_next_show_records_to_a_numbered_file(nats_server,
                                                                                                  motion, tmp_path):
    first, second = description(motion, 21), description(motion, 22)
    encode = frame_encoder(first.frame_version, first.frame_joints)
    path = tmp_path / "seat.csv"

    async def play(nc, desc, n: int) -> None:
        kv = await description_bucket(nc)
        await kv.put("changing", desc.to_json())
        await asyncio.sleep(0.3)
        for k in range(n):
            await nc.publish(subject("changing", "frame"),
                             encode(desc.epoch, k, k / motion.fps, time.time(), motion.positions[k], None))
            await asyncio.sleep(1 / motion.fps)
        await nc.publish(subject("changing", "end"), encode_event(epoch=desc.epoch, seq=1, t=n / motion.fps))
        await nc.flush()

    async def scenario():
        nc = await connect(nats_server.url, name="venue")
        task = asyncio.create_task(listen(f"{nats_server.url}/changing", [f"record:{path}"], seat=Seat(),
                                          security=REHEARSAL, handle_signals=False))
        await asyncio.sleep(0.5)
        await play(nc, first, 60)
        # the show is over: its recording is written and stays as it is while the seat waits
        await wait_for(lambda: path.exists() or task.done(), 10)
        assert not task.done()
        size = path.stat().st_size
        await asyncio.sleep(1.5)
        assert path.stat().st_size == size and not task.done()
        await play(nc, second, 30)                # the next show: a new recording beside the first
        await wait_for(lambda: (tmp_path / "seat-2.csv").exists() or task.done(), 10)
        await stop(task)
        await nc.close()

    run_within(scenario(), 60)
    rows = hapmotion.load_track(path).intensities
    # 60 frames, the fade (stall_ms 250) and a few rows of margin (0.4 s: the end's timer, the recorder's flush);
    # not the 1.5 s of silence waited after it
    assert 60 <= len(rows) <= 60 + (0.25 + 0.4) * motion.fps, len(rows)
    assert rows.max() > 0 and not rows[-1].any()
    assert 30 <= len(hapmotion.load_track(tmp_path / "seat-2.csv").intensities) <= 30 + (0.25 + 0.4) * motion.fps


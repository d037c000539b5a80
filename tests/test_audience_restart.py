"""A publisher restarted with another frame format, a seat waiting before the show, and a seat after its show ended,
each against a real nats-server."""

from __future__ import annotations

import asyncio
import logging
import time

import hapmotion
import pytest
from support.audience import Tap, start_seat, stop
from support.live_fakes import BVH, wait_for

from hapmotion.audience import Seat
from hapmotion.audience.compact import frame_encoder
from hapmotion.audience.connection import connect, description_bucket
from hapmotion.audience.publisher import describe_show
from hapmotion.audience.wire import subject
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

    counts, played_before = asyncio.run(asyncio.wait_for(scenario(), 30))
    assert counts.get("format_changing", 0) == 20 and counts.get("malformed", 0) == 0, counts
    assert played_before == 0                      # never decoded with the full frames' decoder
    text = " ".join(r.getMessage() for r in live_log)
    assert "malformed" not in text and "format is changing" in text, text
    assert not [r for r in live_log if r.levelno >= logging.WARNING and "format" in r.getMessage()]

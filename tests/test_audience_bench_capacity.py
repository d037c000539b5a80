"""The audience capacity sweep's parts: a load-generator seat moved to another show receives that show's frames
only, the fit and the saturation figure on numbers worked out by hand, the server counters read from /proc, and the
perf report read as its text says. Not timed."""

from __future__ import annotations

import asyncio
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.wire import encode_frame, subject

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the benchmarks package lives beside tests/ (python -m pytest puts it there too)
    sys.path.insert(0, str(ROOT))
from benchmarks import bench_audience_capacity as cap  # noqa: E402
from benchmarks import bench_audience_load as load  # noqa: E402
from support.bounded import run_within


def test_a_seat_moved_to_another_show_receives_only_that_shows_frames():
    # one publisher connection: its messages reach a subscriber in the order sent, so once a show's last frame has
    # arrived, a frame of the other show sent before it would have arrived first had the seat been subscribed to it
    async def until(predicate) -> None:
        for _ in range(500):
            if predicate():
                return
            await asyncio.sleep(0.02)
        raise AssertionError("not received in 10 s")

    async def scenario():
        with LocalNatsServer() as server:
            _, writer = await asyncio.open_connection("127.0.0.1", server.port)
            writer.write(b'CONNECT {"verbose":false,"pedantic":false}\r\n')

            async def publish(show: str, seq: int) -> None:
                payload = encode_frame(1, seq, seq / 60, time.time(), np.zeros((32, 3)), None)
                writer.write(f"PUB {subject(show, 'frame')} {len(payload)}\r\n".encode() + payload + b"\r\n")
                await writer.drain()

            ages: list[float] = []
            marks = {"on": True}
            conn = await load.open_light_connection(server.url, 1, ages, marks, show="one")
            for seq in range(1, 4):
                await publish("two", 100 + seq)
                await publish("one", seq)
            await until(lambda: marks.get("last") == 3)
            assert conn.count == 3

            conn.follow(subject("two", "frame"))
            probe = 200
            while marks["last"] < 200:  # the new subscription in place (another connection: no order between them)
                probe += 1
                await publish("two", probe)
                await asyncio.sleep(0.02)
            await until(lambda: marks["last"] == probe)
            base = conn.count
            for seq in range(4, 9):
                await publish("one", seq)
                await publish("two", 100 + seq)
            await until(lambda: marks["last"] == 108)
            assert conn.count - base == 5
            assert all(0 <= a < 10 for a in ages)
            conn.transport.close()
            writer.close()

    run_within(scenario(), 60)


def test_fit_and_saturation_on_numbers_worked_out_by_hand():
    # 2 % of a core fixed, 0.05 % a seat: a core at (1 - 0.02) / 0.0005 = 1,960 seats
    ns = [200, 500, 900]
    a, b = cap.fit(ns, [0.02 + 0.0005 * n for n in ns])
    assert a == pytest.approx(0.02) and b == pytest.approx(0.0005)
    assert cap.saturation(a, b) == pytest.approx(1960.0)
    assert cap.saturation(0.01, 0.0) == float("inf")  # a server whose CPU does not grow with the seats


def test_server_counters_follow_this_process():
    before = cap.server_counters(os.getpid())
    fd = os.open(os.devnull, os.O_WRONLY)
    try:
        for _ in range(50):
            os.write(fd, b"x")
    finally:
        os.close(fd)
    end = time.process_time() + 0.05
    while time.process_time() < end:
        pass
    after = cap.server_counters(os.getpid())
    assert after["writes"] - before["writes"] >= 50
    assert after["cpu"] - before["cpu"] >= 0.04  # nanoseconds on a CPU, summed over the threads
    assert all(after[k] >= before[k] for k in before)


REPORT = """# Total Lost Samples: 0
#
# Samples: 920  of event 'cpu-clock:pppH'
# Event count (approx.): 1843687310
#
# Children      Self  Symbol
# ........  ........  ..............................................
#
    91.12%     0.00%  [.] runtime.goexit.abi0
    78.48%     1.08%  [.] github.com/nats-io/nats-server/v2/server.(*client).writeLoop
    39.43%     0.67%  [k] do_syscall_64
    13.50%     0.00%  [.] github.com/nats-io/nats-server/v2/server.(*client).readLoop
     3.50%     0.54%  [.] runtime.sysmon
     2.50%     0.54%  [.] runtime.schedule
     0.40%     0.40%  [.] runtime.(*timers).schedule
"""


def test_the_perf_report_is_read_by_function():
    shares = cap.perf_shares(REPORT)
    assert shares == {"samples": 920.0, "seats' write path": 78.48, "fan-out": 13.5, "sysmon": 3.5,
                      "scheduler": 2.5}


def synthetic_rows(rate: float, per_write: float, late: float = 0.0) -> list[tuple[int, int, dict]]:
    """Windows of a server costing 2 % of a core plus ``per_write`` seconds a write call, at N = 200, 500, 900 in
    two passes, ``late`` of the messages at N = 900 written together with the one before."""
    rows = []
    for n in (0, 200, 500, 900):
        for p in (0, 1):
            delivered = n * rate
            writes = delivered * (1 - (late if n == 900 else 0.0))
            rows.append((n, p, {"cpu": 0.02 + per_write * writes, "writes": writes, "delivered": delivered,
                                "p99": 10.0}))
    return rows


def test_summary_counts_seats_with_every_message_written_on_its_own(capsys):
    # 12 us a write: (1 - 0.02) / (12e-6 x 60) = 1,361 seats per core at 60 Hz and 2,722 at 30 Hz (2.00x), even
    # when the 60 Hz server wrote a third of its messages at N = 900 together with the one before (late), which
    # flatters the line through N (the reference's CPU bends down)
    rows = {"full@60": synthetic_rows(60.0, 12e-6, late=1 / 3), "compact@30": synthetic_rows(30.0, 12e-6)}
    cap.summarise(rows, {"full@60": ("full", 60.0), "compact@30": ("compact", 30.0)}, [0, 200, 500, 900])
    out = capsys.readouterr().out
    assert "1,361 seats per server core with every message written on its own" in out
    assert "2,722 seats per server core with every message written on its own" in out
    assert "(every message written on its own): 2.00x" in out and "met]" in out
    fitted = float(out.split("(the lines through N): ")[1].split("x")[0])
    assert fitted < 2.0  # the late 60 Hz writes make today's frames look cheaper per message


def test_the_help_is_whole_shows_defaults_and_a_short_run(capsys):
    with pytest.raises(SystemExit):
        cap.main(["--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "swept over the number of seats, per stream, fitted as a fixed part plus a part per seat." in out, out
    assert "(default: 0,200,500,900)" in out and "(default: full@60,compact@30,packed@30)" in out, out
    assert f"A short run: python -m benchmarks.bench_audience_capacity {cap.SHORT_RUN}" in out, out
    with pytest.raises(SystemExit):
        cap.main(["--steps", "0,200"])
    assert cap.SHORT_RUN in capsys.readouterr().err


def test_a_step_without_seats_prints_a_dash_not_nan():
    assert cap.ratio(0.05, 0, 1e6) == "    -" and cap.ratio(0.05, 1000, 1e6) == " 50.0"
    assert cap.ratio(3.0, 0, fmt=".2f") == "-" and cap.ratio(3.0, 2, fmt=".2f") == "1.50"
    assert "nan" not in cap.ratio(float("nan"), 0, 1, ".1f")


def test_the_control_splits_the_seats_evenly():
    # the default steps' groups (200, 300 and 400 seats): 400 on one side, 300 + 200 on the other
    assert cap.halves([200, 300, 400]) == ([2], [1, 0])
    assert cap.halves([100, 100]) == ([0], [1])
    assert cap.halves([50, 100, 150, 200]) == ([3, 0], [2, 1])


def test_the_control_reads_each_write_above_the_idle_seats(capsys):
    # idle seats 2 % of a core; at N = 900 a 60 Hz write 10 us, a 30 Hz one 12.5 us, and 12 us with the server woken
    # 60 times a second: the wake-ups take (12.5 - 12) / (12.5 - 10) = 20 % of the difference away; the sweep's
    # compact 30 Hz stream at 12.5 us a write against today's 60 Hz at 10: 2 / 1.25 = 1.60x the seats
    def window(rate: float, per_write: float) -> dict:
        writes = 900 * rate
        return {"cpu": 0.02 + per_write * writes, "writes": writes, "delivered": writes}

    rows = {"full@60": [(900, p, window(60.0, 10e-6)) for p in (0, 1)] + [(500, 0, window(60.0, 99e-6))],
            "compact@30": [(900, p, window(30.0, 12.5e-6)) for p in (0, 1)]}
    idle = {"cpu": 0.02, "writes": 0.0, "delivered": 0.0}
    control = {"idle": [idle, idle], "30 Hz": [window(30.0, 12.5e-6)] * 2, "halves": [window(30.0, 12e-6)] * 2,
               "60 Hz": [window(60.0, 10e-6)] * 2}
    out = cap.summarise_control(rows, control, 900)
    assert out["idle"] == pytest.approx(0.02)
    assert out["30 Hz"] == pytest.approx(12.5) and out["halves"] == pytest.approx(12.0)
    assert out["60 Hz"] == pytest.approx(10.0) and out["explained"] == pytest.approx(0.2)
    assert out["per:full@60"] == pytest.approx(10.0)  # the windows at N = 900 only
    text = capsys.readouterr().out
    assert "a 30 Hz write costs 1.25x a 60 Hz one" in text and "takes 20 % of the difference away" in text
    assert "compact@30: 12.50 us a write against 10.00 for full@60 (1.25x)" in text
    assert "375 us a second a seat against 600: 1.60x the seats" in text and "[reported: one N" in text


def test_the_control_counts_the_seats_on_cpu_not_on_writes_when_a_late_server_coalesces(capsys):
    # today's 60 Hz at 10 us a write but 0.8 writes a message (the server ran late and wrote some messages in pairs):
    # 480 us a second a seat; compact 30 Hz at 12.5 us, one write a message: 375 us. 480 / 375 = 1.28x the seats,
    # not the 2 / 1.25 = 1.60x that the write's cost times the message rate would give
    def window(rate: float, per_write: float, writes_a_message: float) -> dict:
        writes = 900 * rate * writes_a_message
        return {"cpu": 0.02 + per_write * writes, "writes": writes, "delivered": 900 * rate}

    rows = {"full@60": [(900, p, window(60.0, 10e-6, 0.8)) for p in (0, 1)],
            "compact@30": [(900, p, window(30.0, 12.5e-6, 1.0)) for p in (0, 1)]}
    idle = {"cpu": 0.02, "writes": 0.0, "delivered": 0.0}
    control = {"idle": [idle, idle], "30 Hz": [window(30.0, 12.5e-6, 1.0)] * 2,
               "halves": [window(30.0, 12e-6, 1.0)] * 2, "60 Hz": [window(60.0, 10e-6, 1.0)] * 2}
    cap.summarise_control(rows, control, 900)
    assert "480: 1.28x the seats" in capsys.readouterr().out


def test_the_bare_publisher_plays_its_streams_half_a_period_apart():
    # a light seat on each stream: 60 Hz gets every tick, the two 30 Hz streams the even and the odd ones
    async def scenario():
        with LocalNatsServer() as server:
            seen: dict[str, list[int]] = {}
            conns = {}
            for show in ("bare60", "bare30a", "bare30b"):
                marks: dict = {"on": True}
                conns[show] = (await load.open_light_connection(server.url, 1, [], marks, show=show), marks)
            with cap.BarePublisher(server.url) as pub:
                while pub.sent < 60:  # 30 ticks, however slowly this machine plays them
                    await asyncio.sleep(0.05)
            for _ in range(200):  # every message sent delivered (one connection: in order)
                if conns["bare60"][0].count * 2 >= pub.sent:
                    break
                await asyncio.sleep(0.05)
            for show, (conn, marks) in conns.items():
                seen[show] = [conn.count, marks.get("last", -1)]
                conn.transport.close()
            return seen, pub.sent

    seen, sent = asyncio.run(asyncio.wait_for(scenario(), 60))
    assert seen["bare60"][0] >= 30 and sent == 2 * seen["bare60"][0]
    assert abs(seen["bare30a"][0] - seen["bare30b"][0]) <= 1
    assert seen["bare30a"][0] + seen["bare30b"][0] == seen["bare60"][0]
    assert seen["bare30a"][1] % 2 == 0 and seen["bare30b"][1] % 2 == 1

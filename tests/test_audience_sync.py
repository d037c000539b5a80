"""A seat synchronised to what it hears, end to end against a real nats-server: the publisher's music reference (signed
on a venue's server), a seat reading the heard audio from a file locks on the true offset and plays the frames
there; a seat hearing another song never locks and plays at the manual delay or not at all; the command line."""

from __future__ import annotations

import asyncio
import logging
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf
from click.testing import CliRunner
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from support.audience import REHEARSAL, SONG, Venue, stop
from support.bounded import run_within
from support.live_fakes import PlayTimes, start_session, wait_for
from support.sync_signals import SR, real_song

import hapmotion
from hapmotion.audience import PublisherSecurity, Seat, listen, publishing
from hapmotion.audience.seat_sync import HINT_S, MAX_EDGES, STEP_S, SeatSync, SyncSettings
from hapmotion.audio.sync_features import LevelStream
from hapmotion.audience.signing import SeatTrust, VenueSigner
from hapmotion.audience.sync_tracker import ASSUMED_CONFIDENCE, SyncState
from hapmotion.audience.sync_reference import encode_batch
from hapmotion.cli.listen import command

pytestmark = pytest.mark.slow

LEAD_S = 2.5
"""Silence before the song in the heard file: the seat hears media time 0 at the file's start + LEAD_S."""




def heard_file(tmp_path, music: np.ndarray) -> str:
    path = tmp_path / "heard.wav"
    sf.write(path, np.concatenate([np.zeros(int(LEAD_S * SR)), music]), SR)
    return str(path)


async def show_and_seats(url: str, heard: str, *, unsynced: tuple[str, ...] = ("delay",), seconds: float = 14.0,
                         publisher=PublisherSecurity(unsigned=True), seat_security=REHEARSAL, end_show: bool = False):
    """The song published as a music-only show (the venue's reference with it) and one seat listening to ``heard``
    for each of ``unsynced`` (what it does while unlocked); returns [(play times, the seat's sync, its source)], one a
    seat. With ``end_show`` the publisher ends the show after ``seconds`` and the seats get 8 s to end their
    sessions (``source.over``, the engine stopped by itself) before they are stopped."""
    taps = [PlayTimes() for _ in unsynced]
    session_lists: list[list] = [[] for _ in unsynced]
    # the seats wait for the show, as an audience does: they hold the reference from the show's start
    seat_tasks = [asyncio.create_task(listen(url, [lambda d, f, t=tap: t], seat=Seat(), security=seat_security,
                                             sync=SyncSettings(input=f"file:{heard}", unsynced=mode, max_delay_s=5.0),
                                             handle_signals=False, sessions=sessions))
                  for tap, mode, sessions in zip(taps, unsynced, session_lists)]
    await asyncio.sleep(1.0)
    with publishing(publisher):
        show_task, _ = await start_session(None, [url.replace("tls://", "nats://")], audio=SONG, mode="audio")
    try:
        await wait_for(lambda: all(sessions or task.done() for sessions, task in zip(session_lists, seat_tasks)), 10)
        await asyncio.sleep(seconds)
        sources = [sessions[-1][1] for sessions in session_lists]
        if end_show:
            await stop(show_task)
            try:
                # the show over and each session ended by itself (stopped after that, it would say it was cancelled)
                await wait_for(lambda: all(source.over and source.engine.stats.stop_reason for source in sources), 8)
            except AssertionError:
                pass  # the test says what it expected
    finally:
        for task in seat_tasks:
            await stop(task)
        await stop(show_task)
    return [(tap, source.sync, source) for tap, source in zip(taps, sources)]


async def show_and_seat(url: str, heard: str, **kwargs):
    """:func:`show_and_seats` with one seat: (play times, the seat's sync, its source)."""
    return (await show_and_seats(url, heard, **kwargs))[0]


def test_a_seat_locks_on_the_heard_music_and_plays_each_frame_when_it_is_heard(nats_server, tmp_path, caplog):
    heard = heard_file(tmp_path, real_song(seconds=20.0))
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        tap, sync, _ = run_within(show_and_seat(f"{nats_server.url}/synced", heard), 60)
    truth = sync.audio.started + LEAD_S     # local time minus media time of what the seat heard
    locked = [(at, s) for at, _, s in sync.estimates if s.state == "locked"]
    assert locked, "the seat never locked"
    assert locked[0][0] - truth < 5.0        # within 5 s of the music starting
    assert all(abs(s.offset_s - truth) < 0.010 for _, s in locked)
    assert sync.state.state == "locked" and sync.state.confidence > 0.4
    assert 0.0 < sync.delay_behind_edge < 5.0
    played = np.array([(w, t) for w, t in tap.frames if w > locked[0][0] + 0.5])
    assert len(played) > 200
    skew = played[:, 0] - (played[:, 1] + truth)
    # the engine hands a frame on as it becomes due; a loaded machine can hold the loop up now and then
    assert abs(np.median(skew)) < 0.015
    assert np.percentile(np.abs(skew), 90) < 0.050
    # the lock moved the frames later by the delay found: the frames of that last stretch, played before at the
    # manual delay (0), play again in step, so the vest goes on instead of pausing for the delay
    assert sync.delay_behind_edge > 0.5
    around = np.array([(w, t) for w, t in tap.frames if locked[0][0] - 0.5 < w < locked[0][0] + 2.0])
    assert np.diff(around[:, 0]).max() < 0.5  # (1.4 s, the delay found, when the played frames were gone)
    after = np.array([t for w, t in tap.frames if w > locked[0][0] + 0.1])
    assert after[0] < locked[0][0] + 0.1 - truth + 0.1  # the first frame after the lock is the one due then
    said = [m for m in caplog.messages if "frames played again" in m]
    behind = [float(m.split("now ")[1].split(" ms")[0]) for m in said]
    assert behind and abs(behind[0] - sync.delay_behind_edge * 1000) < 50, said   # the delay the seat locked on


def test_seats_hearing_another_song_never_lock_and_play_as_their_users_chose(nats_server, tmp_path):
    heard = heard_file(tmp_path, real_song("lets_go_fishin.ogg", 20.0))
    (tap_delay, sync_delay, _), (tap_silent, sync_silent, _) = run_within(
        show_and_seats(f"{nats_server.url}/other", heard, unsynced=("delay", "silent"), seconds=12.0), 60)
    for sync in (sync_delay, sync_silent):
        assert sync.estimates and all(s.state == "searching" for _, _, s in sync.estimates)
        assert sync.tracker.locks == 0
    assert len(tap_delay.frames) > 300      # the manual delay (0 ms): every frame plays at the live edge
    assert tap_silent.frames == []          # the vest stays still


def test_a_signed_show_carries_a_signed_reference_that_a_checking_seat_locks_on(tmp_path):
    venue = Venue(tmp_path, show="signedsync").__enter__()
    try:
        heard = heard_file(tmp_path, real_song(seconds=14.0))
        url = f"{venue.url}/signedsync"
        tap, sync, source = run_within(show_and_seat(url, heard, seconds=11.0, publisher=venue.publisher(),
                                                     seat_security=venue.seat(), end_show=True), 60)
    finally:
        venue.__exit__()
    assert sync.faults == {}
    assert sync.tracker.locks == 1
    assert abs(sync.state.offset_s - (sync.audio.started + LEAD_S)) < 0.010
    # the venue ended the show: once the frames the seat holds for the music 2.5 s behind have played, its session
    # ends (its recordings are finished), as an unsynchronised seat's does, and says why
    assert source.over and source.engine.stats.stop_reason == "the show ended"


def test_a_forged_reference_is_dropped_and_counted(tmp_path):
    heard = heard_file(tmp_path, np.zeros(SR))
    venue_key, other_key = Ed25519PrivateKey.generate(), Ed25519PrivateKey.generate()
    sync = SeatSync(SyncSettings(input=f"file:{heard}"))
    sync.trust = SeatTrust("s", venue_key.public_key())
    sync.follow(1)
    batch = encode_batch(1, 1, 0.0, 0, np.full((50, 5), 100, dtype=np.uint8))

    sync.receive(batch, 1.0)                                                     # unsigned
    sync.receive(VenueSigner("s", other_key).seal("sync", batch), 1.0)           # someone else's key
    sync.receive(VenueSigner("s", venue_key).seal("frame", batch), 1.0)          # a frame's signature
    sync.receive(VenueSigner("s", venue_key).seal("sync", batch), 1.0)           # the venue's
    sync.receive(VenueSigner("s", venue_key).seal("sync", batch), 1.0)           # replayed
    sync.audio.close()
    assert sync.faults == {"bad_signature": 3, "replayed": 1}
    assert np.isfinite(sync.store.span(0, 50)).all()


def test_a_publisher_of_the_levels_only_version_is_refused_in_one_line_logged_once(tmp_path, caplog):
    sync = _rehearsal_sync(tmp_path)
    old = encode_batch(1, 1, 0.0, 0, np.full((50, 5), 100, dtype=np.uint8))[:32 + 250]
    old = old[:2] + bytes([1]) + old[3:]   # version 1: the levels alone, as publishers before the chroma sent them
    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        for k in range(3):
            sync.receive(old[:8] + bytes([k + 1]) + old[9:], 100.0 + k)
    sync.audio.close()
    assert sync.faults == {"version": 3} and not np.isfinite(sync.store.span(0, 50)).any()
    said = [r.getMessage() for r in caplog.records if "version" in r.getMessage()]
    assert len(said) == 1 and "\n" not in said[0]
    assert "version 1" in said[0] and "version 2" in said[0] and "older hapmotion" in said[0]


def test_list_audio_inputs_works_without_a_show_or_a_sound_card():
    result = CliRunner().invoke(command, ["--list-audio-inputs"])
    assert result.exit_code == 0, result.output
    assert "file:PATH" in result.output and "raw:" in result.output


def test_sync_options_on_the_command_line(tmp_path):
    runner = CliRunner()
    base = ["nats://127.0.0.1:1/x", "--unsigned", "--sink", "player"]
    result = runner.invoke(command, base + ["--audio-input", "mic"])
    assert result.exit_code == 2 and "--sync audio" in result.output
    result = runner.invoke(command, base + ["--sync", "audio", "--sync-max-delay", "100"])
    assert result.exit_code != 0 and "--sync-max-delay" in str(result.exception or result.output)


def test_a_device_that_is_not_there_is_one_line_from_the_real_command():
    """With or without a sound system, a device that does not exist stops the seat with one line (no traceback),
    before it connects anywhere."""
    env = {**os.environ, "PYTHONPATH": str(Path(hapmotion.__file__).parents[1])}
    done = subprocess.run([sys.executable, "-m", "hapmotion", "listen", "nats://127.0.0.1:1/x", "--unsigned",
                           "--sink", "player", "--sync", "audio", "--audio-input", "device:no such device 81b2"],
                          capture_output=True, text=True, timeout=60, env=env)
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert done.returncode != 0
    assert len(lines) == 1 and "audio" in lines[0] and "Traceback" not in done.stderr, done.stderr


def _rehearsal_sync(tmp_path) -> SeatSync:
    """A seat's sync on an unsigned show, fed through :meth:`SeatSync.receive` (the parse path of every message)."""
    sync = SeatSync(SyncSettings(input=f"file:{heard_file(tmp_path, np.zeros(SR))}"))
    sync.trust = SeatTrust.unsigned("s")
    sync.follow(1)
    return sync


def _real_batches(sync: SeatSync, first: int, count: int, t0: float, edge: float) -> None:
    """The publisher's batches ``first ..``: batch k sent at media time k / 2, arriving ``edge`` s later, 0.5 s
    apart (local time ``t0 + k / 2 + edge``)."""
    for k in range(first, first + count):
        sync.receive(encode_batch(1, k, k * 0.5, k * 50, np.full((50, 5), 100, dtype=np.uint8)),
                     t0 + k * 0.5 + edge)


def test_a_forged_far_future_seq_on_an_unsigned_show_does_not_silence_the_reference(tmp_path):
    sync = _rehearsal_sync(tmp_path)
    _real_batches(sync, 1, 4, 100.0, 0.2)
    sync.receive(encode_batch(1, 0xFFFFFFFF, 2.5, 250, np.zeros((50, 5), dtype=np.uint8)), 102.3)
    assert sync.faults == {"seq_jump": 1}                       # refused at once: the time since allows a few
    _real_batches(sync, 5, 4, 100.0, 0.2)
    assert sync._last[0] == 8 and sync.faults == {"seq_jump": 1}  # every real batch after it accepted
    assert np.isfinite(sync.store.span(350, 50)).all()
    # the forgery as the very first batch a seat sees: the real ones count as replayed until RESYNC_S has passed,
    # then the seat starts afresh on them
    sync = _rehearsal_sync(tmp_path)
    sync.receive(encode_batch(1, 0xFFFFFFFF, 0.0, 0, np.zeros((50, 5), dtype=np.uint8)), 100.0)
    _real_batches(sync, 1, 10, 100.0, 0.2)
    assert sync.faults["replayed"] == 4 and sync.faults["resync"] == 1
    assert sync._last[0] == 10 and np.isfinite(sync.store.span(500, 50)).all()
    assert sync._edge == pytest.approx(100.2)


def test_a_forged_far_future_sent_t_does_not_pin_the_live_edge(tmp_path):
    sync = _rehearsal_sync(tmp_path)
    _real_batches(sync, 1, 4, 100.0, 0.2)
    assert sync._edge == pytest.approx(100.2)                    # arrival minus media time
    sync.receive(encode_batch(1, 5, 1e6, 250, np.zeros((50, 5), dtype=np.uint8)), 102.3)
    assert sync.faults == {"time_jump": 1} and sync._edge == pytest.approx(100.2)
    _real_batches(sync, 5, 4, 100.0, 0.2)
    assert sync.faults == {"time_jump": 1} and sync._last[0] == 8
    # as the first batch: the next real one goes back in media time, and the edge is measured afresh from it
    sync = _rehearsal_sync(tmp_path)
    sync.receive(encode_batch(1, 1, 1e6, 0, np.zeros((50, 5), dtype=np.uint8)), 100.0)
    assert sync._edge == pytest.approx(100.0 - 1e6)
    _real_batches(sync, 2, 3, 100.0, 0.2)
    assert sync._edge == pytest.approx(100.2) and sync.faults == {}


def test_the_live_edge_keeps_a_bounded_number_of_arrivals(tmp_path):
    sync = _rehearsal_sync(tmp_path)
    # a flood within the edge's time window, each arriving later than the last against its media time (the case
    # a time window alone keeps every one of), as fast as the seq bound lets through
    for k in range(1, 2001):
        sync.receive(encode_batch(1, k, k * 0.001, k, np.zeros((1, 5), dtype=np.uint8)), 100.0 + k * 0.002)
    assert len(sync._edges) <= MAX_EDGES
    assert sync._edge is not None and math.isfinite(sync._edge)


@pytest.mark.skipif(os.name == "nt", reason="named pipes and signals as on POSIX")
def test_a_seat_on_a_named_pipe_whose_writer_has_not_started_runs_and_stops_on_ctrl_c(nats_server, tmp_path):
    # the writer starts with the show, after the seat: the seat does not wait for it to connect and say so, and
    # Ctrl-C stops it (it sat blocked on the pipe, deaf to Ctrl-C, saying nothing)
    fifo = tmp_path / "heard.fifo"
    os.mkfifo(fifo)
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from hapmotion.cli import main; "
                             "sys.exit(main(sys.argv[1:]))", "listen", f"{nats_server.url}/later", "--unsigned",
                             "--sink", f"record:{tmp_path / 'seat.csv'}", "--sync", "audio", "--audio-input",
                             f"wav:{fifo}"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, "")), daemon=True)
    reader.start()
    try:
        wait_until = time.monotonic() + 30
        while not any("listening to wav stream" in line for line in lines):
            assert time.monotonic() < wait_until and proc.poll() is None, f"no start-up line: {lines}"
            time.sleep(0.05)
        assert any("waiting for its writer to start" in line for line in lines), lines
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=20)
        reader.join(5)
    finally:
        proc.kill()
    assert proc.returncode in (0, 130), (proc.returncode, lines)
    assert not any("Traceback" in line for line in lines), lines


@pytest.mark.parametrize("heard, kind", [("silence", "silent_input"), ("tone", "no_onsets")])
def test_a_seat_that_hears_nothing_to_match_says_so_once(tmp_path, caplog, heard, kind):
    # a seat holding the venue's music that hears silence (a muted stream, the wrong device) or a steady tone (a raw
    # stream read in the wrong format sounds as flat) searches for ever: after HINT_S of it, it says which, once
    sync = _rehearsal_sync(tmp_path)
    _real_batches(sync, 1, 40, 100.0, 0.2)
    t = np.arange(int(3.0 * SR)) / SR
    audio = np.zeros(t.size) if heard == "silence" else 0.3 * np.sin(2 * np.pi * 440 * t)
    levels = LevelStream(SR).push(audio)
    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        for k in range(int(HINT_S / STEP_S) + 20):
            sync._step(levels, 110.0 + k * STEP_S)
    assert sync.faults == {kind: 20 + 1}
    said = [m for m in caplog.messages if kind.replace("_", " ") in m or "silent for" in m or "nothing to match" in m]
    assert len(said) == 1 and ("silent for 10 s" if heard == "silence" else "&format=") in said[0], said


def test_a_seat_whose_input_ends_stops_saying_it_hears_the_music(tmp_path, caplog):
    # a locked seat whose pipe or file ends keeps the delay it held (the stream most likely plays on) but says it
    # lost the music, at a guess's confidence, instead of reporting the lock for ever
    sf.write(tmp_path / "short.wav", np.zeros(SR // 2), SR)     # half a second: it ends before a window is full
    sync = SeatSync(SyncSettings(input=f"file:{tmp_path / 'short.wav'}"))
    sync.state = SyncState("locked", 2.0, 0.8)
    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        sync._listen()                                   # reads the file to its end in this thread
    assert sync.state.state == "lost" and sync.state.offset_s == 2.0 and sync.state.confidence <= ASSUMED_CONFIDENCE
    assert sum("no more audio to follow (holding the last delay)" in m for m in caplog.messages) == 1

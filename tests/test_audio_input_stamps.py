"""When a pipe's audio was heard: a live writer's as it arrives, a file's (a regular file, a file copied into a pipe)
in real time from the seat's first read, as ``file:`` plays it; and what a seat locks on either way."""

from __future__ import annotations

import contextlib
import io
import os
import threading
import time

import numpy as np
import pytest
import soundfile as sf
from support.sync_signals import SR, song

from hapmotion.audience.seat_sync import HeardClock
from hapmotion.audio.inputs import FAST_S, PipeInput


def wav_bytes(x: np.ndarray, sr: int = SR) -> bytes:
    buf = io.BytesIO()
    sf.write(buf, x, sr, format="WAV", subtype="PCM_16")
    return buf.getvalue()


def read_all(inp: PipeInput, audio_s: float = 30.0) -> tuple[list[int], list[float], float]:
    """Each block's size and stamp to the end or to ``audio_s`` of audio, and the perf_counter() just before the
    first read."""
    t0, sizes, stamps = time.perf_counter(), [], []
    while sum(sizes) < audio_s * inp.sample_rate and time.perf_counter() - t0 < audio_s + 30.0:
        block, t = inp.read()
        if block is None:
            break
        sizes.append(block.size)
        stamps.append(t)
    return sizes, stamps, t0


def assert_played_from_first_read(inp: PipeInput, sizes: list[int], stamps: list[float], t0: float) -> None:
    """Each block stamped when its last sample plays, the file played from the first read (as file: does)."""
    assert inp.paced is True
    ends = np.cumsum(sizes) / inp.sample_rate
    assert np.allclose(np.array(stamps) - ends, stamps[0] - ends[0], atol=1e-9)   # one clock: the sample clock
    assert 0.0 <= stamps[0] - ends[0] - t0 < 0.05                                # started at the first read


def test_a_wav_file_named_as_a_stream_plays_from_the_first_read_like_file(tmp_path):
    # wav:PATH on a regular file read as a pipe was stamped as it arrived: its first second, read at once, put the
    # whole file a second early (a seat locked 1 s short of the delay file: found)
    path = tmp_path / "heard.wav"
    path.write_bytes(wav_bytes(0.3 * song(3, 1.0)))
    inp = PipeInput(f"wav:{path}", "wav", str(path))
    sizes, stamps, t0 = read_all(inp)
    inp.close()
    assert sum(sizes) == SR
    assert_played_from_first_read(inp, sizes, stamps, t0)
    assert time.perf_counter() - t0 >= 0.98          # read in real time, not at once


@pytest.mark.parametrize("seconds", [FAST_S + 3.0, 3.0])
def test_a_file_copied_into_a_pipe_plays_from_the_first_read(tmp_path, seconds):
    # `cat heard.wav | hapmotion listen ... wav:-` (here a named pipe and a thread as cat): the writer hands over the
    # pipe's capacity plus FAST_S of audio at once, which no live capture has queued, or (a short file) its whole
    # stream, longer than the pipe holds, and ends: a file's audio either way
    fifo = tmp_path / "heard.fifo"
    os.mkfifo(fifo)
    data = wav_bytes(0.3 * song(4, seconds))

    def cat() -> None:
        with contextlib.suppress(BrokenPipeError), open(fifo, "wb") as f:   # (the reader stops after 1 s)
            f.write(data)

    writer = threading.Thread(target=cat)
    writer.start()
    inp = PipeInput(f"wav:{fifo}", "wav", str(fifo))
    sizes, stamps, t0 = read_all(inp, 1.0)   # the first second tells (read in real time: a second of the suite's)
    inp.close()
    writer.join(5)
    assert sum(sizes) >= SR
    assert_played_from_first_read(inp, sizes, stamps, t0)


def test_a_live_writer_with_a_queue_is_stamped_as_it_arrives(tmp_path):
    # a capture program started before the seat read (0.4 s queued in the pipe), then writing 20 ms every 20 ms:
    # its audio is stamped as it arrives (the seat's clock takes the earliest arrival), not played from the first read
    fifo = tmp_path / "live.fifo"
    os.mkfifo(fifo)
    x = 0.3 * song(5, 2.4)
    pcm = (x * 32767).astype("<i2").tobytes()
    block = int(0.02 * SR) * 2
    stop = threading.Event()

    def capture() -> None:
        with open(fifo, "wb", buffering=0) as f:
            queued = int(0.4 * SR) * 2
            f.write(pcm[:queued])
            start = time.perf_counter()
            for k, at in enumerate(range(queued, len(pcm), block)):
                if stop.is_set():
                    return
                time.sleep(max(0.0, start + (k + 1) * 0.02 - time.perf_counter()))
                f.write(pcm[at:at + block])

    writer = threading.Thread(target=capture)
    writer.start()
    inp = PipeInput(f"raw:{fifo}?rate={SR}&channels=1", "raw", f"{fifo}?rate={SR}&channels=1")
    try:
        sizes, stamps, t0 = read_all(inp)
    finally:
        stop.set()
        inp.close()
        writer.join(5)
    assert inp.paced is False
    assert sum(sizes) == len(pcm) // 2
    # the queued 0.4 s arrived at once: stamped before the sample clock from the first read would have them
    lag = np.array(stamps) - (t0 + np.cumsum(sizes) / SR)
    assert lag.min() < -0.25



def test_a_file_whose_writer_pauses_at_its_start_is_still_a_file(tmp_path):
    # a decoder or a network stream starting: 0.05 s of audio, a 0.15 s pause, then the rest at once (the first read
    # used to end at the first pause of 0.1 s and take the file for a live writer: a second early)
    fifo = tmp_path / "paused.fifo"
    os.mkfifo(fifo)
    data = wav_bytes(0.3 * song(7, FAST_S + 4.0))
    head = 44 + int(0.05 * SR) * 2

    def decoder() -> None:
        with contextlib.suppress(BrokenPipeError), open(fifo, "wb", buffering=0) as f:
            f.write(data[:head])
            time.sleep(0.15)
            f.write(data[head:])

    writer = threading.Thread(target=decoder)
    writer.start()
    inp = PipeInput(f"wav:{fifo}", "wav", str(fifo))
    sizes, stamps, t0 = read_all(inp, 1.0)
    inp.close()
    writer.join(5)
    assert_played_from_first_read(inp, sizes, stamps, t0)


def test_a_live_writer_s_long_queue_is_heard_when_it_was_recorded(tmp_path):
    # a capture program that had recorded 2 s before the seat's first read (8 kHz mono: a 64 KiB pipe holds 4 s)
    # hands them over at once, then writes in real time: the seat's clock (the earliest arrival) puts its first
    # sample 2 s before the writer started, as it was heard. Holding such a queue back to real time after 1 s (as a
    # runaway writer is held) put everything it sent a second late, for good
    fifo = tmp_path / "queued.fifo"
    os.mkfifo(fifo)
    sr, queued_s = 8000, 2.0
    pcm = (0.3 * song(9, 4.0, sr) * 32767).astype("<i2").tobytes()
    block = int(0.02 * sr) * 2
    started = []

    def capture() -> None:
        with contextlib.suppress(BrokenPipeError), open(fifo, "wb", buffering=0) as f:
            queued = int(queued_s * sr) * 2
            started.append(time.perf_counter())
            f.write(pcm[:queued])
            for k, at in enumerate(range(queued, len(pcm), block)):
                time.sleep(max(0.0, started[0] + (k + 1) * 0.02 - time.perf_counter()))
                f.write(pcm[at:at + block])

    writer = threading.Thread(target=capture)
    writer.start()
    inp = PipeInput(f"raw:{fifo}?rate={sr}&channels=1", "raw", f"{fifo}?rate={sr}&channels=1")
    clock = HeardClock(sr)
    try:
        while True:
            block_x, t = inp.read()
            if block_x is None:
                break
            zero = clock.push(block_x.size, t)
    finally:
        inp.close()
        writer.join(5)
    assert inp.paced is False
    assert zero == pytest.approx(started[0] - queued_s, abs=0.03)

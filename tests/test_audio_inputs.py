"""The seat's file and pipe audio inputs on hostile and streaming input: a file's sample rate is checked, a WAV
stream with a placeholder data size is read to its end, inf/NaN samples become 0 (counted), a pipe faster than
real time is held to real time (counted), and --sync-max-delay needs --sync audio."""

from __future__ import annotations

import logging
import os
import struct
import threading
import time

import click
import numpy as np
import pytest
from click.testing import CliRunner
from support.sync_signals import SR, real_song

from hapmotion.audio import inputs
from hapmotion.audio.inputs import open_input
from hapmotion.audio.sync_features import LevelStream
from hapmotion.cli.audience_options import seat_sync_options
from hapmotion.errors import InputError, UsageError


def wav_header(rate: int, channels: int, data_size: int, riff_size: int = 0xFFFFFFFF, tag: int = 1,
               bits: int = 16) -> bytes:
    fmt = struct.pack("<HHIIHH", tag, channels, rate, rate * channels * bits // 8, channels * bits // 8, bits)
    return (b"RIFF" + struct.pack("<I", riff_size) + b"WAVEfmt " + struct.pack("<I", 16) + fmt + b"data"
            + struct.pack("<I", data_size))


def read_all(inp) -> np.ndarray:
    got = []
    while True:
        block, _ = inp.read()
        if block is None:
            break
        got.append(block)
    inp.close()
    return np.concatenate(got) if got else np.zeros(0)


def from_pipe(payload: bytes):
    """A pipe whose writer sends ``payload`` and closes: the ``/dev/fd/N`` path of its reading end. A payload the
    pipe holds whole is in it before this returns (a reader that checks what is there at once finds it)."""
    r, w = os.pipe()
    if len(payload) <= 4096:
        with os.fdopen(w, "wb") as f:
            f.write(payload)
        return r, f"/dev/fd/{r}"

    def write() -> None:
        with os.fdopen(w, "wb") as f:
            f.write(payload)

    threading.Thread(target=write, daemon=True).start()
    return r, f"/dev/fd/{r}"


# ---------------------------------------------------------------------------------------------------- file:
def test_a_file_whose_header_claims_2_ghz_is_refused_in_one_line_naming_it(tmp_path):
    path = tmp_path / "liar.wav"
    path.write_bytes(wav_header(2_000_000_000, 1, 4000, riff_size=36 + 4000) + b"\x01\x00" * 2000)
    with pytest.raises(InputError) as info:
        open_input(f"file:{path}")
    text = str(info.value)
    assert "\n" not in text and str(path) in text and "4000..768000 Hz" in text and "2000000000" in text


# ---------------------------------------------------------------------------------------------------- wav:
@pytest.mark.parametrize("data_size,riff_size", [(0, 8), (0xFFFFFFFF, 0xFFFFFFFF), (0x7FFFF000, 0x7FFFF024)])
def test_a_streaming_wav_is_read_to_its_end(data_size, riff_size):
    """libsndfile writes RIFF size 8 and data size 0 to a pipe, ffmpeg 0xFFFFFFFF, arecord 0x7FFFF000: a real
    song's second comes through whole, and its levels equal those of the song itself."""
    song = real_song(seconds=1.0)
    pcm = np.round(song * 32767).astype("<i2")
    r, where = from_pipe(wav_header(SR, 1, data_size, riff_size) + pcm.tobytes())
    inp = open_input(f"wav:{where}")
    assert inp.sample_rate == SR
    x = read_all(inp)
    os.close(r)
    assert x.size == song.size
    assert np.abs(x - song).max() < 2 / 32768
    assert np.allclose(LevelStream(SR).push(x), LevelStream(SR).push(pcm / 32768.0))


def test_a_wav_stream_with_a_real_data_size_ends_there_and_skips_other_chunks():
    pcm = np.array([16384, -16384, 8192, 0] * 50, dtype="<i2").reshape(-1, 2)     # 100 stereo frames
    head = wav_header(8000, 2, pcm.nbytes)
    list_chunk = b"LIST" + struct.pack("<I", 5) + b"INFOx\x00"                      # odd size: padded
    blob = head[:36] + list_chunk + head[36:] + pcm.tobytes() + b"junk after the samples"
    r, where = from_pipe(blob)
    x = read_all(open_input(f"wav:{where}"))
    os.close(r)
    assert x.size == 100 and np.allclose(x[:2], [0.0, 0.125])


@pytest.mark.parametrize("blob,said", [
    (b"", "ended before sending anything"),
    (b"RIFF", "ended in the RIFF header"),
    (b"hello world!" * 3, "RIFF ... WAVE"),
    (wav_header(8000, 1, 0, bits=8), "found format 1 with 8-bit samples"),
    (b"RIFF\xff\xff\xff\xffWAVELIST" + struct.pack("<I", 200_000_000) + b"x" * 100, "at most 1048576 bytes"),
    (wav_header(1, 2, 0), "expected a rate of 4000..768000 Hz and 1..32 channels, found 1 Hz and 2 channels"),
])
def test_bad_wav_streams_are_one_line_errors(blob, said):
    r, where = from_pipe(blob)
    with pytest.raises((InputError, UsageError)) as info:
        open_input(f"wav:{where}")
    os.close(r)
    assert said in str(info.value) and "\n" not in str(info.value)
    assert str(info.value).startswith(f"--audio-input wav:{where}: ")  # the option named, as for every input


# ---------------------------------------------------------------------------------------------------- raw:
def test_inf_and_nan_samples_read_as_0_and_are_counted_and_logged_once(caplog):
    x = np.full(8000, 0.5, dtype="<f4")
    x[::100] = np.inf
    x[50::100] = np.nan
    x[1::100] = 3e38                                                   # finite but absurd: clipped to full scale
    r, where = from_pipe(x.tobytes())
    inp = open_input(f"raw:{where}?rate=8000&channels=1&format=f32")
    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        y = read_all(inp)
    os.close(r)
    assert y.size == 8000
    assert np.all(y[::100] == 0.0) and np.all(y[50::100] == 0.0) and np.all(y[1::100] == 1.0)
    assert inp.faults == {"non_finite": 160}
    assert sum("not numbers" in m for m in caplog.messages) == 1
    levels = LevelStream(8000).push(y)
    assert levels.shape[0] > 0 and np.isfinite(levels).all()


def test_an_endless_source_read_at_once_is_played_in_real_time_at_little_cpu(caplog):
    """raw:/dev/zero hands over as much as is asked at once: a file's audio, played in real time from the first read
    (load can only make the wall time longer, never shorter), said once, and the reading costs a fraction of a
    core."""
    t0, cpu0, n = time.perf_counter(), time.thread_time(), 0
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        inp = open_input("raw:/dev/zero?rate=8000&channels=2")
        while n < int(1.2 * 8000):
            block, _ = inp.read()
            n += block.size
    wall, cpu = time.perf_counter() - t0, time.thread_time() - cpu0
    inp.close()
    assert inp.paced is True
    assert wall >= n / 8000 - 0.001                              # the sample clock from the first read
    assert cpu < 0.5 * wall                                      # unpaced, the loop is all CPU
    said = [r for r in caplog.records if "a file's audio" in r.getMessage()]
    assert len(said) == 1 and said[0].levelno == logging.INFO   # a file piped in does so by design: no warning


def test_a_live_writer_that_runs_ahead_later_is_held_to_real_time(monkeypatch, caplog):
    """A writer live at the first read (20 ms every 20 ms) that then dumps 3 s at once, more than it could have
    queued (here FAST_S 0.2 s past the pipe's capacity), is held back to the sample clock there, said once at info
    level and counted."""
    monkeypatch.setattr(inputs, "FAST_S", 0.2)
    r, w = os.pipe()
    block = np.zeros(160 * 2, dtype="<i2").tobytes()          # 20 ms of 8 kHz stereo

    def write() -> None:
        with os.fdopen(w, "wb") as f:
            start = time.perf_counter()
            for k in range(80):                                # 1.6 s live, past the first read's look
                time.sleep(max(0.0, start + k * 0.02 - time.perf_counter()))
                f.write(block)
                f.flush()
            f.write(block * 150)                               # then 3 s at once

    writer = threading.Thread(target=write)
    writer.start()
    t0 = time.perf_counter()
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        inp = open_input(f"raw:/dev/fd/{r}?rate=8000&channels=2")
        x = read_all(inp)
    wall = time.perf_counter() - t0
    writer.join(5)
    os.close(r)
    assert inp.paced is False and x.size == 230 * 160
    allowance = (1 << 16) / 32000 + 0.2                         # 64 KiB of 8 kHz stereo s16 is 2.05 s
    assert wall >= 4.6 - allowance - 0.03                        # the sample clock, less the allowance and a block
    assert inp.faults["too_fast"] > 0
    said = [r for r in caplog.records if "faster than real time" in r.getMessage()]
    assert len(said) == 1 and said[0].levelno == logging.INFO


def test_a_writer_within_the_allowance_is_not_held_back():
    pcm = np.zeros(int(0.5 * 8000) * 2, dtype="<i2")           # 0.5 s written at once: a pipe's buffered start
    r, where = from_pipe(pcm.tobytes())
    inp = open_input(f"raw:{where}?rate=8000&channels=2")
    assert read_all(inp).size == 4000
    os.close(r)
    assert inp.faults == {}


def test_a_directory_is_a_one_line_usage_error(tmp_path):
    with pytest.raises(UsageError) as info:
        open_input(f"raw:{tmp_path}?rate=8000")
    assert "cannot read" in str(info.value) and "\n" not in str(info.value)


# ---------------------------------------------------------------------------------------------------- options
@click.command()
@seat_sync_options
def _listen(sync) -> None:
    click.echo(f"max_delay_s={sync.max_delay_s if sync else None}")


@pytest.mark.parametrize("args", [["--sync-max-delay", "5000"], ["--sync-max-delay", "10000"],
                                  ["--sync", "off", "--sync-max-delay", "5000"]])
def test_sync_max_delay_without_sync_audio_is_refused(args):
    result = CliRunner().invoke(_listen, args)
    assert result.exit_code == 2 and "--sync-max-delay need --sync audio" in result.output


def test_sync_max_delay_with_sync_audio_is_taken():
    assert CliRunner().invoke(_listen, ["--sync", "audio", "--sync-max-delay", "5000"]).output == "max_delay_s=5.0\n"
    assert CliRunner().invoke(_listen, []).output == "max_delay_s=None\n"


# ---------------------------------------------------------------------------------------------------- a late writer
def _late_writer(path, payload: bytes) -> tuple[threading.Thread, threading.Event]:
    """A writer that opens the named pipe ``path`` once told to (the event), sends ``payload`` and closes."""
    go = threading.Event()

    def write() -> None:
        go.wait(30)
        with open(path, "wb") as f:
            f.write(payload)

    thread = threading.Thread(target=write, daemon=True)
    thread.start()
    return thread, go


@pytest.mark.skipif(os.name == "nt", reason="named pipes are POSIX here")
def test_a_named_pipe_whose_writer_starts_later_is_opened_at_once_and_read_when_it_comes(tmp_path, monkeypatch,
                                                                                         caplog):
    # a seat started before the show whose writer starts with it: opening the input neither blocks nor fails (the
    # seat can join its show and stop on Ctrl-C meanwhile); the first read waits for the writer, then reads on
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 0.1)
    fifo = tmp_path / "heard.fifo"
    os.mkfifo(fifo)
    pcm = (np.arange(800, dtype="<i2") * 8).tobytes()
    writer, go = _late_writer(fifo, wav_header(8000, 1, len(pcm)) + pcm)
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        inp = open_input(f"wav:{fifo}")                          # returns before the writer even opens the pipe
    assert any("waiting for its writer" in m for m in caplog.messages)
    go.set()
    x = read_all(inp)                                            # waits for the writer, reads to the end
    writer.join(5)
    inp.close()
    assert inp.sample_rate == 8000 and x.size == 800
    assert np.allclose(x[:3], np.array([0, 8, 16]) / 32768)


@pytest.mark.skipif(os.name == "nt", reason="named pipes are POSIX here")
def test_a_late_writer_that_sends_no_wav_is_one_line_at_the_first_read(tmp_path, monkeypatch):
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 0.1)
    fifo = tmp_path / "heard.fifo"
    os.mkfifo(fifo)
    writer, go = _late_writer(fifo, b"hello world!" * 3)
    inp = open_input(f"wav:{fifo}")
    go.set()
    with pytest.raises(InputError) as info:
        inp.read()
    writer.join(5)
    inp.close()
    assert str(info.value) == f"--audio-input wav:{fifo}: header: expected a WAV stream (RIFF ... WAVE)"


@pytest.mark.skipif(os.name == "nt", reason="named pipes are POSIX here")
def test_an_input_closed_while_it_waits_for_its_writer_stops_its_reader(tmp_path, monkeypatch):
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 0.1)
    fifo = tmp_path / "heard.fifo"
    os.mkfifo(fifo)
    inp = open_input(f"raw:{fifo}?rate=8000&channels=1")
    failed: list = []

    def reader() -> None:
        try:
            inp.read()
        except Exception as exc:  # the seat's thread ends on it, quietly when the seat is stopping
            failed.append(exc)

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    time.sleep(0.3)
    inp.close()
    thread.join(5)
    assert not thread.is_alive() and failed

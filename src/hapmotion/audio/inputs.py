"""Audio a seat listens to: a sound device (the loopback of the computer's output, a monitor source, a microphone)
or a file or pipe, all as blocks of mono samples stamped with the local time their last sample was heard.

``open_input(spec)`` takes:

* ``loopback`` (the default): what the default output device plays (WASAPI loopback on Windows, the output's
  PulseAudio/PipeWire monitor source on Linux; macOS has none: route the output through a virtual device such as
  BlackHole and name it);
* ``mic``: the default microphone;
* ``device:NAME``: a device by (part of) the name ``hapmotion listen --list-audio-inputs`` shows;
* ``file:PATH``: an audio file (WAV, FLAC, Ogg, ...) played in real time from the moment the seat starts;
* ``wav:PATH`` or ``wav:-``: a WAV stream from a named pipe or standard input, stamped as it arrives (a streaming
  WAV, whose data size is a placeholder, is read to its end: :mod:`hapmotion.audio.wav_stream`);
* ``raw:PATH?rate=48000&channels=2&format=s16`` (or ``raw:-?...``): headerless PCM (``s16`` little-endian or
  ``f32``) from a pipe or standard input, stamped as it arrives (``parec --format=s16le`` writes this).

Every input has a rate of ``MIN_SAMPLE_RATE..MAX_SAMPLE_RATE`` (:mod:`hapmotion.audio.io`) and 1..32 channels.
Samples that are not finite (a float stream's inf or NaN) become 0 and float samples are clipped to -1..1, so the
levels stay finite. A pipe is read no faster than real time: a live writer that runs further ahead than it could
have queued (its pipe's capacity plus :data:`FAST_S`) is held back to the sample clock, at the cost of no CPU. Both
are counted in :attr:`AudioInput.faults` and logged once per kind.

When was a sample heard? A live writer's (a capture program's) as it arrives, minus what it had queued: the seat
takes the earliest arrival relative to the sample clock (``seat_sync.HeardClock``), as no captured sample arrives
before it was heard. A file has no such moment; ``file:PATH`` plays it in real time from the seat's first read, and
so do ``wav:``/``raw:`` on a regular file and on a pipe whose writer hands over far more than a live writer could
have queued (:data:`FAST_S` past the pipe's capacity, within :data:`FAST_LOOK_S`: ``cat song.wav |``). Stamped as
they arrived, such a file's first seconds (read at once) would put the whole file that much early; held back as a
runaway writer is, a live writer's queue would put all it sends that much late.

Devices are read with SoundCard (PyPI ``soundcard``), which captures the output's loopback on Windows (WASAPI) and
Linux (PulseAudio and PipeWire's pulse server) with no driver to install, where PortAudio (``sounddevice``) has no
loopback capture in its released builds. It is imported when a device is opened or listed: a seat without sync, a
machine without sound, never loads it. Nothing read here leaves the machine: the samples become band levels
(:mod:`hapmotion.audio.sync_features`) in the seat's own process.
"""

from __future__ import annotations

import logging
import os
import select
import stat
import sys
import time
from dataclasses import dataclass
from typing import BinaryIO, Optional
from urllib.parse import parse_qs

try:
    import fcntl   # a pipe's capacity (Linux); not on Windows, whose pipes are not looked at
except ImportError:  # pragma: no cover - Windows
    fcntl = None

import numpy as np
import soundfile as sf

from ..errors import InputError, UsageError
from .io import MAX_SAMPLE_RATE, MIN_SAMPLE_RATE, downmix, probe
from .wav_stream import read_header

log = logging.getLogger("hapmotion.live")

BLOCK_S = 0.02
"""Samples per block read, seconds (devices and files); pipes hand over what has arrived, up to this."""
DEVICE_RATE = 48000
MAX_CHANNELS = 32
"""Most channels an input may have (a header claiming thousands would make every block that many times larger)."""
PIPE_WAIT_S = 0.1
"""How long a seat starting on a pipe waits for its first bytes before it goes on and waits for them while it runs:
a writer already running (``cat song.wav |``, started with the seat) has sent them by the time the seat has started;
one that starts with the show must not hold the seat up (it would join its show late)."""
FAST_S = 5.0
"""A pipe whose writer hands over more than its capacity plus this much audio at once is a file being copied in, not
a live capture: a capture program queues what the seat has not yet read, a second or two while the seat starts, not
five (the pipe itself holds 0.34 s of 48 kHz stereo s16 on Linux, 1.5 s of 22 kHz mono)."""
FAST_LOOK_S = 1.0
"""How long a pipe's first read keeps taking what its writer hands over (pauses included: a decoder starting, a
network stream's first bytes): a file is copied in far faster, a live writer adds this much at most."""
LOOK_MAX_BYTES = 32 << 20
"""The most a pipe's first read takes (what it holds until it plays): 5 s of 192 kHz 8-channel float is 31 MB; a
format larger still is judged on this many bytes."""
SPECS = "loopback, mic, device:NAME, file:PATH, wav:PATH|-, raw:PATH|-?rate=R&channels=C&format=s16|f32"


class AudioInput:
    """One source of heard audio: :meth:`read` blocks until the next block ``(n,)`` float64 mono and returns it with
    the ``time.perf_counter()`` at which its last sample was heard, or ``(None, t)`` at the end; :meth:`close`."""

    sample_rate: float = DEVICE_RATE
    name: str = ""
    faults: dict[str, int]
    """What was wrong with the audio, counted per kind (``non_finite`` samples, ``too_fast`` blocks held back)."""

    def _fault(self, kind: str, count: int, text: str, level: int = logging.WARNING) -> None:
        """Count ``count`` faults of ``kind``; log ``text`` the first time (at ``level``)."""
        faults = self.__dict__.setdefault("faults", {})
        if kind not in faults:
            log.log(level, "seat sync: %s: %s (counted; logged once)", self.name, text)
        faults[kind] = faults.get(kind, 0) + count

    def _clean(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """``(n, channels)`` samples times ``scale`` (full scale 1) -> ``(n,)`` float64 mono; non-finite samples
        0 (counted), the rest clipped to -1..1."""
        x = np.asarray(x)
        if x.dtype.kind == "f":
            bad = ~np.isfinite(x)
            if bad.any():   # replaced before any arithmetic: a signalling NaN would warn in the cast
                self._fault("non_finite", int(bad.sum()), "samples that are not numbers (inf/NaN) read as 0")
                x = np.where(bad, x.dtype.type(0), x)
        return downmix(np.clip(x.astype(np.float64) * scale, -1.0, 1.0))

    def read(self) -> tuple[Optional[np.ndarray], float]:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def describe(self) -> str:
        return self.name


class FileInput(AudioInput):
    """An audio file played in real time from the first :meth:`read` (the seat hears it as a listener would)."""

    def __init__(self, path: str):
        if not os.path.isfile(path):
            raise UsageError(f"--audio-input file:{path}: no such file")
        info = probe(path)   # the rate MIN_SAMPLE_RATE..MAX_SAMPLE_RATE, channels, samples: one line naming the file
        if info.channels > MAX_CHANNELS:
            raise InputError(path, "header", f"expected 1..{MAX_CHANNELS} channels, found {info.channels}")
        try:
            self._f = sf.SoundFile(path)
        except (sf.LibsndfileError, RuntimeError, OSError) as exc:
            raise InputError(path, "", f"cannot read it as audio: {exc}") from None
        self.faults = {}
        self.sample_rate = float(self._f.samplerate)
        self.name = f"file {path}"
        self._block = max(1, int(BLOCK_S * self.sample_rate))
        self.started: Optional[float] = None
        """``perf_counter()`` at which the file's first sample was heard (its first :meth:`read`)."""
        self._done = 0

    def read(self) -> tuple[Optional[np.ndarray], float]:
        if self.started is None:
            self.started = time.perf_counter()
        data = self._f.read(self._block, dtype="float32", always_2d=True)
        if data.shape[0] == 0:
            return None, time.perf_counter()
        self._done += data.shape[0]
        due = self.started + self._done / self.sample_rate
        wait = due - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        return self._clean(data), due

    def close(self) -> None:
        self._f.close()


def _open_stream(where: str, spec: str) -> BinaryIO:
    if where == "-":
        return sys.stdin.buffer
    try:
        return open(where, "rb", buffering=0)
    except OSError as exc:  # a directory, no permission: the user's mistake, in one line
        raise UsageError(f"--audio-input {spec}: cannot read {where} ({exc.strerror})") from None


def _pipe_capacity(fd: int) -> int:
    """Bytes the pipe ``fd`` holds (Linux says; 64 KiB, the most other systems give one, elsewhere)."""
    try:
        return int(fcntl.fcntl(fd, fcntl.F_GETPIPE_SZ))
    except (AttributeError, OSError):
        return 1 << 16


def _pipe_descriptor(where: str) -> Optional[int]:
    """A descriptor of standard input (``-``) or of the named pipe ``where``, opened without waiting for its writer
    (a plain open blocks until one comes), to wait on with ``select``; None for a regular file, on Windows (whose
    pipes ``select`` cannot wait on) and where standard input is no file (an embedding program's)."""
    if os.name == "nt":
        return None
    if where == "-":
        try:
            return sys.stdin.fileno()
        except (AttributeError, OSError, ValueError):  # (io.UnsupportedOperation is an OSError)
            return None
    if not stat.S_ISFIFO(os.stat(where).st_mode):
        return None
    return os.open(where, os.O_RDONLY | os.O_NONBLOCK)


class PipeInput(AudioInput):
    """Raw PCM or a WAV stream from a pipe or standard input: a file's audio played in real time from the first read,
    a live writer's stamped on arrival and held back once it runs further ahead than it could have queued (module
    docstring).

    A pipe (standard input, a named pipe) whose writer has not started yet (it may start with the show) is waited for
    :data:`PIPE_WAIT_S` here and then by the first :meth:`read` (the seat's listening thread): a seat blocked on it
    could neither join its show nor stop on Ctrl-C. What arrives in time is checked here (a WAV header that is not
    one stops the seat at once); what arrives later, there (said once, the seat playing unsynced). Windows, whose
    pipes cannot be waited on this way, opens and checks at once."""

    def __init__(self, spec: str, kind: str, rest: str):
        where, _, query = rest.partition("?")
        self.name = f"{kind} stream {where}"
        self.faults = {}
        self._spec, self._where, self._kind = spec, where, kind
        self._closed = False
        self._left: Optional[int] = None
        """Bytes of samples the WAV header announced that are still to come (None: until the stream ends)."""
        self._carry = b""
        self._started: Optional[float] = None
        self._frames = 0
        self.paced: Optional[bool] = None
        """True when the stream is a file's audio played in real time from the first read (a regular file, a file
        copied into the pipe); False for a live writer's, stamped as it arrives; None before the first read."""
        self._ahead = bytearray()
        """What the first read took from a pipe at once (:meth:`_first_look`), handed over before the stream's own."""
        self._hold_s = FAST_S
        """How far ahead of the sample clock a live writer is read before it is held back, seconds."""
        self._stream: Optional[BinaryIO] = None
        self._pending: Optional[int] = None
        """The descriptor of a pipe whose writer has not sent anything yet (opened, not yet read)."""
        if kind == "raw":  # the options first: a mistake in them is said before anything is opened
            q = {k: v[-1] for k, v in parse_qs(query).items()}
            unknown = set(q) - {"rate", "channels", "format"}
            if unknown:
                raise UsageError(f"--audio-input {spec}: unknown {', '.join(sorted(unknown))} (rate, channels, "
                                 f"format)")
            try:
                self.sample_rate = float(q.get("rate", DEVICE_RATE))
                self.channels = int(q.get("channels", 2))
            except ValueError:
                raise UsageError(f"--audio-input {spec}: rate and channels must be numbers") from None
            fmt = q.get("format", "s16")
            if fmt not in ("s16", "f32"):
                raise UsageError(f"--audio-input {spec}: format s16 or f32, not {fmt!r}")
            self._dtype = np.dtype("<i2") if fmt == "s16" else np.dtype("<f4")
            self._check_format()
        if where != "-" and not os.path.exists(where):
            raise UsageError(f"--audio-input {spec}: no such file or pipe {where}")
        fd = _pipe_descriptor(where)
        if fd is not None:
            if select.select([fd], [], [], PIPE_WAIT_S)[0]:
                self._stream = self._from_fd(fd)
            else:
                self._pending = fd
                log.info("seat sync: %s: waiting for its writer to start", self.name)
        else:
            self._stream = _open_stream(where, spec)
        if kind == "wav" and self._stream is not None:
            self._open()

    def _from_fd(self, fd: int) -> BinaryIO:
        os.set_blocking(fd, True)
        # unbuffered, standard input too: what select says is there is what a read returns
        return os.fdopen(fd, "rb", buffering=0, closefd=self._where != "-")

    def _open(self) -> None:
        """Wait for a pipe's writer (it may only now start) and read a WAV stream's header."""
        while self._stream is None and self._pending is not None and not self._closed:
            if select.select([self._pending], [], [], 0.25)[0]:
                self._stream, self._pending = self._from_fd(self._pending), None
        if self._stream is None:
            raise UsageError(f"--audio-input {self._spec}: closed before its writer started")
        if self._kind == "wav" and not hasattr(self, "_dtype"):
            header = read_header(self._stream, f"--audio-input {self._spec}")
            self.sample_rate = float(header.sample_rate)
            self.channels = header.channels
            self._dtype = header.dtype
            self._left = header.data_bytes
            self._check_format()

    def _check_format(self) -> None:
        if not (MIN_SAMPLE_RATE <= self.sample_rate <= MAX_SAMPLE_RATE and 1 <= self.channels <= MAX_CHANNELS):
            raise UsageError(f"--audio-input {self._spec}: expected a rate of {MIN_SAMPLE_RATE}..{MAX_SAMPLE_RATE} "
                             f"Hz and 1..{MAX_CHANNELS} channels, found {self.sample_rate:g} Hz and {self.channels} "
                             f"channels")
        self._frame_bytes = self._dtype.itemsize * self.channels
        self._max = max(1, int(BLOCK_S * self.sample_rate)) * self._frame_bytes

    def _chunk(self) -> bytes:
        want = self._max if self._left is None else min(self._max, self._left)
        if self._ahead:
            chunk = bytes(self._ahead[:want])
            del self._ahead[:want]
        else:
            chunk = self._stream.read(want) if want else b""
        if self._left is not None:
            self._left -= len(chunk)
        return chunk

    def _first_look(self) -> None:
        """Decide :attr:`paced` (module docstring): a regular file is; a pipe is when its writer hands over more
        than the pipe's capacity plus :data:`FAST_S` of audio within :data:`FAST_LOOK_S`, or its whole stream,
        longer than the pipe holds (kept in :attr:`_ahead`). Where select cannot wait on the stream (Windows), a
        pipe is a live writer's. Sets :attr:`_hold_s`, how far a live writer may run ahead."""
        try:
            fd: Optional[int] = self._stream.fileno()
            regular = stat.S_ISREG(os.fstat(fd).st_mode)
        except (AttributeError, OSError, ValueError):  # a stream without a descriptor (an embedding program's)
            fd, regular = None, False
        per_s = self.sample_rate * self._frame_bytes
        capacity = _pipe_capacity(fd) if fd is not None else 1 << 16
        limit = int(min(capacity + FAST_S * per_s, LOOK_MAX_BYTES))
        self._hold_s = limit / per_s
        self.paced = regular
        if regular or fd is None or os.name == "nt":
            return
        allowed = limit if self._left is None else min(limit, self._left)
        deadline = time.perf_counter() + FAST_LOOK_S
        ended = False
        while len(self._ahead) < allowed and not self._closed:
            wait = deadline - time.perf_counter()
            if wait <= 0 or not select.select([fd], [], [], wait)[0]:
                break
            chunk = self._stream.read(min(1 << 16, allowed - len(self._ahead)))
            if not chunk:
                ended = True
                break
            self._ahead += chunk
        ended = ended or len(self._ahead) == self._left
        self.paced = len(self._ahead) >= limit or (ended and len(self._ahead) > capacity + FAST_LOOK_S * per_s)
        if self.paced:
            log.info("seat sync: %s: a file's audio (handed over at once): played in real time from now, as "
                     "file: would", self.name)

    def read(self) -> tuple[Optional[np.ndarray], float]:
        self._open()
        if self.paced is None:
            self._started = time.perf_counter()   # a file's audio is heard from the first read, as file: plays it
            self._first_look()
        while True:
            chunk = self._chunk()
            now = time.perf_counter()
            if not chunk:
                return None, now
            data = self._carry + chunk
            usable = len(data) - len(data) % self._frame_bytes
            self._carry = data[usable:]
            if usable:
                break
        x = np.frombuffer(data[:usable], dtype=self._dtype).reshape(-1, self.channels)
        self._frames += x.shape[0]
        scale = 1.0 if self._dtype.kind == "f" else 1.0 / float(np.iinfo(self._dtype).max + 1)
        if self.paced:   # a file's audio: heard in real time from the first read, as FileInput plays it
            due = self._started + self._frames / self.sample_rate
            if due > now:
                time.sleep(due - now)
            return self._clean(x, scale), due
        # A writer faster than real time (raw:/dev/zero) would be read, analysed and matched as fast as a core
        # allows, and its stamps would say the music runs fast: hold the block until the sample clock is due
        # (the writer then blocks on a full pipe, costing nothing).
        due = self._started + self._frames / self.sample_rate - self._hold_s
        if due > now:
            # a file piped in (a rehearsal) does so by design: said, not warned about
            self._fault("too_fast", 1, "the input delivers audio faster than real time (a file piped in?); reading "
                                       "it at real time", logging.INFO)
            time.sleep(due - now)
            now = time.perf_counter()
        return self._clean(x, scale), now

    def close(self) -> None:
        self._closed = True
        if self._stream is not None and self._stream is not sys.stdin.buffer:
            self._stream.close()   # (standard input's descriptor stays open: not closefd)
        elif self._pending is not None and self._where != "-":
            os.close(self._pending)
            self._pending = None


def _soundcard():
    """SoundCard, imported on first use (it connects to the sound server on import); UsageError in one line when
    this machine has no sound system to talk to."""
    try:
        if len(sys.argv) < 2:  # soundcard names its PulseAudio client after sys.argv[1]
            sys.argv.append("")
            try:
                import soundcard
            finally:
                sys.argv.pop()
        else:
            import soundcard
    except Exception as exc:  # no PulseAudio/PipeWire server, no CoreAudio/WASAPI: one line, not a traceback
        detail = f": {exc}" if str(exc) else ""  # SoundCard says nothing more than a bare assertion here
        raise UsageError(f"no sound system to capture from (SoundCard found no PulseAudio/PipeWire, WASAPI or "
                         f"CoreAudio server{detail}); use --audio-input file:PATH, wav:- or raw:- instead") from None
    return soundcard


class DeviceInput(AudioInput):
    """A capture device through SoundCard: ``loopback``, ``mic`` or ``device:NAME``."""

    def __init__(self, spec: str):
        sc = _soundcard()
        try:
            if spec == "loopback":
                speaker = sc.default_speaker()
                mic = sc.get_microphone(str(speaker.name), include_loopback=True)
            elif spec == "mic":
                mic = sc.default_microphone()
            else:
                mic = sc.get_microphone(spec.partition(":")[2], include_loopback=True)
        except Exception as exc:  # SoundCard raises IndexError/RuntimeError/... for a device that is not there
            raise UsageError(f"--audio-input {spec}: no such audio input ({exc.__class__.__name__}: {exc}); "
                             f"hapmotion listen --list-audio-inputs shows what there is") from None
        self.name = f"device {mic.name}"
        self.faults = {}
        self.sample_rate = float(DEVICE_RATE)
        self._block = int(BLOCK_S * DEVICE_RATE)
        try:
            self._ctx = mic.recorder(samplerate=DEVICE_RATE, blocksize=self._block)
            self._rec = self._ctx.__enter__()
        except Exception as exc:
            raise UsageError(f"--audio-input {spec}: cannot record from {mic.name} ({exc})") from None

    def read(self) -> tuple[Optional[np.ndarray], float]:
        data = self._rec.record(numframes=self._block)
        return self._clean(data), time.perf_counter()

    def close(self) -> None:
        try:
            self._ctx.__exit__(None, None, None)
        except Exception:  # a device unplugged meanwhile: nothing left to release
            pass


def open_input(spec: str) -> AudioInput:
    """The input ``spec`` names (module docstring); UsageError in one line when it cannot be opened."""
    kind, sep, rest = spec.partition(":")
    if spec in ("loopback", "mic") or kind == "device":
        return DeviceInput(spec)
    if kind == "file" and rest:
        return FileInput(rest)
    if kind in ("wav", "raw") and rest:
        return PipeInput(spec, kind, rest)
    raise UsageError(f"--audio-input {spec!r}: expected one of {SPECS}")


@dataclass(frozen=True)
class InputListing:
    """What ``--list-audio-inputs`` prints: the devices (``(spec, description)``) and why there are none."""

    devices: tuple[tuple[str, str], ...]
    problem: Optional[str]


def list_inputs() -> InputListing:
    """The capture devices this machine has (loopbacks first), or the reason it has none."""
    try:
        sc = _soundcard()
        mics = sc.all_microphones(include_loopback=True)
        speaker = sc.default_speaker() if mics else None
    except UsageError as exc:
        return InputListing((), str(exc))
    except Exception as exc:  # a sound server that went away while listing
        return InputListing((), f"the sound system did not answer ({exc.__class__.__name__})")
    rows = []
    for mic in sorted(mics, key=lambda m: not getattr(m, "isloopback", False)):
        kind = "loopback/monitor" if getattr(mic, "isloopback", False) else "input"
        rows.append((f"device:{mic.name}", kind))
    if speaker is not None:
        rows.insert(0, ("loopback", f"what {speaker.name} plays"))
    return InputListing(tuple(rows), None if rows else "the sound system has no capture devices")

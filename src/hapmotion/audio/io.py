"""Reading audio files block by block, as a mono float stream, with one-line errors for bad files.

Everything goes through libsndfile (python-soundfile): WAV, FLAC, Ogg Vorbis/Opus, AIFF and, when the installed
libsndfile is 1.1 or newer, MP3. A file is never loaded whole: :func:`mono_blocks` yields blocks of at most
``BLOCK_FRAMES`` frames, downmixed to mono, so memory stays flat however long the file is. Rate conversion is not
done here: the analysis filters at the native rate and decimates (see :mod:`hapmotion.audio.analysis`).
"""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Iterator

import numpy as np
import soundfile as sf

from ..errors import InputError

BLOCK_FRAMES = 1 << 19
"""Frames read per block (12 s at 44.1 kHz; 12 MB for 6 channels of float32). Every step of the analysis carries
its state across blocks, so the block size changes no number; larger blocks spend less time per call (an hour at
22.05 kHz is 150 blocks instead of 1,200, each with three filter calls)."""

MIN_SAMPLE_RATE = 4000
"""Lowest sample rate the analysis supports: its anti-alias corner (1.8 kHz) must sit below Nyquist."""

MAX_SAMPLE_RATE = 768000
"""Highest sample rate accepted (sanity bound; libsndfile reads higher, nothing records it)."""

MAX_SAMPLE_MAGNITUDE = 1e4
"""Largest sample magnitude accepted. Samples are nominally -1..1 (integer formats cannot exceed it; float files
may run a little over full scale); 1e4 is 80 dB over full scale, so anything beyond is a damaged float file, whose
values (up to 3.4e38) would overflow the analysis' energy sums."""


@dataclass(frozen=True)
class AudioInfo:
    """What the file header says.

    ``frames`` is the header's frame count; for compressed formats (MP3 in particular) the decoded length can
    differ slightly, so the analysis counts the samples it actually reads.
    """

    path: str
    sample_rate: int
    channels: int
    frames: int
    format: str
    subtype: str

    @property
    def duration_s(self) -> float:
        return self.frames / self.sample_rate


def mp3_supported() -> bool:
    """True if the installed libsndfile decodes MP3 (libsndfile >= 1.1)."""
    return "MP3" in sf.available_formats()


@contextmanager
def _decoder_messages(active: bool) -> Iterator[list[str]]:
    """Capture what C decoders print on the process's stderr (file descriptor 2) while the block runs.

    libsndfile decodes MP3 with libmpg123, which prints its own notes ("Note: Illegal Audio-MPEG-Header ...",
    "error: dequantization failed!") straight to stderr, where they would appear as stray lines around our one-line
    error. While active, fd 2 points at a temporary file; the lines are in the yielded list once the block ends
    (also when it raises). Process-wide for its short duration, so it is used around each MP3 open and read only.
    """
    lines: list[str] = []
    if not active:
        yield lines
        return
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines.extend(ln.strip() for ln in sink.read(65536).decode("utf-8", "replace").splitlines() if ln.strip())


def _decoder_error(lines: list[str]) -> str | None:
    """The first error the decoder reported, shortened (its source-file prefix dropped), or None.

    Notes and warnings (a resync, an inexact Xing size) describe problems the decoder worked around; an error line
    means audio was lost, so the file is refused rather than analysed with a hole in it.
    """
    for line in lines:
        if "error" in line.lower():
            text = line.split("] ", 1)[-1]  # "[src/libmpg123/layer3.c:...] error: ..." -> "error: ..."
            return text[len("error: "):][:160] if text.lower().startswith("error: ") else text[:160]
    return None


def _is_mp3(path: str) -> bool:
    return path.lower().endswith((".mp3", ".mp2", ".mpga"))


def _libsndfile_problem(err: Exception) -> str:
    """The useful part of a libsndfile error, on one line."""
    text = getattr(err, "error_string", None) or str(err)
    return " ".join(str(text).split()).rstrip(".")


def probe(path: "str | os.PathLike[str]") -> AudioInfo:
    """Check that ``path`` is a readable, non-empty audio file at a usable rate; return its header facts.

    Raises
    ------
    InputError
        Missing file, a directory, an unknown or unsupported format (MP3 without libsndfile >= 1.1), no samples,
        or a sample rate outside ``MIN_SAMPLE_RATE..MAX_SAMPLE_RATE``.
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise InputError(path, "", "file not found")
    if os.path.isdir(path):
        raise InputError(path, "", "is a directory, expected an audio file")
    if path.lower().endswith(".mp3") and not mp3_supported():
        raise InputError(path, "", f"MP3 needs libsndfile 1.1 or newer (installed: {sf.__libsndfile_version__}); "
                                   "convert it to WAV, FLAC or Ogg")
    try:
        with _decoder_messages(_is_mp3(path)) as notes:
            with sf.SoundFile(path) as f:
                info = AudioInfo(path, int(f.samplerate), int(f.channels), int(f.frames), f.format, f.subtype)
    except (sf.LibsndfileError, RuntimeError, OSError) as err:
        said = _decoder_error(notes)
        raise InputError(path, "", f"cannot read it as audio (WAV, FLAC, Ogg, MP3): {_libsndfile_problem(err)}"
                         + (f" (decoder: {said})" if said else "")) from None
    if info.channels < 1:
        raise InputError(path, "header", f"expected at least 1 channel, found {info.channels}")
    if not MIN_SAMPLE_RATE <= info.sample_rate <= MAX_SAMPLE_RATE:
        raise InputError(path, "header", f"expected a sample rate of {MIN_SAMPLE_RATE}..{MAX_SAMPLE_RATE} Hz, "
                                         f"found {info.sample_rate} Hz")
    if info.frames <= 0:
        raise InputError(path, "", "contains no audio samples")
    return info


def downmix(block: np.ndarray) -> np.ndarray:
    """``(n, channels)`` -> ``(n,)`` float64 mean of the channels (every channel, LFE included, weighs the same).

    A plain mean keeps a mono file unchanged and a centred (identical L/R) stereo mix at its level; content in one
    channel only drops by 6 dB, which the analysis' per-file reference level takes out again.
    """
    if block.ndim == 1:
        return block.astype(np.float64, copy=False)
    out = block[:, 0].astype(np.float64)
    for c in range(1, block.shape[1]):          # a column loop: 5x faster than mean(axis=1) on interleaved data
        out += block[:, c]
    if block.shape[1] > 1:
        out *= 1.0 / block.shape[1]
    return out


def mono_blocks(info: AudioInfo, block_frames: int = BLOCK_FRAMES) -> Iterator[np.ndarray]:
    """Yield the file as consecutive ``(n,)`` float64 mono blocks (n <= block_frames), values nominally -1..1.

    Raises
    ------
    InputError
        A decode error or a non-finite sample (float WAV with NaN/inf), naming the time where it happened.
    """
    done = 0
    mp3 = _is_mp3(info.path) or info.format == "MPEG"
    notes: list[str] = []
    try:
        with _decoder_messages(mp3) as notes:
            f = sf.SoundFile(info.path)
        with f:
            buf = np.empty((block_frames, info.channels), dtype=np.float32)
            while True:
                with _decoder_messages(mp3) as notes:
                    block = f.read(block_frames, dtype="float32", always_2d=True, out=buf)
                said = _decoder_error(notes)
                if said:
                    raise InputError(info.path, f"near {done / info.sample_rate:.2f} s", f"decode error: {said}")
                if len(block) == 0:
                    break
                with np.errstate(all="ignore"):  # a signalling NaN in a float file warns on every operation
                    mono = downmix(block)
                if not np.isfinite(mono).all():
                    bad = done + int(np.flatnonzero(~np.isfinite(mono))[0])
                    raise InputError(info.path, f"sample {bad} ({bad / info.sample_rate:.3f} s)",
                                     "expected finite sample values, found NaN or infinity")
                loud = np.abs(mono) > MAX_SAMPLE_MAGNITUDE
                if loud.any():
                    bad = done + int(np.flatnonzero(loud)[0])
                    raise InputError(info.path, f"sample {bad} ({bad / info.sample_rate:.3f} s)",
                                     f"expected sample values within +-{MAX_SAMPLE_MAGNITUDE:g} (full scale is 1), "
                                     f"found {mono[bad - done]:.3g}")
                done += len(mono)
                yield mono
                if len(block) < block_frames:
                    break
    except (sf.LibsndfileError, RuntimeError, OSError) as err:
        said = _decoder_error(notes)
        raise InputError(info.path, f"near {done / info.sample_rate:.2f} s",
                         f"decode error: {_libsndfile_problem(err)}" + (f" (decoder: {said})" if said else "")
                         ) from None

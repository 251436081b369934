"""Live audio in: a file played in real time, a PCM or WAV stream on stdin, or the default microphone.

Every source yields blocks of mono float64 samples at its own rate, in the order they were captured;
:class:`Resampler` takes them to the acoustic model's 16 kHz as they come.

Stream formats
--------------
A stream that starts with ``RIFF`` is read as a WAV stream (its header says the rate, channels and
sample format; 8/16/24/32-bit PCM or 32-bit float; the length fields may be wrong, as in a WAV piped
out of ffmpeg: the stream is read until it ends). Anything else is raw little-endian PCM of the given
``--format`` (``s16le``, ``s32le``, ``f32le``), ``--sample-rate`` and ``--channels``.

A stream whose samples cannot be of the stated format is refused before any output
(:func:`check_format`): 32-bit floats that are not finite or far outside [-1, 1] (integer samples read as
floats), or 16-bit samples of which nearly every other one lies in the two narrow bands that the upper
halves of 32-bit floats in [-1, 1] take (floats read as 16-bit integers: their exponent bytes).
"""

from __future__ import annotations

import os
import queue
import struct
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from visemeface.errors import InputError

#: Raw stream sample formats: name -> (numpy dtype, full scale).
FORMATS = {"s16le": ("<i2", 32768.0), "s32le": ("<i4", 2147483648.0), "f32le": ("<f4", 1.0)}
#: Sample rates accepted (Hz): below 8 kHz no speech model works; above 192 kHz is no audio interface.
RATES = (8000, 192000)
#: Seconds of a stream inspected by :func:`check_format` before anything is sent.
CHECK_S = 0.25
#: Fraction of the odd 16-bit words inside a float32 exponent band above which an s16le stream is taken
#: to hold 32-bit floats (speech puts a few percent of its samples in those bands).
FLOAT_BAND_FRACTION = 0.9
#: Largest |sample| a float stream may hold: clipping audio is at 1, integer PCM read as floats is far off.
FLOAT_LIMIT = 64.0


def check_rate(rate, what: str) -> int:
    try:
        value = int(rate)
    except (TypeError, ValueError):
        raise InputError(f"{what}: the sample rate must be a whole number of Hz, got {rate!r}") from None
    if not RATES[0] <= value <= RATES[1]:
        raise InputError(f"{what}: a sample rate of {value} Hz is outside {RATES[0]}..{RATES[1]} Hz")
    return value


def check_format(samples: np.ndarray, fmt: str, raw: bytes, where: str) -> None:
    """Refuse samples that cannot be of the format ``fmt`` (see the module docstring)."""
    if fmt in ("f32le", "f64le"):
        bad = ~np.isfinite(samples)
        if bad.any() or (samples.size and np.abs(samples).max() > FLOAT_LIMIT):
            peak = "not finite" if bad.any() else f"up to {np.abs(samples).max():.3g}"
            raise InputError(f"the stream's samples are not 32-bit floats in [-1, 1] (values {peak}); "
                             "is it 16-bit PCM? give --format s16le", where)
    elif fmt == "s16le" and len(raw) >= 4000:
        words = np.frombuffer(raw[:len(raw) // 4 * 4], dtype="<u2")
        low, high = words[0::2], words[1::2]
        band = lambda w: ((w >= 0x3000) & (w <= 0x3F80)) | ((w >= 0xB000) & (w <= 0xBF80))  # noqa: E731
        if band(high).mean() > FLOAT_BAND_FRACTION and band(low).mean() < 0.5:
            raise InputError("the stream looks like 32-bit float samples, not 16-bit PCM; give --format f32le",
                             where)


class Source:
    """Base of the audio sources: ``rate`` (Hz), ``what`` (for messages), :meth:`blocks`, :meth:`close`."""

    rate: int = 16000
    what: str = ""

    def blocks(self) -> Iterator[np.ndarray]:
        raise NotImplementedError

    def pending(self) -> bool:
        """Whether the next block is already waiting (the reader has fallen behind a real-time source)."""
        return False

    def close(self) -> None:
        pass


class FileSource(Source):
    """A recording (any file :func:`visemeface.speech.audio.read_audio` reads) played block by block.

    ``realtime``: each block is given when it would have been captured (the wall clock paces the file);
    otherwise as fast as they are taken (the timing of what is sent is the same, only sooner).
    """

    def __init__(self, path, realtime: bool = True, block_s: float = 0.01):
        from visemeface.speech.audio import read_audio

        self.samples, self.rate = read_audio(Path(path))
        self.what = str(path)
        self.realtime = realtime
        self.block = max(1, int(round(block_s * self.rate)))
        self._next_due = None

    def pending(self) -> bool:
        return self.realtime and self._next_due is not None and time.monotonic() > self._next_due

    def blocks(self):
        start = time.monotonic()
        self._next_due = None
        for i in range(0, self.samples.size, self.block):
            chunk = self.samples[i:i + self.block]
            self._next_due = start + (i + chunk.size + self.block) / self.rate
            if self.realtime:
                due = start + (i + chunk.size) / self.rate
                wait = due - time.monotonic()
                if wait > 0:
                    time.sleep(wait)
            yield chunk


def _wav_format(fmt_chunk: bytes, where: str) -> tuple[str, int, int]:
    """(sample format, channels, rate) of a WAV ``fmt `` chunk; unsupported encodings refused."""
    if len(fmt_chunk) < 16:
        raise InputError("the WAV stream's format chunk is too short", where)
    tag, channels, rate, _, _, bits = struct.unpack("<HHIIHH", fmt_chunk[:16])
    if tag == 0xFFFE and len(fmt_chunk) >= 26:          # WAVE_FORMAT_EXTENSIBLE: the sub-format's tag
        tag = struct.unpack("<H", fmt_chunk[24:26])[0]
    names = {(1, 8): "u8", (1, 16): "s16le", (1, 24): "s24le", (1, 32): "s32le", (3, 32): "f32le", (3, 64): "f64le"}
    if (tag, bits) not in names:
        kind = {1: "PCM", 3: "float", 6: "A-law", 7: "mu-law", 2: "ADPCM"}.get(tag, f"encoding {tag}")
        raise InputError(f"the WAV stream holds {bits}-bit {kind} samples; 8/16/24/32-bit PCM or 32/64-bit float "
                         "are read", where)
    if channels < 1:
        raise InputError("the WAV stream has no channels", where)
    return names[tag, bits], channels, check_rate(rate, where)


def _decode(raw: bytes, fmt: str) -> np.ndarray:
    if fmt == "u8":
        return (np.frombuffer(raw, dtype=np.uint8).astype(np.float64) - 128.0) / 128.0
    if fmt == "s24le":
        b = np.frombuffer(raw, dtype=np.uint8).reshape(-1, 3).astype(np.int32)
        v = b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16)
        return np.where(v >= 1 << 23, v - (1 << 24), v) / float(1 << 23)
    if fmt == "f64le":
        return np.frombuffer(raw, dtype="<f8").astype(np.float64)
    dtype, scale = FORMATS[fmt]
    return np.frombuffer(raw, dtype=dtype).astype(np.float64) / scale


_WIDTH = {"u8": 1, "s16le": 2, "s24le": 3, "s32le": 4, "f32le": 4, "f64le": 8}


class StreamSource(Source):
    """PCM from a file descriptor (stdin): a WAV stream, or raw samples of ``fmt``, ``rate``, ``channels``.

    Reads what the pipe holds as it arrives (``os.read``), so a block is passed on as soon as it is
    written; a block is at most ``block_s`` long. A WAV header is read when the first block is asked for
    (:attr:`rate` and the format are then the header's).
    """

    def __init__(self, fd: int, rate: int = 16000, fmt: str = "s16le", channels: int = 1, block_s: float = 0.01,
                 what: str = "stdin"):
        self.fd, self.what = fd, what
        if os.isatty(fd):
            raise InputError("standard input is a terminal: pipe audio into it (e.g. ffmpeg ... -f s16le - |) "
                             "or name a file or --mic", what)
        self._pending = b""
        self._buffered = b""
        self.block_bytes = 1
        if fmt not in FORMATS:
            raise InputError(f"unknown sample format {fmt!r}; choose one of {', '.join(FORMATS)}")
        self.fmt, self.channels, self.rate = fmt, int(channels), check_rate(rate, what)
        if self.channels < 1:
            raise InputError(f"--channels must be at least 1, got {channels}")
        self.block_s = block_s
        self.started = False

    def _start(self) -> None:
        """Read a WAV stream's header (the stream's first bytes say whether it has one)."""
        self.started = True
        head = self._read_at_least(12)
        if head[:4] == b"RIFF" and head[8:12] == b"WAVE":
            self._read_wav_header(head[12:])
        else:
            self._pending = head
        self.frame = _WIDTH[self.fmt] * self.channels
        self.block_bytes = max(1, int(round(self.block_s * self.rate))) * self.frame
        self.checked = False

    def _read(self, n: int) -> bytes:
        return os.read(self.fd, n)

    def pending(self) -> bool:
        import select

        if len(self._buffered) >= self.block_bytes:
            return True
        try:
            return bool(select.select([self.fd], [], [], 0)[0])
        except (OSError, ValueError):
            return False

    def _read_at_least(self, n: int) -> bytes:
        out = b""
        while len(out) < n:
            more = self._read(n - len(out))
            if not more:
                break
            out += more
        return out

    def _read_wav_header(self, rest: bytes) -> None:
        buf = rest
        fmt = None
        while True:
            if len(buf) < 8:
                buf += self._read_at_least(8 - len(buf))
                if len(buf) < 8:
                    raise InputError("the WAV stream ends before its data", self.what)
            cid, size = buf[:4], struct.unpack("<I", buf[4:8])[0]
            buf = buf[8:]
            if cid == b"data":
                if fmt is None:
                    raise InputError("the WAV stream has no format chunk before its data", self.what)
                self.fmt, self.channels, self.rate = fmt
                self._pending = buf
                return
            if size > 1 << 20:
                raise InputError(f"the WAV stream's {cid!r} chunk is {size} bytes long: not a WAV header", self.what)
            need = size + (size & 1) - len(buf)
            if need > 0:
                buf += self._read_at_least(need)
            body, buf = buf[:size], buf[size + (size & 1):]
            if cid == b"fmt ":
                fmt = _wav_format(body, self.what)

    def blocks(self):
        if not self.started:
            self._start()
        check_raw = b""
        self._buffered = self._pending
        while True:
            if len(self._buffered) < self.frame:
                more = self._read(self.block_bytes)
                if not more:
                    break
                self._buffered += more
                continue
            n = min(len(self._buffered), self.block_bytes) // self.frame * self.frame
            raw, self._buffered = self._buffered[:n], self._buffered[n:]
            x = _decode(raw, self.fmt).reshape(-1, self.channels).mean(axis=1)
            if not self.checked:
                check_raw += raw
                check_format(x, self.fmt, check_raw, self.what)
                self.checked = len(check_raw) >= CHECK_S * self.rate * self.frame
            elif self.fmt in ("f32le", "f64le") and not np.all(np.isfinite(x)):
                raise InputError("the stream holds non-finite samples (NaN or infinity)", self.what)
            yield x


class MicSource(Source):
    """The default (or a named) input device through ``sounddevice`` (PortAudio), an optional extra."""

    def __init__(self, device=None, rate: int | None = None, block_s: float = 0.01):
        try:
            import sounddevice as sd
        except (ImportError, OSError) as exc:
            raise InputError("--mic needs the optional extra 'live' (pip install 'visemeface[live]': sounddevice "
                             f"and the PortAudio library): {exc}") from None
        try:
            info = sd.query_devices(device, kind="input")
        except (ValueError, sd.PortAudioError) as exc:
            raise InputError(f"--mic: no microphone ({exc})") from None
        self.rate = check_rate(rate or int(info["default_samplerate"]), "--mic")
        self.what = f"microphone {info['name']!r}"
        self.queue: queue.Queue = queue.Queue()
        self.overflows = 0

        def callback(indata, frames, t, status):
            if status.input_overflow:
                self.overflows += 1
            self.queue.put(indata[:, 0].astype(np.float64))

        try:
            self.stream = sd.InputStream(device=device, channels=1, samplerate=self.rate, dtype="float32",
                                         blocksize=max(1, int(round(block_s * self.rate))), callback=callback)
            self.stream.start()
        except sd.PortAudioError as exc:
            raise InputError(f"--mic: the microphone cannot be opened ({exc})") from None

    def pending(self) -> bool:
        return not self.queue.empty()

    def blocks(self):
        while True:
            try:
                yield self.queue.get(timeout=0.5)
            except queue.Empty:
                if not self.stream.active:
                    return

    def close(self) -> None:
        self.stream.close()


class Resampler:
    """Streaming resampling to ``target`` Hz: a windowed-sinc low-pass (Hamming, ``taps``) at the input rate,
    then linear interpolation at the output instants. Output sample ``m`` is the input at
    ``m / target - delay`` s, the filter's half length (31 samples: 0.7 ms at 44.1 kHz), the same across
    blocks. The delay is left in: compensating it would hold each block's last 10 ms decoder frame back
    until the next block (measured: 10 ms more latency), for a shift 1/50 of a 30 fps frame."""

    def __init__(self, rate: int, target: int = 16000, taps: int = 63):
        self.rate, self.target = int(rate), int(target)
        self.step = self.rate / self.target
        cutoff = min(1.0, self.target / self.rate) * 0.9
        n = np.arange(taps) - (taps - 1) / 2
        h = cutoff * np.sinc(cutoff * n) * np.hamming(taps)
        self.h = h / h.sum()
        self.delay = (taps - 1) / 2          # input samples, in seconds: delay / rate
        self.history = np.zeros(taps - 1)
        self.y = np.zeros(0)          # filtered samples kept, the first at global index y0
        self.y0 = 0
        self.m = 0                    # next output sample

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=np.float64)
        if self.rate == self.target:
            return x
        xs = np.concatenate([self.history, x])
        self.history = xs[-(len(self.h) - 1):]
        self.y = np.concatenate([self.y, np.convolve(xs, self.h, mode="valid")])
        last = self.y0 + self.y.size - 1                       # global index of the newest filtered sample
        m_end = int(np.floor((last - 1) / self.step)) + 1 if last >= 1 else 0
        if m_end <= self.m:
            return np.zeros(0)
        p = np.arange(self.m, m_end) * self.step - self.y0
        i = np.floor(p).astype(np.int64)
        frac = p - i
        out = self.y[i] * (1 - frac) + self.y[i + 1] * frac
        self.m = m_end
        keep = min(int(np.floor(self.m * self.step)) - self.y0, self.y.size)
        self.y, self.y0 = self.y[keep:], self.y0 + keep
        return out

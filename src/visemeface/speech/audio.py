"""Reading recordings: any audio file or a video's sound track, and where its speech is.

:func:`read_audio` decodes a sound file with ``soundfile`` (WAV, FLAC, OGG,
MP3 where libsndfile reads it) and anything else ffmpeg reads (a video's
audio track, M4A...) through the ffmpeg of ``imageio-ffmpeg``, mixed to mono
float64. :func:`speech_span` finds the speech relative to the recording's own
noise floor, so a quiet recording and a loud one are trimmed alike.

Speech span
-----------
The signal is cut into frames of 20 ms every 10 ms; frame :math:`k` has the
level :math:`L_k = 20\\log_{10}\\mathrm{rms}_k` (dB). With the noise floor
:math:`F` (the 10th percentile of :math:`L`) and the peak :math:`P` (the
maximum), a frame is speech when

.. math:: L_k > F + \\max\\big(6\\,\\mathrm{dB},\\; 0.3\\,(P - F)\\big),

and the span runs from the first run of at least :data:`MIN_RUN_S` of speech
frames to the end of the last such run (0.3 was chosen on the three GRID
clips: 0.2 let a noise burst of ``bbaf2n`` start its speech 0.36 s early). A
recording whose peak is below :data:`MIN_PEAK_DBFS` (silence) or less than
:data:`MIN_DYNAMIC_DB` above its floor (steady hum) holds no speech.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
from pathlib import Path

import numpy as np

from visemeface.errors import InputError

__all__ = ["AUDIO_SUFFIXES", "MIN_DYNAMIC_DB", "audio_duration", "is_recording", "media_wav", "read_audio", "resample",
           "speech_span"]

#: Suffixes read as sound files (soundfile first, then ffmpeg).
AUDIO_SUFFIXES = (".wav", ".flac", ".ogg", ".oga", ".opus", ".mp3", ".aif", ".aiff", ".au", ".m4a", ".aac",
                  ".wma")
#: Video containers whose audio track is the recording.
VIDEO_SUFFIXES = (".mp4", ".mpg", ".mpeg", ".mov", ".mkv", ".avi", ".webm", ".m4v")
#: A recording whose loudest frame is less than this above its noise floor holds no speech (dB):
#: silence and steady noise or hum stay within 1-3 dB; speech without pauses (cut tight) spans 12 dB or more.
MIN_DYNAMIC_DB = 8.0
#: A recording whose loudest 20 ms frame is below this (dB re full scale) is silent, however far above its
#: floor that is (a refusal read "loudest 112 dB above its floor, speech needs 8" for this reason).
MIN_PEAK_DBFS = -70.0
#: Shortest run of loud frames that counts as speech (s): shorter ones are clicks.
MIN_RUN_S = 0.05
#: Longest recording read (s).
MAX_SECONDS = 3 * 3600


def is_recording(path) -> bool:
    """True when ``path`` names a sound or video file (by suffix), not a transcript."""
    return Path(path).suffix.lower() in AUDIO_SUFFIXES + VIDEO_SUFFIXES


def _ffmpeg_decode(path: Path) -> tuple[np.ndarray, int]:
    import imageio_ffmpeg

    exe = imageio_ffmpeg.get_ffmpeg_exe()
    probe = subprocess.run([exe, "-hide_banner", "-i", str(path)], capture_output=True, text=True)
    rate = 0
    for line in probe.stderr.splitlines():
        if "Audio:" in line and " Hz" in line:
            rate = int(line.split(" Hz")[0].split()[-1])
            break
    if rate == 0:
        raise InputError("unreadable audio (not a sound file, and no audio stream in it)", path)
    proc = subprocess.run([exe, "-v", "error", "-i", str(path), "-vn", "-ac", "1", "-f", "f32le",
                           "-acodec", "pcm_f32le", "-"], capture_output=True)
    if proc.returncode != 0:
        why = (proc.stderr.decode(errors="replace").strip().splitlines() or ["ffmpeg failed"])[-1]
        raise InputError(f"unreadable audio ({why})", path)
    return np.frombuffer(proc.stdout, dtype="<f4").astype(np.float64), rate


@contextlib.contextmanager
def native_stderr_quiet():
    """Silence what C libraries print on file descriptor 2 (libmpg123's "warning: Cannot read next
    header" on a fake MP3) while libsndfile reads: the user sees one line, the InputError's."""
    try:
        saved = os.dup(2)
    except OSError:                     # no stderr at all
        yield
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)


def _check_sound(n_samples, rate, samples, path) -> None:
    """A recording holds samples at a positive rate, all finite (``samples``: those read)."""
    if n_samples <= 0 or rate <= 0:
        raise InputError("audio file holds no samples", path)
    if not np.all(np.isfinite(samples)):
        raise InputError("audio holds non-finite samples (NaN or infinity)", path)


def read_audio(path) -> tuple[np.ndarray, int]:
    """Decode a recording to mono float64 samples and its sample rate.

    Parameters
    ----------
    path : str or Path
        A sound file or a video with an audio track.

    Returns
    -------
    samples : ndarray, float64 (n,)
        The channels' mean, in [-1, 1].
    rate : int
        Samples per second.

    Raises
    ------
    InputError
        Missing or unreadable file, no audio stream, no samples, NaN or infinite samples.
    """
    import soundfile as sf

    path = Path(path)
    if not path.is_file():
        raise InputError("audio file not found", path)
    try:
        with native_stderr_quiet():
            data, rate = sf.read(str(path), dtype="float64", always_2d=True)
        samples = data.mean(axis=1)
    except Exception:  # not a format libsndfile knows: let ffmpeg try (video tracks, m4a...)
        samples, rate = _ffmpeg_decode(path)
    _check_sound(samples.size, rate, samples, path)
    if samples.size / rate > MAX_SECONDS:
        raise InputError(f"audio lasts {samples.size / rate:.0f} s, over the {MAX_SECONDS} s limit", path)
    return samples, int(rate)


def audio_duration(path) -> float:
    """Seconds of sound in a recording, checked readable and finite without decoding hours of it.

    A sound file's header gives its length and its first minute is read (and checked for NaN);
    anything else (a video's track) is decoded by :func:`read_audio`.
    """
    import soundfile as sf

    path = Path(path)
    if not path.is_file():
        raise InputError("audio file not found", path)
    try:
        with native_stderr_quiet():
            info = sf.info(str(path))
            head, _ = sf.read(str(path), frames=min(info.frames, 60 * info.samplerate), dtype="float32")
    except Exception:  # not a libsndfile format: decode it all (videos: minutes, not hours)
        samples, rate = read_audio(path)
        return samples.size / rate
    _check_sound(info.frames, info.samplerate, head, path)
    return info.frames / info.samplerate


def resample(samples: np.ndarray, rate: int, target: int) -> np.ndarray:
    """Mono ``samples`` from ``rate`` to ``target`` Hz (ffmpeg's band-limited resampler, through a pipe).

    ffmpeg rather than :func:`scipy.signal.resample_poly`: importing ``scipy.signal`` alone takes
    longer than aligning a short recording.
    """
    x = np.asarray(samples, dtype=np.float64)
    if rate == target or x.size == 0:
        return x
    import imageio_ffmpeg

    proc = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-f", "f32le", "-ar", str(int(rate)),
                           "-ac", "1", "-i", "-", "-ar", str(int(target)), "-f", "f32le", "-"],
                          input=x.astype("<f4").tobytes(), capture_output=True, check=True)
    return np.frombuffer(proc.stdout, dtype="<f4").astype(np.float64)


def frame_levels(samples: np.ndarray, rate: int, frame: float = 0.02, hop: float = 0.01):
    """Frame start times (s) and RMS levels (dB re full scale) of mono samples."""
    n = max(1, int(round(frame * rate)))
    h = max(1, int(round(hop * rate)))
    x = np.asarray(samples, dtype=np.float64)
    if x.size < n:
        x = np.pad(x, (0, n - x.size))
    starts = np.arange(0, x.size - n + 1, h)
    windows = np.lib.stride_tricks.sliding_window_view(x, n)[starts]
    rms = np.sqrt(np.mean(windows ** 2, axis=1))
    return starts / rate, 20 * np.log10(np.maximum(rms, 1e-10)), n / rate


def speech_span(samples: np.ndarray, rate: int, where=None) -> tuple[float, float]:
    """Start and end (s) of the speech in a recording, relative to its noise floor.

    See the module docstring for the rule.

    Raises
    ------
    InputError
        No speech: the recording is silent or a steady noise.
    """
    times, level, frame = frame_levels(samples, rate)
    floor, peak = float(np.percentile(level, 10)), float(level.max())
    if peak < MIN_PEAK_DBFS:                  # the reason given is the one that holds
        raise InputError(f"no speech found: the audio is silent (its loudest moment is {peak:.0f} dBFS, "
                         f"speech needs {MIN_PEAK_DBFS:g} dBFS or louder)", where)
    if peak - floor < MIN_DYNAMIC_DB:
        raise InputError(f"no speech found: the audio is a steady noise (loudest {peak - floor:.0f} dB above "
                         f"its floor, speech needs {MIN_DYNAMIC_DB:g})", where)
    loud = level > floor + max(6.0, 0.3 * (peak - floor))
    edges = np.flatnonzero(np.diff(np.r_[0, loud.astype(np.int8), 0]))
    runs = [(a, b) for a, b in zip(edges[::2], edges[1::2])
            if times[b - 1] + frame - times[a] >= MIN_RUN_S]
    if not runs:
        runs = [(int(np.argmax(level)), int(np.argmax(level)) + 1)]
    t0 = float(times[runs[0][0]])
    t1 = float(min(samples.size / rate, times[runs[-1][1] - 1] + frame))
    return t0, t1


def media_wav(path, folder) -> Path:
    """A WAV of a recording for muxing: ``path`` itself for a sound file, else its track in ``folder``.

    A video handed to the muxer as "audio" would offer ffmpeg a second video
    stream; its sound is written to ``folder/<stem>.wav`` instead, as 32-bit float: the samples decoded
    exactly, so what is analysed of it (the articulation, the gestures) is what ``--audio`` with the same
    video gives (16-bit PCM rounded the channels' mean and moved the jaw by up to 0.005).
    """
    import soundfile as sf

    path = Path(path)
    if path.suffix.lower() in AUDIO_SUFFIXES:
        return path
    samples, rate = read_audio(path)
    out = Path(folder) / (path.stem + ".wav")
    sf.write(str(out), samples.astype(np.float32), rate, subtype="FLOAT")
    return out

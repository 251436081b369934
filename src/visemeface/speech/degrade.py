"""Degraded copies of a recording, for checking that alignment holds on voices and rooms it was not tuned on.

:func:`degrade` returns ``(samples, rate)`` of one of :data:`KINDS`: quieter (16-bit quantised, with
or without a microphone's noise floor), white or speech-shaped noise at a signal-to-noise ratio,
played faster or slower (pitch moves with it, as a higher or lower voice), the telephone band
(300-3400 Hz, 8 kHz, mu-law) or a reverberant room. Seeded: the same call gives the same samples.
Used by ``benchmarks/align_margin.py`` and the alignment tests.
"""

from __future__ import annotations

import numpy as np

__all__ = ["KINDS", "degrade"]

#: Kind -> what it does (the name's number is its parameter).
KINDS = {
    "clean": "as recorded",
    "quiet30": "30 dB quieter, 16-bit",
    "quiet20floor": "20 dB quieter over a noise floor at -66 dB of full scale, 16-bit",
    "white15": "white noise at 15 dB SNR",
    "white10": "white noise at 10 dB SNR",
    "speech10": "stationary noise with the recording's own spectrum at 10 dB SNR",
    "speed0.85": "played at 0.85 of its speed (pitch 0.85 times)",
    "speed1.2": "played at 1.2 times its speed (pitch 1.2 times)",
    "telephone": "300-3400 Hz band, 8 kHz, 8-bit mu-law",
    "reverb": "a room: 0.5 s reverberation time, reverberant sound 10 dB above the direct",
}


def _q16(x: np.ndarray) -> np.ndarray:
    return np.round(np.clip(x, -1.0, 1.0) * 32767) / 32767


def _noise_at(x: np.ndarray, noise: np.ndarray, snr_db: float) -> np.ndarray:
    return x + noise * np.sqrt(np.mean(x ** 2) / 10 ** (snr_db / 10) / np.mean(noise ** 2))


def degrade(samples, rate: int, kind: str, seed: int = 7) -> tuple[np.ndarray, int]:
    """``(samples, rate)`` of mono ``samples`` at ``rate`` degraded as ``kind`` (:data:`KINDS`)."""
    from scipy import signal

    from visemeface.speech.audio import resample

    if kind not in KINDS:
        raise ValueError(f"unknown degradation {kind!r}; one of {', '.join(KINDS)}")
    x = np.asarray(samples, dtype=np.float64).ravel()
    rng = np.random.default_rng(seed)
    if kind == "clean":
        return x.copy(), rate
    if kind == "quiet30":
        return _q16(x * 10 ** (-30 / 20)), rate
    if kind == "quiet20floor":
        return _q16(x * 10 ** (-20 / 20) + rng.normal(0.0, 10 ** (-66 / 20), x.size)), rate
    if kind.startswith("white"):
        return _noise_at(x, rng.normal(size=x.size), float(kind[5:])), rate
    if kind.startswith("speech"):
        spectrum = np.abs(np.fft.rfft(x)) * np.exp(2j * np.pi * rng.random(x.size // 2 + 1))
        return _noise_at(x, np.fft.irfft(spectrum, x.size), float(kind[6:])), rate
    if kind.startswith("speed"):
        return resample(x, rate, int(round(rate / float(kind[5:])))), rate   # fewer samples at the same rate
    if kind == "telephone":
        sos = signal.butter(6, [300, 3400], "bandpass", fs=rate, output="sos")
        y = resample(signal.sosfilt(sos, x), rate, 8000)
        y = y / max(float(np.abs(y).max()), 1e-12)
        mu = 255.0
        code = np.round(np.sign(y) * np.log1p(mu * np.abs(y)) / np.log1p(mu) * 127) / 127
        return 0.9 * np.sign(code) * ((1 + mu) ** np.abs(code) - 1) / mu, 8000
    # reverb: the direct sound, then exponentially decaying noise (-60 dB at 0.5 s) of 10 times its energy
    t = np.arange(1, int(0.5 * rate)) / rate
    tail = rng.normal(size=t.size) * np.exp(-6.9 * t / 0.5)
    h = np.r_[1.0, tail * np.sqrt(10.0 / np.sum(tail ** 2))]
    y = signal.fftconvolve(x, h)[: x.size]
    return y * (np.abs(x).max() / max(float(np.abs(y).max()), 1e-12)), rate

"""What a recording says about how it was spoken: level, pitch (F0) and the first two formants, per 10 ms.

:func:`analyse` turns mono samples into an :class:`Acoustics` (frames every :data:`HOP_S`), the input of
the articulation (:mod:`visemeface.speech.articulation`, JA/LI from the recording) and of the
gestures (:mod:`visemeface.speech.gestures`, head, brows and gaze from prosody). Everything is numpy:
no pitch tracker dependency.

Level
    RMS of 25 ms frames in dB re full scale (:func:`visemeface.speech.audio.frame_levels`).
Pitch
    YIN (de Cheveigné & Kawahara, JASA 111:1917, 2002): the cumulative-mean-normalised difference
    function :math:`d'(\\tau)` of 40 ms frames over lags for 60-400 Hz, its first dip below
    :data:`YIN_THRESHOLD` (else its minimum) refined by parabolic interpolation; a frame is voiced
    when :math:`d'` there is below the threshold and the frame is within 35 dB of the loudest one.
Formants
    LPC of 25 ms pre-emphasised Hamming frames (autocorrelation method, order :data:`LPC_ORDER` at the
    :data:`LPC_RATE` the samples are decimated to), the angles of the predictor's roots with bandwidth under
    500 Hz between 150 and 4000 Hz; F1 the lowest, F2 the next (Markel & Gray, *Linear Prediction of
    Speech*, 1976). Voiced frames only; NaN elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["HOP_S", "Acoustics", "analyse", "span_mean", "span_median"]

#: Analysis hop (s).
HOP_S = 0.01
#: YIN's absolute threshold on the normalised difference (de Cheveigné & Kawahara 2002 use 0.1-0.15).
YIN_THRESHOLD = 0.15
#: Pitch range searched (Hz): adult speech.
F0_MIN, F0_MAX = 60.0, 400.0
#: Rate the formants are measured at (Hz): 5.5 kHz of band holds F1-F3 of men and women.
LPC_RATE = 11025
#: LPC order at LPC_RATE (two poles per kHz and two for the glottal source and radiation).
LPC_ORDER = 12
#: Voiced frames within this many dB of the loudest frame (quieter: breath, noise).
VOICED_RANGE_DB = 35.0


@dataclass(frozen=True)
class Acoustics:
    """Frame-wise measures of a recording, frame ``k`` centred at ``times[k]`` (s).

    Attributes
    ----------
    times : (K,) float
    level : (K,) float
        dB re full scale.
    f0 : (K,) float
        Hz; NaN where unvoiced.
    f1, f2 : (K,) float
        Hz; NaN where unvoiced or no formant found.
    duration : float
        Length of the recording (s).
    """

    times: np.ndarray
    level: np.ndarray
    f0: np.ndarray
    f1: np.ndarray
    f2: np.ndarray
    duration: float

    @property
    def voiced(self) -> np.ndarray:
        return np.isfinite(self.f0)


def _frames(x: np.ndarray, rate: int, length_s: float, centres: np.ndarray) -> np.ndarray:
    """(K, n) windows of ``x`` of ``length_s`` centred on ``centres`` (s), zero-padded at the ends."""
    n = max(2, int(round(length_s * rate)))
    pad = n
    xp = np.pad(x, (pad, pad + n))
    starts = np.clip(np.round(centres * rate).astype(int) - n // 2 + pad, 0, xp.size - n)
    return np.lib.stride_tricks.sliding_window_view(xp, n)[starts]


def _decimate(x: np.ndarray, rate: int, target: int) -> tuple[np.ndarray, int]:
    """``x`` low-passed (FFT brick wall) and resampled to about ``target`` Hz by linear interpolation."""
    if rate <= target:
        return x, rate
    spec = np.fft.rfft(x)
    freqs = np.fft.rfftfreq(x.size, 1.0 / rate)
    spec[freqs > 0.45 * target] = 0.0
    y = np.fft.irfft(spec, x.size)
    t_new = np.arange(0.0, x.size / rate, 1.0 / target)
    return np.interp(t_new, np.arange(x.size) / rate, y), target


def _yin(x: np.ndarray, rate: int, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F0 (Hz, NaN unvoiced) and the aperiodicity d' at the chosen lag, per frame."""
    tau_min = max(2, int(rate / F0_MAX))
    tau_max = int(rate / F0_MIN) + 1
    w = tau_max                                   # integration window: one period of the lowest pitch
    seg = _frames(x, rate, (w + tau_max) / rate, times + (tau_max / 2) / rate)  # (K, w + tau_max)
    nfft = 1 << int(np.ceil(np.log2(seg.shape[1] + w)))
    a = np.fft.rfft(seg[:, :w], nfft)
    b = np.fft.rfft(seg, nfft)
    cross = np.fft.irfft(np.conj(a) * b, nfft)[:, :tau_max + 1]          # r_t(tau) = sum x_j x_{j+tau}
    sq = np.concatenate([np.zeros((seg.shape[0], 1)), np.cumsum(seg ** 2, axis=1)], axis=1)
    e0 = sq[:, w][:, None]
    taus = np.arange(tau_max + 1)
    e_tau = sq[:, taus + w] - sq[:, taus]
    d = np.maximum(e0 + e_tau - 2 * cross, 0.0)
    d[:, 0] = 0.0
    csum = np.cumsum(d[:, 1:], axis=1)
    dn = np.ones_like(d)
    dn[:, 1:] = d[:, 1:] * taus[1:] / np.where(csum > 0, csum, 1.0)
    dn[:, :tau_min] = np.inf
    below = dn < YIN_THRESHOLD
    # first dip below the threshold: the first lag below it, then down to its local minimum
    first = np.where(below.any(axis=1), np.argmax(below, axis=1), np.argmin(dn, axis=1))
    k = np.arange(d.shape[0])
    tau = first.copy()
    for _ in range(tau_max):                        # walk to the local minimum (a few steps in practice)
        nxt = np.minimum(tau + 1, tau_max)
        step = dn[k, nxt] < dn[k, tau]
        if not step.any():
            break
        tau = np.where(step, nxt, tau)
    lo, hi = np.maximum(tau - 1, 1), np.minimum(tau + 1, tau_max)
    y0, y1, y2 = dn[k, lo], dn[k, tau], dn[k, hi]
    y0 = np.where(np.isfinite(y0), y0, y1)
    den = y0 - 2 * y1 + y2
    shift = np.where(np.abs(den) > 1e-12, 0.5 * (y0 - y2) / np.where(np.abs(den) > 1e-12, den, 1.0), 0.0)
    tau_f = tau + np.clip(shift, -1, 1)
    f0 = rate / np.maximum(tau_f, 1e-9)
    return f0, y1


def _lpc_formants(x: np.ndarray, rate: int, times: np.ndarray, which: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F1 and F2 (Hz) of the frames ``which`` (bool mask); NaN elsewhere."""
    f1 = np.full(times.size, np.nan)
    f2 = np.full(times.size, np.nan)
    idx = np.flatnonzero(which)
    if idx.size == 0:
        return f1, f2
    y = np.append(x[0], x[1:] - 0.97 * x[:-1])                      # pre-emphasis
    win = _frames(y, rate, 0.025, times[idx]) * np.hamming(int(round(0.025 * rate)) if int(round(0.025 * rate)) > 1
                                                             else 2)
    p = LPC_ORDER
    nfft = 1 << int(np.ceil(np.log2(2 * win.shape[1])))
    spec = np.fft.rfft(win, nfft)
    r = np.fft.irfft(np.abs(spec) ** 2, nfft)[:, :p + 1]
    r[:, 0] *= 1.0 + 1e-6
    toe = r[:, np.abs(np.arange(p)[:, None] - np.arange(p)[None, :])]    # (K, p, p)
    ok = r[:, 0] > 1e-12
    coef = np.zeros((idx.size, p))
    coef[ok] = np.linalg.solve(toe[ok], r[ok, 1:p + 1][..., None])[..., 0]
    for j, i in enumerate(idx):
        if not ok[j]:
            continue
        roots = np.roots(np.r_[1.0, -coef[j]])
        roots = roots[np.imag(roots) > 0]
        freq = np.angle(roots) * rate / (2 * np.pi)
        bw = -np.log(np.maximum(np.abs(roots), 1e-12)) * rate / np.pi
        f = np.sort(freq[(bw < 500) & (freq > 150) & (freq < 4000)])
        if f.size >= 2:
            f1[i], f2[i] = f[0], f[1]
    return f1, f2


def analyse(samples: np.ndarray, rate: int) -> Acoustics:
    """Level, F0 and formants of mono ``samples`` every :data:`HOP_S` (module doc)."""
    from visemeface.speech.audio import frame_levels

    x = np.asarray(samples, dtype=np.float64)
    duration = x.size / rate
    n = max(1, int(np.floor(duration / HOP_S)))
    times = (np.arange(n) + 0.5) * HOP_S
    starts, level, frame = frame_levels(x, rate, frame=0.025, hop=HOP_S)
    level = np.interp(times, starts + frame / 2, level)
    y, r = _decimate(x, rate, 16000)
    f0, ap = _yin(y, r, times)
    voiced = (ap < YIN_THRESHOLD) & (level > level.max() - VOICED_RANGE_DB) & (f0 >= F0_MIN) & (f0 <= F0_MAX)
    f0 = np.where(voiced, f0, np.nan)
    z, rz = _decimate(y, r, LPC_RATE)
    f1, f2 = _lpc_formants(z, rz, times, voiced)
    return Acoustics(times, level, f0, f1, f2, duration)


def _span_index(times: np.ndarray, start: np.ndarray, end: np.ndarray, middle: float) -> list[np.ndarray]:
    out = []
    for a, b in zip(start, end):
        trim = (b - a) * (1 - middle) / 2
        lo, hi = np.searchsorted(times, a + trim), np.searchsorted(times, b - trim, side="right")
        if hi <= lo:                                   # shorter than a hop: the nearest frame
            lo = int(np.clip(np.searchsorted(times, (a + b) / 2) - 1, 0, times.size - 1))
            hi = lo + 1
        out.append(np.arange(lo, min(hi, times.size)))
    return out


def _span_stat(values, times, start, end, middle, stat) -> np.ndarray:
    out = np.full(len(start), np.nan)
    for s, ix in enumerate(_span_index(times, np.asarray(start, float), np.asarray(end, float), middle)):
        v = values[ix]
        v = v[np.isfinite(v)]
        if v.size:
            out[s] = stat(v)
    return out


def span_mean(values: np.ndarray, times: np.ndarray, start, end, middle: float = 0.6) -> np.ndarray:
    """Mean of ``values`` over the middle ``middle`` of each span ``[start, end)`` (NaN ignored; NaN if none)."""
    return _span_stat(values, times, start, end, middle, np.mean)


def span_median(values: np.ndarray, times: np.ndarray, start, end, middle: float = 0.6) -> np.ndarray:
    """Median of ``values`` over the middle of each span (NaN ignored; NaN if none)."""
    return _span_stat(values, times, start, end, middle, np.median)

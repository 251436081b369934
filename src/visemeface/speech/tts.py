"""Speech synthesis for ``say``: eSpeak NG through the optional ``tts`` extra.

``pip install "visemeface[tts]"`` installs ``espeakng-loader`` (a wheel holding
libespeak-ng and its voice data, offline). eSpeak NG is GPL-3.0, so it is an
optional extra, never imported by visemeface itself: :func:`synthesise` runs
it in a child Python process (``python -m visemeface.speech.tts TEXT OUT.wav``)
that loads the library with ``ctypes`` and writes a 16-bit WAV. Without the
extra, :func:`available` is false and :data:`HINT` says how to get it.

``say`` then aligns its own text to the synthesised audio
(:func:`visemeface.speech.align.utterance_from_audio`), so the phone timing
is that of the sound muxed into the video.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

from visemeface.errors import InputError

__all__ = ["HINT", "available", "synthesise"]

#: One line for users without the extra.
HINT = 'no speech synthesiser: install the optional extra (pip install "visemeface[tts]", GPL-3.0 eSpeak NG) ' \
       "for a spoken soundtrack; the video is silent"
#: Silence (s) before and after the synthesised speech.
PAD_S = 0.15
#: Seconds a synthesis may take before it is abandoned.
TIMEOUT_S = 120


def available() -> bool:
    """True when the ``tts`` extra (``espeakng-loader``) is installed."""
    return importlib.util.find_spec("espeakng_loader") is not None


def synthesise(text: str, path, voice: str = "en-us", rate_wpm: float | None = None) -> Path:
    """Speak ``text`` into the WAV file ``path`` (eSpeak NG in a child process).

    Parameters
    ----------
    text : str
        Plain text (emotion tags are removed first).
    path : str or Path
        The WAV to write (16-bit mono at eSpeak's rate, 22050 Hz).
    voice : str
        eSpeak NG voice.
    rate_wpm : float, optional
        Speaking rate (eSpeak's default 175 words/min).

    Raises
    ------
    InputError
        The extra is not installed, or synthesis failed.
    """
    from visemeface.speech.g2p import _TAG

    if not available():
        raise InputError(HINT)
    plain = " ".join(_TAG.sub(" ", str(text)).split())
    cmd = [sys.executable, "-m", "visemeface.speech.tts", plain, str(path), voice,
           str(int(round(rate_wpm))) if rate_wpm else "0"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise InputError(f"speech synthesis took over {TIMEOUT_S} s") from None
    if proc.returncode != 0 or not Path(path).is_file():
        why = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise InputError(f"speech synthesis failed ({why})")
    return Path(path)


def _child(text: str, out: str, voice: str, rate: int) -> int:
    """The child process: libespeak-ng synthesises ``text`` into ``out`` (see the module docstring)."""
    import ctypes

    import espeakng_loader
    import numpy as np
    import soundfile as sf

    lib = ctypes.CDLL(espeakng_loader.get_library_path())
    callback_t = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.c_void_p)
    chunks = []

    def collect(wav, n, _events):
        if n > 0:
            chunks.append(np.ctypeslib.as_array(wav, shape=(n,)).copy())
        return 0

    keep = callback_t(collect)
    lib.espeak_Initialize.restype = ctypes.c_int
    rate_hz = lib.espeak_Initialize(2, 0, espeakng_loader.get_data_path().encode(), 0)  # AUDIO_OUTPUT_SYNCHRONOUS
    if rate_hz <= 0:
        print("eSpeak NG did not initialise", file=sys.stderr)
        return 1
    lib.espeak_SetSynthCallback(keep)
    if lib.espeak_SetVoiceByName(voice.encode()) != 0:
        print(f"unknown eSpeak NG voice {voice!r}", file=sys.stderr)
        return 1
    if rate:
        lib.espeak_SetParameter(1, rate, 0)                       # espeakRATE
    data = text.encode("utf-8") + b"\0"
    if lib.espeak_Synth(data, len(data), 0, 1, 0, 0, None, None) != 0:   # POS_CHARACTER, espeakCHARS_AUTO
        print("eSpeak NG could not synthesise the text", file=sys.stderr)
        return 1
    lib.espeak_Synchronize()
    samples = np.concatenate(chunks) if chunks else np.zeros(0, np.int16)
    if samples.size == 0:
        print("eSpeak NG produced no sound", file=sys.stderr)
        return 1
    pad = np.zeros(int(PAD_S * rate_hz), np.int16)           # a breath of silence either side, as a recording has
    sf.write(out, np.concatenate([pad, samples, pad]), rate_hz, subtype="PCM_16")
    return 0


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])))

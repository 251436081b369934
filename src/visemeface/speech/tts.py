"""Speech synthesis for ``say``: eSpeak NG through the optional ``tts`` extra.

``pip install "visemeface[tts]"`` installs ``espeakng-loader`` (a wheel holding
libespeak-ng and its voice data, offline). eSpeak NG is GPL-3.0, so it is an
optional extra, never imported by visemeface itself: :func:`synthesise` runs
it in a child Python process (``python -m visemeface.speech.tts TEXT OUT.wav``)
that loads the library with ``ctypes`` and writes a 16-bit WAV. Without the
extra, :func:`available` is false and :data:`HINT` says how to get it.

The child also reports eSpeak NG's own events: each phone it spoke (IPA)
and each word, at the sample where it starts. ``say`` aligns its text to the
synthesised audio (:func:`visemeface.speech.align.utterance_from_audio`), so
the phone timing is that of the sound muxed into the video, and keeps that
alignment while its words start where eSpeak NG says they do
(:data:`AGREE_S`); when the audio cannot be aligned (the acoustic model is
of human voices) or the alignment strays, :func:`events_utterance` times the
phones by the synthesiser's events instead, and if those are unusable,
:func:`stretched_utterance` lays the duration model's timing over the speech.
Never an error for the timing: the sound is the synthesiser's own.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

from dataclasses import dataclass, field

from visemeface.errors import InputError

__all__ = ["AGREE_S", "HINT", "Synthesis", "available", "events_utterance", "stretched_utterance",
           "synthesise", "utterance_of"]

#: One line for users without the extra.
HINT = 'no speech synthesiser: install the optional extra (pip install "visemeface[tts]", GPL-3.0 eSpeak NG) ' \
       "for a spoken soundtrack; the video is silent"
#: Silence (s) before and after the synthesised speech.
PAD_S = 0.15
#: Seconds a synthesis may take before it is abandoned.
TIMEOUT_S = 120
#: Mean distance (s) between the aligned words' starts and eSpeak NG's word events above which the
#: alignment is taken to have strayed and the events time the phones. Four 10 ms decoder frames: on
#: eSpeak's own sentences the alignment's word starts lie 10-30 ms from the events (mean).
AGREE_S = 0.04
#: eSpeak NG event types (speak_lib.h).
_WORD, _END, _PHONEME, _MSG_END = 1, 5, 7, 6
#: IPA letters of eSpeak NG that the project's IPA table lacks, as the nearest it has.
_IPA_NEAREST = {"ᵻ": "ɪ", "ɬ": "l"}


@dataclass(frozen=True)
class Synthesis:
    """A synthesised WAV and eSpeak NG's events in it.

    Attributes
    ----------
    path : Path
        The WAV (16-bit mono).
    text : str
        The plain text spoken (emotion tags removed, white space collapsed).
    phones : list of (str, float, float)
        eSpeak NG's phones (IPA with stress marks; ``""`` a pause) with start and end (s, in the WAV).
    words : list of (int, int, float)
        Each word event: 0-based character offset and length in ``text``, start (s).
    marks : list of int
        Character offset in ``text`` of each emotion tag of the original text, in order.
    end : float
        Length of the WAV (s).
    """

    path: Path
    text: str
    phones: list = field(default_factory=list)
    words: list = field(default_factory=list)
    marks: list = field(default_factory=list)
    end: float = 0.0


def available() -> bool:
    """True when the ``tts`` extra (``espeakng-loader``) is installed."""
    return importlib.util.find_spec("espeakng_loader") is not None


def plain_text(text: str) -> tuple[str, list[int]]:
    """The text eSpeak NG speaks (emotion tags removed; its words as this project reads them,
    :func:`~visemeface.speech.tokens.spoken`, so the sound says what the aligner looks for) and the character
    offset in it of each tag (where the next word starts)."""
    from visemeface.speech.tokens import TAG, spoken

    plain, marks, pos = "", [], 0

    def add(piece: str) -> str:
        words = spoken(piece)
        return (f"{plain} {words}" if plain else words) if words else plain

    for m in TAG.finditer(text):
        plain = add(text[pos:m.start()])
        marks.append(len(plain) + (1 if plain else 0))
        pos = m.end()
    return add(text[pos:]), marks


def synthesise(text: str, path, voice: str = "en-us", rate_wpm: float | None = None) -> Synthesis:
    """Speak ``text`` into the WAV file ``path`` (eSpeak NG in a child process), with its events.

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
    import json

    if not available():
        raise InputError(HINT)
    plain, marks = plain_text(str(text))
    cmd = [sys.executable, "-m", "visemeface.speech.tts", plain, str(path), voice,
           str(int(round(rate_wpm))) if rate_wpm else "0"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise InputError(f"speech synthesis took over {TIMEOUT_S} s") from None
    if proc.returncode != 0 or not Path(path).is_file():
        why = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise InputError(f"speech synthesis failed ({why})")
    try:
        report = json.loads(proc.stdout)
    except json.JSONDecodeError:
        report = {"rate": 1, "pad": 0, "samples": 0, "events": []}
    return _synthesis(Path(path), plain, marks, report)


def _synthesis(path: Path, plain: str, marks: list[int], report: dict) -> Synthesis:
    """A :class:`Synthesis` from the child's report (rate, padding, sample count, events)."""
    rate, pad = float(report["rate"]), int(report["pad"])
    end = (int(report["samples"]) + 2 * pad) / rate
    events = sorted(report["events"], key=lambda e: e[3])          # stable: the report's order at a tie
    bounds = [e for e in events if e[0] in (_PHONEME, _END, _MSG_END)]
    phones = []
    for k, e in enumerate(bounds):                   # a phone lasts until the next phone or sentence end
        if e[0] == _PHONEME:
            start = (e[3] + pad) / rate
            stop = (bounds[k + 1][3] + pad) / rate if k + 1 < len(bounds) else end
            phones.append((str(e[4]), start, max(start, min(stop, end))))
    words = [(int(e[1]) - 1, int(e[2]), (e[3] + pad) / rate) for e in events if e[0] == _WORD]
    return Synthesis(path, plain, phones, words, marks, end)


def _ipa_phones(label: str) -> list[str]:
    """DECtalk phones of one eSpeak NG phone label (IPA, stress marks ignored): as a whole if the IPA table
    knows it, else split into the longest pieces it knows ("ɑːɹ" -> aa r); an unknown letter is dropped,
    a label of none is a schwa."""
    from visemeface.errors import InputError as _Unknown
    from visemeface.postures.phonemes import to_dectalk

    rest = "".join(_IPA_NEAREST.get(ch, ch) for ch in label if ch not in "ˈˌ")
    out = []
    while rest:
        for n in range(len(rest), 0, -1):
            try:
                out.append(to_dectalk(rest[:n], "ipa"))
            except _Unknown:
                continue
            rest = rest[n:]
            break
        else:
            rest = rest[1:]
    return [p for p in out if p != "_"] or ["ax"]


def _event_words(syn: Synthesis) -> list[tuple[int, int, float]]:
    """eSpeak NG's word events merged where they share text (a number's spoken words): (offset, end, start s)."""
    merged = []
    for offset, length, start in syn.words:
        if merged and offset < merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], offset + length), merged[-1][2])
        else:
            merged.append((offset, offset + length, start))
    return merged


def events_utterance(syn: Synthesis, text: str):
    """The Utterance of the synthesised speech timed by eSpeak NG's own phone and word events.

    Phones as eSpeak NG spoke them (its IPA, mapped to DECtalk); words where its word events put them
    (labelled with the text's words when they pair one to one, else with the text they cover); emotion
    tags at the start of the word after them. InputError if the synthesis reported no phones.
    """
    import pandas as pd

    from visemeface.postures.phonemes import SILENCE
    from visemeface.speech.align import _words_of
    from visemeface.speech.transcripts.segments import Row, make_segments
    from visemeface.speech.utterance import Utterance

    spoken = [(label, s, e) for label, s, e in syn.phones if e > s]
    if not any(label for label, _, _ in spoken):
        raise InputError("the synthesiser reported no phones")
    rows = [Row(0.0, spoken[0][1], SILENCE, None)] if spoken[0][1] > 0 else []
    for label, s, e in spoken:
        pieces = _ipa_phones(label) if label else [SILENCE]
        step = (e - s) / len(pieces)
        rows += [Row(s + i * step, s + (i + 1) * step, sym, None) for i, sym in enumerate(pieces)]
    if rows[-1].end < syn.end:
        rows.append(Row(rows[-1].end, syn.end, SILENCE, None))
    segments = make_segments(rows, "synthesised speech", alphabet="dectalk")
    merged = _event_words(syn)
    text_words, tags = _words_of(text, None)
    starts = [w[2] for w in merged] + [syn.end]
    ends = []
    for k in range(len(merged)):                           # to the end of the word's last phone
        inside = [e for label, s, e in spoken if label and starts[k] <= s < starts[k + 1]]
        ends.append(max(inside) if inside else starts[k + 1])
    labels = text_words if len(text_words) == len(merged) else [syn.text[a:b].strip() for a, b, _ in merged]
    words = pd.DataFrame({"start": pd.Series(starts[:-1], dtype=float), "end": pd.Series(ends, dtype=float),
                          "word": pd.Series(labels, dtype=object)})
    key_times = []
    for offset in syn.marks[:len(tags)]:
        after = [w[2] for w in merged if w[0] >= offset]
        key_times.append(0.0 if offset == 0 else (after[0] if after else (ends[-1] if ends else 0.0)))
    keys = pd.DataFrame({"time": pd.Series(key_times, dtype=float),
                         "emotion": pd.Series([t[1] for t in tags[:len(key_times)]], dtype=object),
                         "weight": pd.Series([t[2] for t in tags[:len(key_times)]], dtype=float)})
    return Utterance(segments, words, keys, source_format="synthesised")


def stretched_utterance(syn: Synthesis, text: str, rate_wpm: float | None = None):
    """The duration model's Utterance of ``text`` (:func:`visemeface.speech.g2p.text_to_utterance`), its
    speech laid linearly over the synthesised speech's span and its end at the WAV's."""
    from dataclasses import replace

    from visemeface.postures.phonemes import SILENCE
    from visemeface.speech.audio import read_audio, speech_span
    from visemeface.speech.g2p import text_to_utterance

    u = text_to_utterance(text, rate_wpm=rate_wpm, warn=False)
    samples, rate = read_audio(syn.path)
    try:
        t0, t1 = speech_span(samples, rate, "synthesised speech")
    except InputError:
        t0, t1 = 0.0, syn.end
    seg = u.segments
    speech = seg[seg["phoneme"] != SILENCE]
    a, b = float(speech["start"].iloc[0]), float(speech["end"].iloc[-1])

    def move(t):
        return t0 + (t - a) * (t1 - t0) / max(b - a, 1e-9)

    seg = seg.copy()
    for col in ("start", "end"):
        seg[col] = seg[col].map(move).clip(0.0, syn.end)
    seg.loc[seg.index[0], "start"], seg.loc[seg.index[-1], "end"] = 0.0, max(syn.end, seg["end"].iloc[-1])
    seg = seg[seg["end"] > seg["start"]].reset_index(drop=True)
    words = u.words.copy()
    for col in ("start", "end"):
        words[col] = words[col].map(move).clip(0.0, syn.end)
    keys = u.emotion_keys.copy()
    keys["time"] = keys["time"].map(lambda t: 0.0 if t <= 0 else min(move(t), syn.end))
    return replace(u, segments=seg, words=words, emotion_keys=keys)


def _agrees(u, syn: Synthesis) -> bool:
    """True when the aligned words start, on the mean, within :data:`AGREE_S` of eSpeak NG's word events."""
    import numpy as np

    events = np.array([w[2] for w in _event_words(syn)])
    if not events.size or not len(u.words):
        return not events.size
    starts = u.words["start"].to_numpy(dtype=float)
    return float(np.mean(np.min(np.abs(starts[:, None] - events[None, :]), axis=1))) <= AGREE_S


def utterance_of(syn: Synthesis, text: str, rate_wpm: float | None = None):
    """(Utterance, how) of synthesised speech: ``"aligned"`` (its text aligned to the sound, agreeing with
    the synthesiser's word events), else ``"events"`` (:func:`events_utterance`), else ``"duration
    model"`` (:func:`stretched_utterance`). Never an error about the timing."""
    from visemeface.speech.align import utterance_from_audio

    try:
        u = utterance_from_audio(syn.path, text, where="synthesised speech", check_text=False)
        if _agrees(u, syn):
            return u, "aligned"
    except InputError:
        pass
    try:
        return events_utterance(syn, text), "events"
    except InputError:
        return stretched_utterance(syn, text, rate_wpm), "duration model"


def _child(text: str, out: str, voice: str, rate: int) -> int:
    """The child process: libespeak-ng synthesises ``text`` into ``out`` (see the module docstring)."""
    import ctypes

    import espeakng_loader
    import numpy as np
    import soundfile as sf

    import json

    class Id(ctypes.Union):
        _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p), ("string", ctypes.c_char * 8)]

    class Event(ctypes.Structure):                              # espeak_EVENT (speak_lib.h)
        _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint), ("text_position", ctypes.c_int),
                    ("length", ctypes.c_int), ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                    ("user_data", ctypes.c_void_p), ("id", Id)]

    lib = ctypes.CDLL(espeakng_loader.get_library_path())
    callback_t = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(Event))
    chunks, events = [], []

    def collect(wav, n, found):
        if n > 0:
            chunks.append(np.ctypeslib.as_array(wav, shape=(n,)).copy())
        i = 0
        while found and found[i].type != 0:                     # espeakEVENT_LIST_TERMINATED
            e = found[i]
            label = bytes(e.id.string).split(b"\0")[0].decode("utf-8", "replace") if e.type == _PHONEME else ""
            events.append([e.type, e.text_position, e.length, e.sample, label])
            i += 1
        return 0

    keep = callback_t(collect)
    lib.espeak_Initialize.restype = ctypes.c_int
    # AUDIO_OUTPUT_SYNCHRONOUS; espeakINITIALIZE_PHONEME_EVENTS | espeakINITIALIZE_PHONEME_IPA
    rate_hz = lib.espeak_Initialize(2, 0, espeakng_loader.get_data_path().encode(), 3)
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
    print(json.dumps({"rate": rate_hz, "pad": pad.size, "samples": int(samples.size), "events": events}))
    return 0


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])))

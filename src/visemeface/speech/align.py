"""Timed phones from a recording: forced alignment of known text, or phone recognition.

Both run offline with ``pocketsphinx`` and the US-English acoustic model,
pronouncing dictionary and phone language model inside its wheel.

Forced alignment (``text`` given)
---------------------------------
The words of the text (numbers spelled out, emotion tags kept as keys) are
looked up in pocketsphinx's dictionary; a word it lacks gets the project's
pronunciation (:func:`visemeface.speech.g2p.word_to_arpabet`: CMUdict, else
the letter-to-sound rules). The decoder searches the best path through the
words (optional silence between them, alternative pronunciations allowed),
then a second pass aligns that path's phones to the 10 ms frames. Phones come
back in ARPAbet without stress; a word pronounced as the project's dictionary
has it gets its stress back (``AH0`` is the schwa ``ax``).

Recognition (no text)
---------------------
An all-phone decode with the shipped phone language model (language weight
:data:`PHONE_LOOP_LW`): far less accurate (a phone error rate of 53 % on the
three GRID clips against their aligned phones; 2 of their 4 bilabial closures
found), but the open vowels and many closures are what the lips show.

Place assimilation
------------------
An /n/ right before a bilabial becomes /m/ ("ten boats" -> ``t eh m b ...``):
the lips close already, as speakers do.

Mismatch
--------
Text that does not match the audio still aligns (the decoder must put the
words somewhere) but with a poor acoustic score. How poor a right text scores
depends on the speaker and the recording (a quiet, noisy, reverberant or
unusual voice scores low on every path), so the score is judged against what
the audio itself supports: the free phone loop's phones (the recognition
below), aligned the same way, score each 10 ms frame too. A word's *margin*
is its forced alignment's score minus the loop's on the same frames, per
frame (log units of the decoder: positive where the text explains the sound
better than any free phone string found, very negative where another word
was said). A word whose margin is below :data:`DOUBTFUL_MARGIN` is doubtful
(its ``confidence``, a logistic of the margin, is below 0.5); a text with
more than :data:`DOUBTFUL_FRACTION` of its words doubtful, and more than
one (a one-word text: that word), is refused. On
the GRID clips, clean and degraded (quieter, noisy, telephone band, sped
up or slowed, reverberant), a right text has at most one word in six
doubtful and another GRID sentence -- even one sharing half its words --
at least two (docs/notes/alignment_margin.md; ``benchmarks/align_margin.py``
prints the margins). One wrong word in six passes, marked doubtful.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError
from visemeface.speech.transcripts.segments import Row, make_segments
from visemeface.speech.utterance import Segments, Utterance

__all__ = ["DOUBTFUL_FRACTION", "DOUBTFUL_MARGIN", "MODEL_RATE", "align", "phone_loop", "utterance_from_audio"]

#: Sample rate of the acoustic model (Hz).
MODEL_RATE = 16000
#: Frames per second of the decoder.
FRAME_RATE = 100
#: Margin (forced alignment's score minus the phone loop's, per 10 ms frame, decoder log units) below
#: which a word is doubtful. Set on the tuning cases of docs/notes/alignment_margin.md (swwp2s and
#: bbaf2n, clean, 30 dB quieter, white noise at 15 dB SNR, slowed to 0.85): any value in -30.6..-2.2
#: separated right from wrong texts there; this is the middle. The other cases were held out.
DOUBTFUL_MARGIN = -16.0
#: Fraction of doubtful words above which a text is refused: between 1 in 6 (the most a right GRID
#: sentence had, held-out cases included) and 2 in 6 (the fewest a wrong one had).
DOUBTFUL_FRACTION = 0.25
#: Margin units per unit of the confidence's logit, ``1 / (1 + exp(-(margin - DOUBTFUL_MARGIN) / s))``:
#: a margin of 0 (as good as the free loop) is 0.88, -40 (a word of another sentence) 0.05. A scale for
#: reading, not tuned.
CONFIDENCE_SCALE = 8.0
#: Language weight of the phone loop: 4 instead of pocketsphinx's 6.5 (chosen on the three GRID clips:
#: phone error rate 53 % instead of 58 %, 2 of 4 bilabial closures found instead of 0).
PHONE_LOOP_LW = 4.0
_SILENCE = {"<sil>", "<s>", "</s>", "SIL", "+SPN+", "+NSN+", "+BREATH+", "+COUGH+", "+NOISE+", "+UM+", "+UH+"}
_BILABIAL = {"P", "B", "M"}


def _model(*parts) -> str:
    from pocketsphinx import get_model_path

    return os.path.join(get_model_path(), *parts)


def _decoder(**options):
    from pocketsphinx import Decoder

    return Decoder(samprate=MODEL_RATE, lm=None, loglevel="FATAL", **options)


def model_pcm(samples: np.ndarray, rate: int, where=None) -> bytes:
    """16 kHz 16-bit PCM of a recording for the decoder, its peak scaled to 0.9 of full scale."""
    from visemeface.speech.audio import resample

    if rate < MODEL_RATE:
        warnings.warn(f"{where or 'audio'}: sampled at {rate} Hz, below the acoustic model's {MODEL_RATE} Hz "
                      "(telephone band?): timing is less accurate", stacklevel=3)
    x = resample(samples, rate, MODEL_RATE)
    peak = float(np.abs(x).max())
    x = x * (0.9 / peak) if peak > 0 else x
    return (np.clip(x, -1, 1) * 32767).astype("<i2").tobytes()


def _read(audio, where):
    """(samples, rate, name for messages) of a path or a ``(samples, rate)`` pair; speech checked."""
    from visemeface.speech.audio import read_audio, speech_span

    if isinstance(audio, (str, Path)):
        where = where if where is not None else audio
        samples, rate = read_audio(audio)
    else:
        samples, rate = np.asarray(audio[0], dtype=np.float64).ravel(), int(audio[1])
        if samples.size == 0 or rate <= 0 or not np.all(np.isfinite(samples)):
            raise InputError("audio holds no finite samples", where)
    speech_span(samples, rate, where)        # silence / steady noise -> InputError
    return samples, rate, where


def _words_of(text: str, where):
    """The words of a text (numbers spelled out) and its emotion tags as (word index, name, weight)."""
    from visemeface.speech.tokens import tokens

    words, tags = [], []
    for kind, value, _line in tokens(str(text).lstrip("\ufeff"), where):
        if kind == "word":
            words.append(value)
        elif kind == "emotion":
            tags.append((len(words), *value))
    return words, tags


def _dictionary_keys(decoder, words) -> list[str]:
    """The decoder's dictionary entry of each word, adding the project's pronunciation where it has none."""
    import re

    from visemeface.speech.g2p import cmu_pronunciations, word_to_arpabet

    keys = []
    for w in words:
        key = re.sub(r"[^a-z0-9']", "", w.lower().replace("’", "'")) or "x"
        if decoder.lookup_word(key) is None:
            known = cmu_pronunciations([key]).get(key)
            phones = [p.rstrip("012") for p in (known[0] if known else word_to_arpabet(w))]
            if not phones:
                raise InputError(f"no pronunciation for the word {w!r}")
            decoder.add_word(key, " ".join(phones), True)
        keys.append(key)
    return keys


#: Standard deviation (16-bit PCM steps, about -70 dB of full scale) of the seeded dither of a second
#: alignment try. pocketsphinx's phone-level pass sometimes finds no path through clean speech (the GRID
#: clip encoded as an MP3 by ffmpeg's defaults failed, its WAV aligned); a trace of noise lets it through,
#: boundaries within 10 ms of the WAV's (the last end 30 ms). Chosen by trying 3, 10 and 30 steps
#: (4/5, 5/5, 5/5 seeds aligned), not tuned further.
RETRY_DITHER = 10.0


def _dithered(pcm: bytes) -> bytes:
    x = np.frombuffer(pcm, dtype="<i2").astype(np.float64)
    x += np.random.default_rng(0).normal(0.0, RETRY_DITHER, x.size)
    return np.clip(np.round(x), -32768, 32767).astype("<i2").tobytes()


def _alignment(pcm: bytes, words, pronunciations=None, **options):
    """pocketsphinx's word and phone alignment of ``words`` (two passes), or None if it found none.

    ``pronunciations`` (key -> ARPAbet string) are added to the decoder's dictionary first and the
    words are taken as keys; ``options`` go to the decoder (beams).
    """
    decoder = _decoder(**options)
    if pronunciations is None:
        keys = _dictionary_keys(decoder, words)     # adds the words it lacks to this decoder's dictionary
    else:
        for key, phones in pronunciations.items():
            decoder.add_word(key, phones, True)
        keys = list(words)
    try:
        decoder.set_align_text(" ".join(keys))
        for second in (False, True):
            if second:
                decoder.set_alignment()
            decoder.start_utt()
            decoder.process_raw(pcm, full_utt=True)
            decoder.end_utt()
        alignment = decoder.get_alignment()
    except RuntimeError:
        return None
    return alignment if sum(w.name not in _SILENCE for w in alignment) == len(keys) else None


#: Beams of the last alignment try (pocketsphinx's defaults: beam 1e-48, word beam 7e-29, phone beam
#: 1e-48). Synthesised speech scores so far below the model's human voices that the default search
#: prunes every path through a long text (eSpeak NG's "the quick brown fox ..." three times: no
#: alignment, with these: all 27 words); 1e-120 lost the last word there. Not tuned further.
WIDE_BEAMS = {"beam": 1e-80, "wbeam": 1e-60, "pbeam": 1e-80}


def _alignment_tries(pcm: bytes, words, pronunciations=None):
    """:func:`_alignment` as it is, with a trace of noise (:data:`RETRY_DITHER`), then with wide beams
    (:data:`WIDE_BEAMS`); None if none found a path."""
    for audio, options in ((pcm, {}), (_dithered(pcm), {}), (pcm, WIDE_BEAMS)):
        alignment = _alignment(audio, words, pronunciations, **options)
        if alignment is not None:
            return alignment
    return None


def _force_align(pcm: bytes, words, where):
    """[(word, start, end, score, [(ARPAbet, start, end, score)])] of the words in the audio (seconds;
    scores in the decoder's log units, summed over the frames)."""
    alignment = _alignment_tries(pcm, words)
    if alignment is None:
        raise InputError("the text could not be aligned to the audio (does it match the recording?)", where)
    out = []
    for w in alignment:
        phones = [(p.name, p.start / FRAME_RATE, (p.start + p.duration) / FRAME_RATE, p.score) for p in w]
        out.append((w.name.split("(")[0], w.start / FRAME_RATE, (w.start + w.duration) / FRAME_RATE, w.score,
                    phones))
    return out


def _frame_scores(aligned, frames: int) -> np.ndarray:
    """Acoustic score of each 10 ms frame under an alignment (each phone's score spread evenly over its
    frames); NaN on frames it does not cover."""
    out = np.full(frames, np.nan)
    for _name, _start, _end, _score, phones in aligned:
        for _p, start, end, score in phones:
            a, b = round(start * FRAME_RATE), min(round(end * FRAME_RATE), frames)
            if b > a:
                out[a:b] = score / (round(end * FRAME_RATE) - a)
    return out


def _loop_reference(pcm: bytes) -> np.ndarray | None:
    """Per-frame acoustic score of what the audio itself supports: the free phone loop's phones
    (:func:`phone_loop`), each run between its silences taken as one word, aligned like a text.
    None when the loop recognised nothing or its phones found no path."""
    runs, run = [], []
    for label, _start, _end in phone_loop(pcm):
        if label in _SILENCE:
            runs, run = (runs + [run] if run else runs), []
        else:
            run.append(label)
    runs += [run] if run else []
    if not runs:
        return None
    keys = [f"vfloop{i}" for i in range(len(runs))]
    alignment = _alignment_tries(pcm, keys, {k: " ".join(r) for k, r in zip(keys, runs)})
    if alignment is None:
        return None
    aligned = [(w.name, 0, 0, w.score, [(p.name, p.start / FRAME_RATE, (p.start + p.duration) / FRAME_RATE,
                                         p.score) for p in w]) for w in alignment]
    return _frame_scores(aligned, len(pcm) // (2 * MODEL_RATE // FRAME_RATE) + 1)


def _align_and_reference(pcm: bytes, words, where, reference: bool = True):
    """(:func:`_force_align`, :func:`_loop_reference` or None) of one recording: one decode job."""
    aligned = _force_align(pcm, words, where)
    return aligned, (_loop_reference(pcm) if reference else None)


#: Recordings longer than this (s) are decoded in a child process. pocketsphinx holds the GIL for a whole
#: decode (about 4 % of the audio's length), so Ctrl-C could not end the run until it finished; a child
#: can be ended at once. Shorter ones decode here (a child costs about 0.5 s to start).
CHILD_DECODE_S = 20.0


def _decode(fn, pcm: bytes, *args):
    """``fn(pcm, *args)``; in a child process for long recordings, ended at once on Ctrl-C or SIGTERM.

    The child is a fresh interpreter (never a fork: a forked numba thread pool can hang) in its own
    session, so a terminal's Ctrl-C reaches only this process, which kills it; it also dies with this
    process (SIGKILL included) instead of decoding on and printing a broken pipe later.
    """
    if len(pcm) < CHILD_DECODE_S * MODEL_RATE * 2:
        return fn(pcm, *args)
    import pickle
    import subprocess
    import sys

    package_root = str(Path(__file__).resolve().parents[2])     # importable however this process found it
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")])))
    proc = subprocess.Popen([sys.executable, "-c", "from visemeface.speech.align import _child; _child()"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, env=env)
    try:
        out, err = proc.communicate(pickle.dumps((os.getpid(), fn.__name__, pcm, args)))
    except BaseException:
        proc.kill()
        proc.wait()
        raise
    if proc.returncode != 0 or not out:
        raise RuntimeError(f"the alignment process failed (exit {proc.returncode}): "
                           f"{err.decode(errors='replace').strip()[-300:]}")
    ok, value = pickle.loads(out)
    if not ok:
        raise value
    return value


def _child() -> None:
    """The child of :func:`_decode`: reads (parent pid, function name, pcm, args), writes (ok, result)."""
    import ctypes
    import pickle
    import signal
    import sys

    parent, name, pcm, args = pickle.loads(sys.stdin.buffer.read())
    try:                                        # die with the parent (Linux); elsewhere it finishes alone
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:
        return
    try:
        result = (True, {"phone_loop": phone_loop, "_align_and_reference": _align_and_reference}[name](pcm, *args))
    except InputError as exc:
        result = (False, exc)
    sys.stdout.buffer.write(pickle.dumps(result))


def phone_loop(pcm: bytes) -> list[tuple[str, float, float]]:
    """Recognised phones ``(ARPAbet or silence label, start, end)`` (s) of 16 kHz PCM, no text."""
    decoder = _decoder(allphone=_model("en-us", "en-us-phone.lm.bin"), lw=PHONE_LOOP_LW)
    decoder.start_utt()
    decoder.process_raw(pcm, full_utt=True)
    decoder.end_utt()
    return [(s.word, s.start_frame / FRAME_RATE, (s.end_frame + 1) / FRAME_RATE) for s in decoder.seg()]


def _stressed(word: str, phones: list[str], known: dict) -> list[str]:
    """The aligned phones with the stress digits of the CMUdict pronunciation they are, if any."""
    for pron in known.get(word.lower(), []):
        if [p.rstrip("012") for p in pron] == phones:
            return pron
    return phones


def assimilate(labels: list[str]) -> list[str]:
    """ARPAbet labels with /n/ before a bilabial made /m/ (module docstring)."""
    out = list(labels)
    for i in range(len(out) - 1):
        if out[i] == "N" and out[i + 1].rstrip("012") in _BILABIAL:
            out[i] = "M"
    return out


def _segments(timed: list[tuple[str, float, float]], total: float, where) -> Segments:
    """Segments of ``(ARPAbet label, start, end)``: silences mapped, /n/ assimilated, ending at ``total``."""
    labels = assimilate(["sil" if lab in _SILENCE else lab for lab, _, _ in timed])
    rows = [Row(s, min(e, total), lab, None) for lab, (_, s, e) in zip(labels, timed) if s < total]
    if not rows or rows[-1].end < total - 1e-9:
        rows.append(Row(rows[-1].end if rows else 0.0, total, "sil", None))
    return make_segments(rows, where, alphabet="arpabet")


def word_margins(aligned, reference: np.ndarray | None) -> np.ndarray:
    """Margin (module docstring) of each word of a forced alignment, NaN without a reference."""
    words = [w for w in aligned if w[0] not in _SILENCE]
    if reference is None:
        return np.full(len(words), np.nan)
    text = _frame_scores(words, reference.size)
    out = []
    for _name, start, end, _score, _phones in words:
        a, b = round(start * FRAME_RATE), min(round(end * FRAME_RATE), reference.size)
        both = np.isfinite(text[a:b]) & np.isfinite(reference[a:b])
        out.append(float(np.mean(text[a:b][both] - reference[a:b][both])) if both.any() else np.nan)
    return np.asarray(out)


def confidence(margins) -> np.ndarray:
    """Word confidence in 0..1 from margins (:data:`CONFIDENCE_SCALE`); below 0.5 = doubtful; NaN stays NaN."""
    return 1.0 / (1.0 + np.exp(-(np.asarray(margins, dtype=float) - DOUBTFUL_MARGIN) / CONFIDENCE_SCALE))


def _check_match(words: list[str], margins: np.ndarray, where) -> None:
    """Refuse a text with more than :data:`DOUBTFUL_FRACTION` of its words doubtful; one doubtful word
    passes unless it is the only one (formant-synthesised "ah ee" at 8 kHz: the decoder stretches "ah"
    over the pause before "ee", margin -22)."""
    if not np.isfinite(margins).any():
        warnings.warn(f"{where or 'audio'}: no free phone decoding to judge the text against; "
                      "taken as it is", stacklevel=3)
        return
    doubtful = [w for w, m in zip(words, margins) if m < DOUBTFUL_MARGIN]
    if len(doubtful) > max(DOUBTFUL_FRACTION * len(words), min(1, len(words) - 1)):
        shown = ", ".join(repr(w) for w in doubtful[:6]) + (", ..." if len(doubtful) > 6 else "")
        raise InputError(f"the text does not match the audio: {len(doubtful)} of its {len(words)} words "
                         f"are not heard there ({shown}); check the words (or give none: the phones are "
                         "then recognised)", where)


def utterance_from_audio(audio, text: str | None = None, *, where=None, check_text: bool = True,
                         text_where=None) -> Utterance:
    """Timed phones (and words, emotion keys) of a recording.

    Parameters
    ----------
    audio : path or (ndarray, int)
        A sound or video file (:func:`visemeface.speech.audio.read_audio`), or mono samples and their rate.
    text : str, optional
        What is said: forced alignment (accurate). None: phone recognition.
    where : str, optional
        Named in error messages (default: the audio path).
    check_text : bool
        Refuse text that does not match the audio (module docstring: too many doubtful words) and
        give each word a ``confidence``; off for audio known to say the text (synthesised speech,
        which scores poorly on a model of human voices): no judgement, confidence NaN.
    text_where : str or Path, optional
        The file the text came from, named (with the line) in errors about the text itself (a bad
        emotion tag); None: the errors name no file (never the audio's "line 1").

    Returns
    -------
    Utterance
        Segments from 0 to the end of the recording (``source_format`` ``"aligned"`` or
        ``"recognised"``); with text, the words' times, ``margin`` and ``confidence`` (module
        docstring) and the text's emotion tags as keys.

    Raises
    ------
    InputError
        Unreadable, silent or non-finite audio; no words; text that does not match the audio.
    """
    samples, rate, where = _read(audio, where)
    total = samples.size / rate
    pcm = model_pcm(samples, rate, where)
    if text is None:
        seg = _segments(_decode(phone_loop, pcm), total, where)
        if not (seg["phoneme"] != "_").any():
            raise InputError("no phones recognised in the audio", where)
        return Utterance(seg, source_format="recognised")
    words, tags = _words_of(text, text_where)
    if not words:
        raise InputError("no words in the text to align", text_where or where)
    aligned, reference = _decode(_align_and_reference, pcm, words, where, check_text)
    margins = word_margins(aligned, reference)
    if check_text:
        _check_match(words, margins, where)
    from visemeface.speech.g2p import cmu_pronunciations

    known = cmu_pronunciations(words)
    timed, word_rows = [], []
    spoken = iter(words)
    for name, start, end, _score, phones in aligned:
        if name in _SILENCE:
            timed.append(("sil", start, end))
            continue
        word = next(spoken)
        labels = _stressed(word, [p[0] for p in phones], known)
        timed += [(lab, s, e) for lab, (_, s, e, _) in zip(labels, phones)]
        word_rows.append((start, min(end, total), word))
    seg = _segments(timed, total, where)
    word_table = pd.DataFrame({"start": [r[0] for r in word_rows], "end": [r[1] for r in word_rows],
                               "word": pd.Series([r[2] for r in word_rows], dtype=object),
                               "margin": margins, "confidence": confidence(margins)})
    key_times = [0.0 if k == 0 else (word_rows[k][0] if k < len(word_rows) else word_rows[-1][1])
                 for k, _, _ in tags]
    keys = pd.DataFrame({"time": pd.Series(key_times, dtype=float),
                         "emotion": pd.Series([t[1] for t in tags], dtype=object),
                         "weight": pd.Series([t[2] for t in tags], dtype=float)})
    return Utterance(seg, word_table, keys, source_format="aligned")


def align(audio, text: str | None = None) -> Segments:
    """Timed DECtalk phones of a recording: forced alignment of ``text``, or recognition without it.

    See :func:`utterance_from_audio` (this returns its Segments).

    Examples
    --------
    >>> seg = align("swwp2s.mpg", "set white with p two soon")   # doctest: +SKIP
    """
    return utterance_from_audio(audio, text).segments

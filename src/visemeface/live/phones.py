"""Phones as they are spoken: pocketsphinx's all-phone decoder fed block by block.

The decoder and its settings are offline recognition's (:func:`visemeface.speech.align.phone_loop`:
the US-English model, the phone language model, language weight ``PHONE_LOOP_LW``); here it is fed
10 ms frames as they arrive and asked after each block for its best segmentation so far. The newest
phones are provisional (the best path may still change); the decoder's features also need a few frames
past the last one decoded, so its frontier trails the audio by about 50 ms (measured on the GRID clips:
5 frames). Which phone a frame gets agrees with the finished decode for 72 % of frames 100 ms behind
the audio and 86 % 200 ms behind (swwp2s), the trade behind ``--latency``.

Long sessions: an utterance is ended and a new one started at a pause once it is longer than
:data:`UTTERANCE_S` (and forced at :data:`FORCE_S`), so the backtrace after each block stays short.
"""

from __future__ import annotations

import numpy as np

from visemeface.speech.align import FRAME_RATE, MODEL_RATE, PHONE_LOOP_LW, _decoder, _model

#: Samples of one decoder frame (10 ms at 16 kHz).
FRAME = MODEL_RATE // FRAME_RATE
#: An utterance longer than this (s) is ended at the next pause of at least :data:`PAUSE_S`.
UTTERANCE_S = 10.0
#: ... or ended regardless at this length (s).
FORCE_S = 30.0
#: Shortest silence (s) an utterance is ended in.
PAUSE_S = 0.3
#: Every this many seconds the decoder's cepstral mean is re-estimated from the utterance so far.
#: pocketsphinx's live mean keeps the model's initial value for the first 8 s (it moves at 800 frames or
#: at an utterance's end), far from a given microphone's; offline recognition normalises over the whole
#: recording. Re-estimating it raised the streamed jawOpen's correlation with the offline run's on swwp2s
#: from 0.69 to 0.81 at a latency of 0.12 s (0.78 to 0.93 at 0.3 s); 0.1 and 0.5 s gave the same.
CMN_EVERY_S = 0.25
_SILENT = {"SIL", "<sil>", "<s>", "</s>"}


class LivePhones:
    """The phones of a 16 kHz stream: :meth:`feed` samples, :meth:`refresh`, then :attr:`phones`
    (``(label, start, end)``, seconds from the start of the stream, ARPAbet or silence labels) and
    :attr:`frontier` (s)."""

    def __init__(self):
        self.decoder = _decoder(allphone=_model("en-us", "en-us-phone.lm.bin"), lw=PHONE_LOOP_LW)
        self.decoder.start_utt()
        self.finished: list[tuple[str, float, float]] = []   # phones of ended utterances
        self.current: list[tuple[str, float, float]] = []
        self._ends: list[float] = []                          # ends of the finished phones (sorted)
        self.offset = 0            # frames before the current utterance
        self.frames = 0            # frames fed into the current utterance
        self._rest = np.zeros(0, dtype=np.int16)
        self.stale = False

    @property
    def samples(self) -> int:
        """Samples fed so far (whole frames; a partial frame waits for the next block)."""
        return (self.offset + self.frames) * FRAME

    @property
    def phones(self) -> list[tuple[str, float, float]]:
        return self.finished + self.current

    def since(self, t: float) -> list[tuple[str, float, float]]:
        """The phones ending after ``t`` (s)."""
        import bisect

        i = bisect.bisect_right(self._ends, t)
        return self.finished[i:] + [p for p in self.current if p[2] > t]

    @property
    def frontier(self) -> float:
        """End (s) of the newest decoded phone."""
        last = self.current or self.finished
        return last[-1][2] if last else self.offset / FRAME_RATE

    def _segments(self) -> list[tuple[str, float, float]]:
        off = self.offset
        return [(s.word, (off + s.start_frame) / FRAME_RATE, (off + s.end_frame + 1) / FRAME_RATE)
                for s in (self.decoder.seg() or [])]

    def feed(self, x: np.ndarray) -> None:
        """Samples in [-1, 1] at 16 kHz; decoded in whole frames."""
        pcm = np.concatenate([self._rest, (np.clip(np.asarray(x), -1.0, 1.0) * 32767).astype(np.int16)])
        n = pcm.size // FRAME * FRAME
        self._rest = pcm[n:]
        if n == 0:
            return
        self.decoder.process_raw(pcm[:n].astype("<i2").tobytes(), False, False)
        before = self.frames
        self.frames += n // FRAME
        self.stale = True
        every = int(CMN_EVERY_S * FRAME_RATE)
        if self.frames // every > before // every:
            self.decoder.get_cmn(True)
            length = self.frames / FRAME_RATE
            if length > UTTERANCE_S:
                self.refresh()
                last = self.current[-1] if self.current else None
                if length > FORCE_S or (last and last[0] in _SILENT and last[2] - last[1] >= PAUSE_S):
                    self._restart()

    def refresh(self) -> None:
        """Ask the decoder for its best segmentation so far (:attr:`phones` and :attr:`frontier` are the
        last one asked for: a backtrace costs time, so it is made only when a frame is due)."""
        if self.stale:
            self.current = self._segments()
            self.stale = False

    def _end(self) -> None:
        self.decoder.end_utt()
        done = self._segments()
        end = (self.offset + self.frames) / FRAME_RATE      # the decoder's last frames may be left out
        if done and done[-1][2] < end:
            done[-1] = (done[-1][0], done[-1][1], end)
        elif not done and self.frames:
            done = [("SIL", self.offset / FRAME_RATE, end)]
        self.finished += done
        self._ends += [e for _, _, e in done]
        self.current = []
        self.stale = False
        self.offset += self.frames
        self.frames = 0

    def _restart(self) -> None:
        self._end()
        self.decoder.start_utt()

    def finish(self) -> None:
        """End the stream: the last utterance's phones become final (no :meth:`feed` after this)."""
        self._end()

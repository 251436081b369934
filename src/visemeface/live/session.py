"""The live loop: audio blocks -> phones -> frames -> senders, with a level meter and a recording.

For each block of audio: resample to 16 kHz, feed the decoder (:class:`~visemeface.live.phones.LivePhones`)
10 ms at a time, and whenever a frame is due make it (:class:`~visemeface.live.mouth.LiveMouth`) and send
it to every sender at once. So what is sent depends only on the audio, not on how it was cut into blocks
or how fast it came, as long as the machine keeps up. Audio that comes in bursts (a pipe's writer: ffmpeg
``-re`` writes its first half second at once, then 26 ms packets) or faster than real time (``cat``) is
all taken, every frame made. When the machine does not keep up -- the next block is already waiting and
the loop has been taking longer than the audio lasts (:data:`SLOWER`, a running mean over about
:data:`COST_BLOCKS` blocks) -- the decoder takes the waiting audio (up to :data:`MAX_DRAIN_S`) without
making frames, then the frames due are made at once and only the newest is retargeted and sent (the others
are recorded): a slow machine sends fewer frames rather than later ones.
When the stream ends the decoder finishes and the frames up to the end of the audio are sent too. What
was sent is kept (each frame's rig activations, and the decoder's final phones) so that the offline
outputs can be written from it afterwards (:func:`record`): the same frames the clients got.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from visemeface.errors import InputError
from visemeface.live.audio import Resampler
from visemeface.live.mouth import WINDOW_S
from visemeface.live.phones import LivePhones
from visemeface.speech.align import MODEL_RATE

#: Samples (16 kHz) the decoder takes between two chances to make a frame: 10 ms, its frame, so what is
#: sent does not depend on how the input was cut into blocks.
STEP = 160
#: Most audio (s) taken without making a frame when the reader has fallen behind.
MAX_DRAIN_S = 0.1
#: The loop has fallen behind when taking a block costs more wall time than the block's audio lasts
#: (this ratio, a running mean) while the next block is already waiting: a waiting block alone is a
#: burst of the writer's, which the loop takes at several times real time.
SLOWER = 1.0
#: Blocks the running mean of the loop's cost spans (its weight 1/COST_BLOCKS per block).
COST_BLOCKS = 10
#: Seconds between two redraws of the terminal's meter.
METER_EVERY_S = 0.066
#: Level (dB re full scale) at the meter's left end.
METER_FLOOR_DB = -60.0


def level_db(x: np.ndarray) -> float:
    """RMS level (dB re full scale) of a block, -120 for silence."""
    if x.size == 0:
        return -120.0
    rms = float(np.sqrt(np.mean(np.square(x))))
    return 20.0 * math.log10(max(rms, 1e-6))


class Meter:
    """One terminal line, redrawn in place: stream time, level bar, dB and the current viseme."""

    def __init__(self, stream=None, width: int = 24):
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.last = 0.0
        self.drawn = False

    def show(self, t: float, level: float, phone: str, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self.last < METER_EVERY_S:
            return
        self.last = now
        fill = int(round(self.width * min(1.0, max(0.0, (level - METER_FLOOR_DB) / -METER_FLOOR_DB))))
        bar = "#" * fill + "-" * (self.width - fill)
        self.stream.write(f"\r{t:7.2f} s [{bar}] {max(level, -99):4.0f} dB  {phone:<3}\033[K")
        self.stream.flush()
        self.drawn = True

    def clear(self) -> None:
        if self.drawn:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self.drawn = False


@dataclass
class Session:
    """What a live run did: the frames sent (times, rig activations, phones), the decoder's phones at the
    end, the stream's length, and how long it took (wall and CPU seconds)."""

    fps: float
    times: list = field(default_factory=list)
    activations: list = field(default_factory=list)
    phones_shown: list = field(default_factory=list)
    phones: list = field(default_factory=list)
    sent: int = 0
    skipped: int = 0
    behind: int = 0
    audio_s: float = 0.0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    finished: bool = False

    @property
    def n_frames(self) -> int:
        return len(self.times)


def run(source, mouth, senders, meter: Meter | None = None, duration: float | None = None,
        keep: bool = True, clock=time.monotonic) -> Session:
    """Stream ``source`` through ``mouth`` into ``senders`` until it ends, ``duration`` (s) of it has
    passed, or Ctrl-C (KeyboardInterrupt, raised on with the session so far in ``exc.session``).

    ``keep``: keep every frame's activations for a recording. ``clock``: the wall clock (seconds) the
    loop's cost is measured on, whether it keeps up with its audio; a test gives its own.
    """
    session = Session(fps=mouth.fps)
    decoder = LivePhones()
    resample = None
    wall0, cpu0 = clock(), time.process_time()
    level = -120.0

    def send(frames):
        for f in frames:
            if f.weights is not None:
                for s in senders:
                    s.send(f)
                session.sent += 1
            else:
                session.skipped += 1
            if keep:
                session.times.append(f.time)
                session.activations.append(f.activations)
                session.phones_shown.append(f.phone)
        if meter is not None and frames:
            meter.show(frames[-1].time, level, frames[-1].phone)

    def make(level, final=False):
        decoder.refresh()
        window = decoder.since(mouth.next / mouth.fps - WINDOW_S)
        send(mouth.advance(window, decoder.frontier, session.audio_s, final=final, level=level,
                           newest_only=not final and mouth.last_due(session.audio_s) > mouth.next))

    def take(block, on_time):
        """Feed one block 10 ms at a time, making each frame as it falls due when ``on_time``."""
        nonlocal resample, level
        if resample is None:
            resample = Resampler(source.rate, MODEL_RATE)
        level = level_db(block)
        y = resample(block)
        for i in range(0, max(y.size, 1), STEP):
            decoder.feed(y[i:i + STEP])
            session.audio_s = decoder.samples / MODEL_RATE
            if on_time and mouth.due(session.audio_s):
                make(level)

    cost = 0.0                                      # wall seconds the loop takes per second of audio

    try:
        blocks = iter(source.blocks())
        for block in blocks:
            behind = cost > SLOWER and source.pending()
            t0, heard = clock(), session.audio_s
            take(block, not behind)
            if session.audio_s > heard:
                ratio = (clock() - t0) / (session.audio_s - heard)
                cost += (ratio - cost) / COST_BLOCKS
            if behind:                              # take what is waiting (up to MAX_DRAIN_S), then the newest
                session.behind += 1
                start = session.audio_s
                while source.pending() and session.audio_s - start < MAX_DRAIN_S:
                    more = next(blocks, None)
                    if more is None:
                        break
                    take(more, False)
                if mouth.due(session.audio_s):
                    make(level)
            if duration is not None and session.audio_s >= duration:
                break
        if not session.audio_s:
            raise InputError("the stream holds no audio", source.what)
        decoder.finish()
        make(level, final=True)
        session.finished = True
    except KeyboardInterrupt as exc:
        exc.session = session
        raise
    finally:
        session.phones = decoder.phones
        session.wall_s = clock() - wall0
        session.cpu_s = time.process_time() - cpu0
        if meter is not None:
            meter.clear()
        source.close()
    return session


def recorded_track(session: Session, rig):
    """The frames sent, as an ActivationTrack (the rig's columns)."""
    from visemeface.track import make_track

    A = np.array(session.activations).reshape(len(session.activations), len(rig.names))
    return make_track(np.arange(len(A)) / session.fps, A, rig.names, session.fps)


def recorded_utterance(session: Session):
    """The decoder's final phones as an Utterance (DECtalk), lasting as long as the frames sent."""
    from visemeface.speech.align import _segments
    from visemeface.speech.utterance import Utterance

    total = max(session.n_frames / session.fps, session.phones[-1][2] if session.phones else 0.0, 1.0 / session.fps)
    timed = session.phones or [("SIL", 0.0, total)]
    return Utterance(_segments(timed, total, "the live stream"), source_format="recognised")


def record(session: Session, rig, sinks, interp: str, source: str, show_progress: bool = False):
    """Write the offline outputs ``sinks`` of what was sent (:func:`visemeface.pipeline.run` on the
    recorded track: every output the offline commands write, all or none); returns its RunStats."""
    from visemeface import pipeline
    from visemeface.motion import KinematicMotion

    track = recorded_track(session, rig)
    utterance = recorded_utterance(session)
    return pipeline.run(KinematicMotion(rig, track), sinks, None,
                        info=dict(rig=rig, track=track, end_time=session.n_frames / session.fps,
                                  extra={"utterance": utterance, "interp": interp, "source": source}),
                        show_progress=show_progress)


def stderr_is_terminal() -> bool:
    try:
        return os.isatty(sys.stderr.fileno())
    except (OSError, ValueError, AttributeError):
        return False

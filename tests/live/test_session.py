"""The live loop: audio that comes in bursts or faster than real time is taken whole, every frame sent;
only a loop slower than its audio sends fewer frames (the newest) rather than later ones."""

import pytest

from visemeface.live import session as live
from visemeface.live.audio import Source
from visemeface.live.mouth import LiveMouth
from visemeface.resources import transcripts_path
from visemeface.speech.audio import read_audio

RECORDING = "set_white_with_p_two_soon.wav"


class Ahead(Source):
    """A recording handed over in blocks of ``block_s``, the next one always waiting: a pipe whose writer
    is ahead of the reader (ffmpeg -re's opening burst, its 26 ms packets, or ``cat``)."""

    def __init__(self, block_s: float):
        self.samples, self.rate = read_audio(transcripts_path(RECORDING))
        self.what, self.n = RECORDING, max(1, int(block_s * self.rate))

    def blocks(self):
        for i in range(0, self.samples.size, self.n):
            yield self.samples[i:i + self.n]

    def pending(self) -> bool:
        return True


class Clock:
    """The loop's wall clock, advanced only by what the test says things cost: the loop is then judged by
    its rule (does it keep up with the audio it holds?), not by how busy the machine running the test is."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class Client:
    """A sender that keeps the frames it gets and takes ``delay`` seconds of ``clock`` over each."""

    def __init__(self, clock: Clock, delay: float = 0.0):
        self.frames, self.clock, self.delay = [], clock, delay

    def send(self, frame) -> None:
        self.frames.append(frame.index)
        self.clock.now += self.delay


def stream(rig, block_s: float, delay: float):
    clock = Clock()
    client = Client(clock, delay)
    session = live.run(Ahead(block_s), LiveMouth(rig, ["arkit"], fps=30.0, latency=0.12), [client],
                       clock=clock)
    return session, client


@pytest.mark.parametrize("delay", [0.0, 0.02])     # 0 or 0.6 s a second of audio at 30 fps: it keeps up
@pytest.mark.parametrize("block_s", [0.01, 0.05, 0.1, 0.5])
def test_audio_ahead_of_the_reader_is_taken_whole_and_every_frame_sent(rig, block_s, delay):
    session, client = stream(rig, block_s, delay)
    assert session.skipped == 0 and session.behind == 0
    assert client.frames == list(range(session.n_frames)) and session.n_frames >= 89


def test_a_loop_slower_than_its_audio_sends_the_newest_frames(rig):
    session, client = stream(rig, 0.01, 0.05)    # 50 ms a frame: frames fall due every 33 ms
    assert session.behind > 0 and session.skipped > 0
    assert client.frames == sorted(client.frames) and len(client.frames) + session.skipped == session.n_frames
    assert len(client.frames) < 0.8 * session.n_frames


def test_the_loop_measures_its_cost_on_the_real_clock_by_default(rig):
    real = Client(Clock())
    session = live.run(Ahead(0.5), LiveMouth(rig, ["arkit"], fps=30.0, latency=0.12), [real])
    assert session.finished and 0.0 < session.wall_s < 600.0 and real.frames[0] == 0

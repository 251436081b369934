"""An interrupt while ffmpeg starts leaves no file: the run waits for the start, then ends ffmpeg and removes
its temporary (before, ffmpeg, started unseen, wrote the temporary after the run had removed it)."""

import os
import signal
import subprocess
import time

import numpy as np
import pytest

from visemeface.export.video import VideoWriter
from visemeface.runtime import signals_deferred


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_in_a_deferred_body_comes_when_it_ends(sig):
    def stop(signum, frame):
        raise KeyboardInterrupt

    kept = signal.signal(signal.SIGTERM, stop)
    try:
        went_on = False
        with pytest.raises(KeyboardInterrupt):
            with signals_deferred():
                os.kill(os.getpid(), sig)
                time.sleep(0.05)                   # a handler would have run by now
                went_on = True
        assert went_on
    finally:
        signal.signal(signal.SIGTERM, kept)


def test_ctrl_c_as_ffmpeg_starts_leaves_no_file(tmp_path, monkeypatch):
    import imageio_ffmpeg._io as io

    started = []
    real = subprocess.Popen

    def popen_then_ctrl_c(*args, **kwargs):      # Ctrl-C arrives the moment ffmpeg exists
        p = real(*args, **kwargs)
        started.append(p)
        os.kill(os.getpid(), signal.SIGINT)
        return p

    monkeypatch.setattr(io.subprocess, "Popen", popen_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(tmp_path / "out.mp4", (32, 32), fps=30) as video:
            video.write(np.zeros((32, 32, 3), np.uint8))
    assert started and started[0].poll() is not None         # ffmpeg was ended, not left running
    time.sleep(0.5)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_writer_stopped_part_way_kills_ffmpeg_instead_of_waiting_for_its_file(tmp_path, monkeypatch):
    """The file of a stopped writer is thrown away: ffmpeg is killed, not left to encode the frames it holds
    (under load that took seconds after Ctrl-C, past the prompt end the signal tests ask for)."""
    import imageio_ffmpeg._io as io

    started = []
    real = subprocess.Popen

    def popen(*args, **kwargs):
        started.append(real(*args, **kwargs))
        return started[-1]

    monkeypatch.setattr(io.subprocess, "Popen", popen)
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(tmp_path / "out.mp4", (256, 256), fps=30) as video:
            for i in range(30):
                video.write(np.full((256, 256, 3), i * 8, np.uint8))
            raise KeyboardInterrupt
    assert started[0].returncode == -signal.SIGKILL
    assert sorted(p.name for p in tmp_path.iterdir()) == []

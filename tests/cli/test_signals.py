"""Real processes and real signals: simulate never hangs, Ctrl-C ends it promptly, kills leave nothing stale.

These run ``visemeface simulate`` as a separate process on a coarse face (800 vertices, 16 frames).
"""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from visemeface.export.pc2 import read_pc2

pytestmark = pytest.mark.slow

SIM = ["simulate", "part", "--resolution", "800", "--fps", "20", "--size", "32", "--msaa", "0", "-q"]


def _start(work, tag, *more):
    argv = [sys.executable, "-m", "visemeface", *SIM, "-o", f"{tag}.mp4", "--frames", f"{tag}_fr",
            "--pc2", f"{tag}.pc2", *more]
    return subprocess.Popen(argv, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for_a_frame(work, tag, proc, timeout=120):
    """Wait until the run has finished a frame (its checkpoint records it): the simulation is running."""
    vertices = work / f"{tag}.mp4.checkpoint" / "vertices.f32"
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if proc.poll() is not None:
            raise AssertionError(f"finished early: {proc.communicate()}")
        if vertices.exists() and vertices.stat().st_size > 0:
            return
        time.sleep(0.05)
    raise AssertionError("no frame finished in time")


def _same_as_an_uninterrupted_run(folder, tag):
    """The resumed run's outputs are the very bytes of a run never interrupted (the simulation restarts exactly)."""
    ref = folder.parent / f"{folder.name}_reference"
    ref.mkdir()
    proc = _start(ref, tag)
    assert proc.wait(timeout=240) == 0, proc.communicate()[1]
    got, want = _files(folder), _files(ref)
    assert sorted(got) == sorted(want)
    for name in want:
        assert got[name] == want[name], f"{name} differs from the uninterrupted run"


def test_simulate_with_every_output_finishes_every_time(tmp_path):
    """Starting the video encoder after numba's thread pool once hung 1 run in 3 (TBB's fork handler)."""
    for k in range(5):
        proc = _start(tmp_path, f"run{k}")
        try:
            out, err = proc.communicate(timeout=240)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise AssertionError(f"run {k} hung")
        assert proc.returncode == 0, err
    a = read_pc2(tmp_path / "run0.pc2")[0]
    for k in range(1, 5):
        np.testing.assert_array_equal(a, read_pc2(tmp_path / f"run{k}.pc2")[0])   # deterministic too


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupt_ends_simulate_promptly_and_resume_completes(tmp_path, sig, prompt_s):
    proc = _start(tmp_path, "cut")
    _wait_for_a_frame(tmp_path, "cut", proc)
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError("did not end within 10 s of the signal")
    assert time.monotonic() - t0 < prompt_s, f"{time.monotonic() - t0:.1f} s to stop"
    assert proc.returncode == 130 and "interrupted" in err
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["cut.mp4.checkpoint", "cut_fr.partial"]        # no output under its final name, no temporary
    proc = _start(tmp_path, "cut", "--resume")
    _, err = proc.communicate(timeout=240)
    assert proc.returncode == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.mp4", "cut.mp4.json", "cut.pc2", "cut.saliva.csv",
                                                          "cut_fr", "cut_fr.json"]
    _same_as_an_uninterrupted_run(tmp_path, "cut")


def test_after_a_kill_the_next_run_resumes_and_removes_what_the_killed_one_left(tmp_path):
    proc = _start(tmp_path, "k")
    _wait_for_a_frame(tmp_path, "k", proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    stale = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert stale, "a killed run leaves its temporaries (it cannot remove them itself)"
    proc = _start(tmp_path, "k", "--resume")
    _, err = proc.communicate(timeout=240)
    assert proc.returncode == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["k.mp4", "k.mp4.json", "k.pc2", "k.saliva.csv",
                                                          "k_fr", "k_fr.json"]
    _same_as_an_uninterrupted_run(tmp_path, "k")
    assert not any(p.name.startswith(".") for p in (tmp_path / "k_fr").iterdir() if p.name != ".visemeface-frames.json")


LONG_TEXT = ("Bob moves five boats past the old mill while seven quiet sheep watch from the hill and "
             "the farmer counts them twice before the rain comes down on the valley.")
KINEMATIC = {
    "speak": ["speak", "{transcript}"],
    "say": ["say", LONG_TEXT, "--rate", "120"],
    "speak-recording": ["speak", "{recording}", "--text", "set white with p two soon"],   # aligned, sound muxed
}


def _kinematic(work, command, tag, *more):
    from visemeface.resources import transcripts_path

    head = [a.format(transcript=transcripts_path("bob_moves_five_boats_long.TextGrid"),
                     recording=transcripts_path("set_white_with_p_two_soon.wav")) for a in KINEMATIC[command]]
    argv = [sys.executable, "-m", "visemeface", *head, "--fps", "120", "--size", "64", "--msaa", "0", "-q",
            "-o", f"{tag}.mp4", "--frames", f"{tag}_fr", "--pc2", f"{tag}.pc2", "--track", f"{tag}.csv", *more]
    return subprocess.Popen(argv, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _files(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL])
@pytest.mark.parametrize("command", sorted(KINEMATIC))
def test_speak_and_say_resume_byte_identical_after_any_interruption(tmp_path, command, sig, prompt_s):
    """Interrupted mid-render by Ctrl-C, SIGTERM or a kill, then --resume: the very bytes of an uninterrupted
    run (video, PNGs, PC2, track), nothing else left in the folder, and Ctrl-C/SIGTERM end it promptly."""
    ref, cut = tmp_path / "ref", tmp_path / "cut"
    ref.mkdir(), cut.mkdir()
    proc = _kinematic(ref, command, "t")
    assert proc.wait(timeout=240) == 0, proc.communicate()[1]

    proc = _kinematic(cut, command, "t")
    partial = cut / "t_fr.partial"
    t0 = time.monotonic()
    while not (partial.is_dir() and len(list(partial.glob("*.png"))) >= 3):
        assert proc.poll() is None, f"finished before it could be interrupted: {proc.communicate()}"
        assert time.monotonic() - t0 < 120, "no frame rendered in time"
        time.sleep(0.02)
    t0 = time.monotonic()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=10)
    if sig != signal.SIGKILL:
        assert time.monotonic() - t0 < prompt_s and proc.returncode == 130 and "interrupted" in err
        assert not any((cut / n).exists() for n in ("t.mp4", "t.pc2", "t.csv", "t_fr"))  # nothing half done
    proc = _kinematic(cut, command, "t", "--resume")
    assert proc.wait(timeout=240) == 0, proc.communicate()[1]
    got, want = _files(cut), _files(ref)
    assert sorted(got) == sorted(want)              # no temporaries, partial folders or checkpoints left
    for name in want:
        assert got[name] == want[name], f"{name} differs from the uninterrupted run"


def test_after_the_interrupted_line_nothing_more_is_printed(tmp_path):
    """What runs at exit after an interrupt (a library's exit hook: Dask closing a cluster caught half made
    printed a 30-line traceback) does not add to the one line."""
    from visemeface.resources import transcripts_path

    program = ("import atexit, sys\n"
               "atexit.register(lambda: print('Exception ignored in atexit callback', file=sys.stderr))\n"
               "from visemeface.cli import main\n"
               "main()\n")
    argv = [sys.executable, "-c", program, "speak", str(transcripts_path("bob_moves_five_boats_long.TextGrid")),
            "--fps", "120", "--size", "64", "--msaa", "0", "-q", "--frames", "fr"]
    proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while not ((tmp_path / "fr.partial").is_dir() and len(list((tmp_path / "fr.partial").glob("*.png"))) >= 3):
        assert proc.poll() is None, f"finished before it could be interrupted: {proc.communicate()}"
        assert time.monotonic() - t0 < 120, "no frame rendered in time"
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    lines = err.splitlines()          # the frames kept for --resume are said before it
    assert proc.returncode == 130 and lines[-1] == "visemeface: interrupted", err
    assert all(line.startswith("visemeface: ") for line in lines), err


def test_an_interrupt_c_code_caught_and_printed_leaves_only_the_line():
    """An interrupt raised where C code calls Python (an extension module importing another, a finaliser) is
    printed there as a traceback through sys.stderr before the command unwinds (seen: two frames of
    importlib, then the line, once in a few hundred interrupts of simulate); the user sees the one line."""
    code = """
import gc, os, signal, sys, time
from visemeface import cli

class Finalised:
    def __del__(self):                       # run by the interpreter, which prints what it raises
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.5)

def run(argv, armed):
    Finalised()
    gc.collect()
    raise ImportError("the extension gave up after the interrupt it printed")

cli._main = run
status = cli.main(["visemes"])
assert not isinstance(sys.stderr, cli._Muted)
print(status)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "130", done.stdout + done.stderr
    assert done.stderr == "visemeface: interrupted\n", done.stderr

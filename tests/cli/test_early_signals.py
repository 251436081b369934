"""Ctrl-C or SIGTERM at any moment of any sub-command: exit 130, the one line "visemeface: interrupted",
nothing half written. Before, a signal in the first seconds (imports and parsing, before the handler
existed) printed a 30-67 line KeyboardInterrupt traceback (SIGINT) or killed the process (SIGTERM, rc -15).

The moments are measured from the launch, but never earlier than the moment the process catches SIGTERM
(read from ``/proc/PID/status``: Python catches SIGINT itself from its start, SIGTERM only once the
command line's first instruction has run): before that no code of the package has run yet, and no
program can handle a signal there. So the test does not depend on how fast this machine starts Python.
"""

import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from visemeface.resources import transcripts_path

#: Launches of every sub-command, each given what it needs to run for a while (or finish).
COMMANDS = {
    "face": ["face", "-o", "out.png"],
    "pose": ["pose", "aa", "-o", "out.png"],
    "speak": ["speak", "{transcript}", "-o", "out.mp4", "--size", "64", "-q"],
    "muscles": ["muscles"],
    "say": ["say", "hello there", "-o", "out.mp4", "--size", "64", "-q"],
    "lipsync": ["lipsync", "{recording}", "-o", "out.lab"],
    "preview": ["preview", "a.glb", "-o", "out.html"],
    "visemes": ["visemes"],
    "emotions": ["emotions"],
    "sheet": ["sheet", "-o", "out.png", "--size", "64"],
    "simulate": ["simulate", "part", "--resolution", "800", "--size", "32", "--msaa", "0", "-o", "out.mp4", "-q"],
    "batch": ["batch", "jobs.csv", "-o", "out", "--size", "32", "--workers", "1", "-q"],
    "analyze": ["analyze", "frames", "--box", "8,12,16,8", "-o", "out.csv", "-q"],
    "compare": ["compare", "a.csv", "a.csv"],
}


def _inputs(work):
    from visemeface.export.images import write_png

    (work / "frames").mkdir()
    rng = np.random.default_rng(0)
    for i in range(40):
        write_png(work / "frames" / f"f{i:03d}.png", rng.integers(0, 255, (32, 32, 3), dtype=np.uint8))
    (work / "jobs.csv").write_text("clip,text\na,hello there\nb,bob moves five boats\n")
    from visemeface.export.gltf import write_morph_animation_glb

    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    write_morph_animation_glb(work / "a.glb", tri, [[0, 1, 2]], tri[None] * 0.1, ["m"], [0.0, 1.0], [[0.0], [1.0]])
    (work / "a.csv").write_text("frame,time,count,area,width,height\n" +
                                "".join(f"{i},{i / 30:.4f},1,{0.01 * (i % 5)},{0.1 * (i % 3)},{0.05 * (i % 4)}\n"
                                        for i in range(60)))
    return {p.name for p in work.iterdir()}


@pytest.fixture(scope="module")
def startup(startup_s):
    """Where ``/proc`` cannot say when the handlers are in (not Linux): twice the slowest of three starts of
    the interpreter importing the entry module, on this machine."""
    return 2 * startup_s


def _catches_sigterm(pid: int) -> bool | None:
    """Whether process ``pid`` has a handler for SIGTERM (its ``SigCgt`` mask); None where /proc cannot say."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signal.SIGTERM - 1) & 1)
    except OSError:
        return None
    return None


def _wait_for_handlers(proc, startup: float, limit: float = 60.0) -> None:
    """Until ``proc`` catches SIGTERM (or ends); without /proc, ``startup`` seconds from now."""
    t0 = time.monotonic()
    while proc.poll() is None and time.monotonic() - t0 < limit:
        caught = _catches_sigterm(proc.pid)
        if caught is None:
            time.sleep(max(0.0, startup - (time.monotonic() - t0)))
            return
        if caught:
            return
        time.sleep(0.002)


def _interrupt(work, command, at, sig, startup):
    argv = [a.format(transcript=transcripts_path("bob_moves_five_boats.txt"),
                     recording=transcripts_path("set_white_with_p_two_soon.wav")) for a in COMMANDS[command]]
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", *argv], cwd=work, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    _wait_for_handlers(proc, startup)
    time.sleep(max(0.0, at - (time.monotonic() - t0)))
    done_before = proc.poll() is not None
    if not done_before:
        proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    return done_before, proc.returncode, err


def _check(work, inputs, command, at, sig, startup):
    done_before, rc, err = _interrupt(work, command, at, sig, startup)
    where = f"{command} {sig.name} at {at:.2f} s"
    if done_before or rc == 0:   # it finished first, or the signal came as it was ending: a whole, normal run
        assert rc == 0, f"{where}: finished with {rc}: {err}"
        import shutil

        for name in {p.name for p in work.iterdir()} - inputs:      # the next launch starts afresh
            shutil.rmtree(work / name) if (work / name).is_dir() else (work / name).unlink()
        return
    # the interrupt adds one line (after any progress line the command had printed), no traceback
    lines = err.splitlines()
    assert rc == 130 and lines[-1:] == ["visemeface: interrupted"], f"{where}: rc {rc}, stderr:\n{err}"
    assert all(line.startswith("visemeface: ") for line in lines), f"{where}: stderr:\n{err}"
    left = {p.name for p in work.iterdir()} - inputs
    # only what --resume continues from (a checkpoint, a folder of frames in progress, a batch folder whose
    # report lists what is not made yet), no finished-looking output
    assert all(n.endswith((".checkpoint", ".partial")) or _resumable_batch(work / n) for n in left), \
        f"{where}: left {sorted(left)}"
    for name in left:
        import shutil

        shutil.rmtree(work / name)


def _resumable_batch(folder):
    """A batch folder stopped part way: its report says which clips are made (each a folder) and which not."""
    from visemeface.batch import REPORT, read_report

    if not (folder / REPORT).is_file():
        return False
    rows = read_report(folder / REPORT)
    made = {r["clip"] for r in rows if r["status"] == "done"}
    return (all(r["status"] == "done" or "interrupted" in r["error"] for r in rows)
            and made <= {p.name for p in folder.iterdir() if p.is_dir()})


def test_an_early_ctrl_c_or_sigterm_is_one_line_and_130(tmp_path, startup):
    inputs = _inputs(tmp_path)
    for at in (0.0, 0.5):
        for sig in (signal.SIGINT, signal.SIGTERM):
            _check(tmp_path, inputs, "visemes", at, sig, startup)


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_signal_at_any_early_moment_of_any_command_is_one_line_and_130(tmp_path, startup, command):
    inputs = _inputs(tmp_path)
    for at in (0.1, 0.5, 1.0, 2.0):
        for sig in (signal.SIGINT, signal.SIGTERM):
            _check(tmp_path, inputs, command, at, sig, startup)


def test_a_signal_as_the_outputs_land_ends_a_finished_run_with_its_outputs_whole(tmp_path):
    """The signal in the last window (the outputs renamed into place, the command returning) came in CI as
    ``speak`` ended: it read as interrupted (130) beside its whole video and sidecar. Sent here exactly there
    (from a hook run as the last outputs land), the run ends as done, every output in place; one sent before
    the outputs land (as the transcript is written) still leaves nothing."""
    code = ("import os, signal, sys\n"
            "from visemeface import runtime\n"
            "runtime.LANDED.append(lambda: os.kill(os.getpid(), signal.SIGTERM))\n"
            "from visemeface.cli import main\n"
            "sys.argv = ['visemeface', *sys.argv[1:]]\n"
            "main()\n")
    argv = ["speak", str(transcripts_path("bob_moves_five_boats.txt")), "-o", "out.mp4", "--size", "32",
            "--msaa", "0", "-q", "--save-transcript", "out.json"]
    done = subprocess.run([sys.executable, "-c", code, *argv], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json", "out.mp4"]     # no temporaries


def test_outputs_land_together_and_a_signal_meanwhile_waits_for_them():
    from visemeface.runtime import LANDED, landing

    came, order = [], []
    kept = signal.signal(signal.SIGTERM, lambda signum, frame: came.append(len(order)))
    LANDED.append(lambda: order.append("landed"))
    try:
        with landing(final=True):
            signal.raise_signal(signal.SIGTERM)
            order.append("renamed")
            assert came == []                    # not delivered inside
        assert order == ["renamed", "landed"] and came == [2]   # delivered after the hooks ran
        with landing():
            pass
        assert order == ["renamed", "landed"]    # not the command's last outputs: no hook
    finally:
        LANDED.pop()
        signal.signal(signal.SIGTERM, kept)

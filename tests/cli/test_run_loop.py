"""The one streaming loop: sinks from one registry, all-or-nothing outputs, exact resume."""

import numpy as np
import pytest

from visemeface import pipeline
from visemeface.cli import main
from visemeface.export import SINKS, Sink
from visemeface.export.pc2 import read_pc2

TINY = "0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n"


class Recorder(Sink):
    """A sink of a test: records what the loop hands it."""

    name = "recorder"
    metavar = "FILE.rec"
    help = "test sink"
    suffixes = (".rec",)
    calls: list = []

    def open(self, run):
        super().open(run)
        Recorder.calls.append(("open", run.n_frames, run.fps))

    def write(self, frame):
        Recorder.calls.append(("write", frame.index, frame.vertices.shape))

    def close(self):
        self.tmp[0].write_text(f"{sum(c[0] == 'write' for c in Recorder.calls)} frames\n")
        Recorder.calls.append(("close",))


@pytest.fixture
def recorder():
    SINKS["recorder"] = Recorder
    Recorder.calls = []
    yield Recorder
    del SINKS["recorder"]


@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.txt").write_text(TINY)
    return tmp_path


def _writes(calls):
    return [c[1] for c in calls if c[0] == "write"]


def test_a_new_sink_is_an_option_of_speak_say_and_simulate_and_is_fed_every_frame(work, recorder, capsys):
    assert main(["speak", "tiny.txt", "--no-video", "--recorder", "a.rec", "-q"]) == 0
    assert _writes(recorder.calls) == list(range(9)) and recorder.calls[-1] == ("close",)
    assert (work / "a.rec").read_text() == "9 frames\n"
    recorder.calls = []
    assert main(["say", "hi", "--no-video", "--recorder", "b.rec", "-q"]) == 0
    assert recorder.calls[0][0] == "open" and _writes(recorder.calls) == list(range(recorder.calls[0][1]))
    recorder.calls = []
    # simulate's frames go through the same loop (checked up to the first frame: the FEM is slow)
    from visemeface.physics import drive

    def one_frame(self, start=None):
        yield next(iter(real_frames(self, start)))
        raise KeyboardInterrupt
    real_frames = drive.StickySimulation.frames
    monkey = pytest.MonkeyPatch()
    monkey.setattr(drive.StickySimulation, "frames", one_frame)
    try:
        code = main(["simulate", "part", "--resolution", "800", "--fps", "10", "--no-video", "--measures", "s.csv",
                     "--recorder", "c.rec", "-q"])
    finally:
        monkey.undo()
    assert code == 130 and _writes(recorder.calls) == [0]
    assert sorted(p.name for p in work.iterdir() if not p.name.startswith(".")) == [
        "a.rec", "b.rec", "s.csv.checkpoint", "tiny.txt"]     # the checkpoint lies beside the first output


def test_a_failing_output_leaves_no_output_at_all(work, recorder, monkeypatch, capsys):
    def broken(self):
        raise OSError("disk full")

    monkeypatch.setattr(Recorder, "close", broken)
    with pytest.raises(OSError):
        pipeline_main(["speak", "tiny.txt", "--size", "32", "--pc2", "a.pc2", "--track", "a.csv",
                       "--recorder", "a.rec", "-q"])
    assert sorted(p.name for p in work.iterdir()) == ["tiny.txt"]


def pipeline_main(argv):
    """The command without the CLI's error handling (to see the real exception)."""
    from visemeface.cli import build_parser

    args = build_parser().parse_args(argv)
    return args.func(args)


def test_stale_temporaries_of_a_killed_run_are_removed_by_the_next(work, capsys):
    stale = work / ".tiny.mp4.vf999999~.mp4"        # pid 999999: no such process
    stale.write_bytes(b"half a video")
    assert main(["speak", "tiny.txt", "--size", "128", "--msaa", "0", "-q"]) == 0
    assert not stale.exists()
    assert sorted(p.name for p in work.iterdir()) == ["tiny.mp4", "tiny.mp4.json", "tiny.txt"]


# ----------------------------------------------------------------------------- resume of a simulation

def _count_steps(monkeypatch):
    """Count the frames the FEM actually simulates (every yielded SimFrame)."""
    from visemeface.physics import drive

    made = []
    real = drive.StickySimulation.frames

    def counting(self, start=None):
        for fr in real(self, start):
            made.append(fr.index)
            yield fr
    monkeypatch.setattr(drive.StickySimulation, "frames", counting)
    return made


def _interrupt_after(monkeypatch, n):
    from visemeface.export import pc2

    real = pc2.Pc2Sink.write
    seen = []

    def write(self, frame):
        if len(seen) == n:
            raise KeyboardInterrupt
        seen.append(frame.index)
        real(self, frame)
    monkeypatch.setattr(pc2.Pc2Sink, "write", write)
    return lambda: monkeypatch.setattr(pc2.Pc2Sink, "write", real)


@pytest.mark.slow
@pytest.mark.parametrize("command", [
    ["simulate", "part", "--resolution", "800", "--fps", "20", "--view", "mouth"],
    ["speak", "tiny.txt", "--physics", "sticky", "--face", "coarse.obj", "--fps", "30"],
])
def test_an_interrupted_simulation_resumes_without_simulating_a_frame_twice(work, monkeypatch, capsys, command):
    from visemeface.face.procedural import default_face

    default_face(resolution=800).save(work / "coarse.obj")
    outs = ["--size", "32", "--msaa", "0", "--pc2", "{}.pc2", "--frames", "{}_fr", "--measures", "{}.csv",
            "-o", "{}.mp4", "-q"]

    def argv(tag, *more):
        return command + [o.format(tag) for o in outs] + list(more)

    made = _count_steps(monkeypatch)
    assert main(argv("full")) == 0, capsys.readouterr().err
    n = len(made)
    assert made == list(range(n)) and n > 6
    made.clear()

    undo = _interrupt_after(monkeypatch, n // 2)
    assert main(argv("cut")) == 130
    undo()
    assert (work / "cut.mp4.checkpoint" / "state.npz").is_file()
    assert not (work / "cut.pc2").exists() and not (work / "cut.mp4").exists()   # nothing half written
    first = list(made)
    made.clear()
    assert main(argv("cut", "--resume")) == 0, capsys.readouterr().err
    # every frame simulated exactly once over the two runs (the interrupted frame was never finished)
    assert sorted(first[:n // 2] + made) == list(range(n)) and len(set(first) & set(made)) <= 1
    assert not (work / "cut.mp4.checkpoint").exists()

    a, _ = read_pc2(work / "full.pc2")
    b, _ = read_pc2(work / "cut.pc2")
    np.testing.assert_array_equal(a[:n // 2], b[:n // 2])         # replayed from the checkpoint
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-7)
    assert sorted(p.name for p in (work / "cut_fr").glob("*.png")) == [f"frame_{i:06d}.png" for i in range(n)]
    # The simulation's state (u, u_prev, step, saliva film) restores exactly: bit-identical outputs.
    np.testing.assert_array_equal(a, b)
    assert (work / "full.csv").read_text() == (work / "cut.csv").read_text()
    for png in sorted((work / "full_fr").glob("*.png")):
        assert png.read_bytes() == (work / "cut_fr" / png.name).read_bytes()


def test_a_checkpoint_of_another_run_or_a_corrupt_one_is_refused(tmp_path, fem_face):
    from visemeface.checkpoint import RunCheckpoint
    from visemeface.errors import InputError

    folder = tmp_path / "x.mp4.checkpoint"
    ck = RunCheckpoint(folder, "key-a", 4, 30.0)
    ck.start(0)
    from visemeface.motion import Frame

    for i in range(3):
        ck.record(Frame(i, i / 30, np.full((4, 3), i, np.float32), {"g": float(i)}))
    ck.save({"frame": 2, "u": np.arange(3.0), "tag": "s"}, 3)
    ck.close()
    done, state = RunCheckpoint(folder, "key-a", 4, 30.0).load()
    assert done == 3 and state["frame"] == 2 and state["tag"] == "s" and state["u"].tolist() == [0, 1, 2]
    assert RunCheckpoint(folder, "key-a", 4, 30.0).replay(1).data == {"g": 1.0}
    with pytest.raises(InputError, match=r"different run \(other input or options\)"):
        RunCheckpoint(folder, "key-b", 4, 30.0).load()
    with pytest.raises(InputError, match="--resume to continue it or --force"):
        RunCheckpoint(folder, "key-a", 4, 30.0).check(resume=False, force=False)
    (folder / "state.npz").write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(InputError, match="not a readable checkpoint"):
        RunCheckpoint(folder, "key-a", 4, 30.0).load()
    # a pickled object is never loaded
    with open(folder / "state.npz", "wb") as fh:
        np.savez(fh, _frames_done=np.int64(1), _key=np.str_("key-a"), evil=np.array([object()], dtype=object))
    with pytest.raises(InputError, match="not a readable checkpoint"):
        RunCheckpoint(folder, "key-a", 4, 30.0).load()


def test_a_refused_checkpoint_names_the_settings_that_differ(tmp_path):
    from visemeface.checkpoint import RunCheckpoint
    from visemeface.errors import InputError
    from visemeface.motion import Frame

    folder = tmp_path / "x.mp4.checkpoint"
    then = {"physics": "sticky", "glue": "0.3", "tissue_limit": "2.5", "dt": "None"}
    ck = RunCheckpoint(folder, "key-a", 4, 30.0, then)
    ck.start(0)
    ck.record(Frame(0, 0.0, np.zeros((4, 3), np.float32), {}))
    ck.save({"frame": 0}, 1)
    ck.close()
    assert RunCheckpoint(folder, "key-a", 4, 30.0, then).load()[0] == 1
    with pytest.raises(InputError, match=r"different run \(tissue_limit 2.5 then, inf now\); use the same input and options"):
        RunCheckpoint(folder, "key-b", 4, 30.0, {**then, "tissue_limit": "inf"}).load()
    with pytest.raises(InputError, match=r"\(dt None then, 1e-05 now; glue 0.3 then, 0.08 now\)"):
        RunCheckpoint(folder, "key-b", 4, 30.0, {**then, "glue": "0.08", "dt": "1e-05"}).load()
    with pytest.raises(InputError, match=r"\(other input, the same options\)"):    # e.g. another transcript
        RunCheckpoint(folder, "key-b", 4, 30.0, then).load()


def test_a_simulations_settings_name_every_option_that_changes_its_result(fem_face, rig):
    from visemeface.motion import SimulatedMotion
    from visemeface.physics import drive

    fem = fem_face
    track = drive.ramp_track(rig.names, 30, 0.0, 0.1, 0.0, 0.2)
    a = SimulatedMotion(drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(tissue_limit=2.5)))
    b = SimulatedMotion(drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=1)))
    diff = {k for k in a.settings() if a.settings()[k] != b.settings()[k]}
    assert diff == {"tissue_limit"} and a.settings()["physics"] == "sticky" and a.settings()["fps"] == "30"
    assert a.key() != b.key()


def test_frame_clock_one_rule():
    from visemeface.track import frame_count, frame_of

    assert frame_count(0.8, 30) == 24 and frame_count(0.1, 30) == 3 and frame_count(0.0, 30) == 1
    assert frame_of(0.1, 30) == 3 and frame_of(0.0999, 30) == 2
    assert pipeline.RenderSettings(size=48, msaa=0).check().key() == "48/face/msaa0"


def test_a_diverged_run_keeps_no_checkpoint_and_does_not_offer_resume(work, recorder, capsys):
    """A simulation is deterministic: resumed after a divergence it diverges at the same step again, and
    with the options changed the checkpoint would be refused. So none is kept (the next run needs no
    --force), the finished frames stay to look at, and nothing says to rerun with --resume."""
    from visemeface.errors import SimulationDiverged
    from visemeface.physics import drive

    def diverges_after_one(self, start=None):
        yield next(iter(real_frames(self, start)))
        raise SimulationDiverged("simulation diverged at step 7 (t = 0.001 s): forced", 7, 0.001, 0)
    real_frames = drive.StickySimulation.frames
    monkey = pytest.MonkeyPatch()
    monkey.setattr(drive.StickySimulation, "frames", diverges_after_one)
    try:
        code = main(["simulate", "part", "--resolution", "800", "--fps", "10", "--no-video", "--measures", "s.csv",
                     "--frames", "fr", "--recorder", "c.rec", "-q"])
    finally:
        monkey.undo()
    err = capsys.readouterr().err
    assert code == 3 and _writes(recorder.calls) == [0]
    assert "diverged at step 7" in err and "--resume to continue" not in err
    assert "1 finished frame(s) kept in fr.partial; to look at" in err
    assert sorted(p.name for p in work.iterdir() if not p.name.startswith(".")) == [
        "fr.partial", "tiny.txt"]                              # no checkpoint, no output written

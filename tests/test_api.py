"""The one-call Python API (``visemeface.speak`` ...): the command's own job, defaults and errors."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import visemeface
from visemeface.cli import main
from visemeface.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
TINY = "0.00 0.05 _\n0.05 0.25 aa\n0.25 0.40 m\n0.40 0.50 _\n"


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.txt").write_text(TINY)
    return tmp_path


def test_import_is_light_and_the_calls_are_there():
    code = ("import sys, visemeface; heavy = {'numpy', 'pandas', 'scipy', 'numba', 'moderngl'} & set(sys.modules);"
            "assert not heavy, heavy; assert callable(visemeface.speak)")
    subprocess.run([sys.executable, "-c", code], check=True)
    assert {"speak", "say", "simulate", "lipsync", "analyze", "Result"} <= set(dir(visemeface))
    with pytest.raises(AttributeError):
        visemeface.no_such_call


def test_speak_writes_what_the_command_writes_with_its_defaults(folder):
    run = visemeface.speak("tiny.txt", no_video=True, track="api.csv", arkit="api_arkit.csv", fps=25,
                           emotion={"happiness": 0.5})
    assert main(["speak", "tiny.txt", "--no-video", "--track", "cli.csv", "--arkit", "cli_arkit.csv", "--fps", "25",
                 "--emotion", "happiness=0.5", "-q"]) == 0
    assert (folder / "api.csv").read_bytes() == (folder / "cli.csv").read_bytes()
    assert (folder / "api_arkit.csv").read_bytes() == (folder / "cli_arkit.csv").read_bytes()
    assert sorted(p.name for p in run.outputs) == ["api.csv", "api_arkit.csv"]
    assert run.frames == 13 and run.seconds > 0 and run.runs[0].live == 13      # 0.5 s at 25 fps
    assert run.command_line.startswith("visemeface speak tiny.txt --no-video --track api.csv")


def test_the_default_video_and_its_sidecar(folder):
    run = visemeface.speak("tiny.txt", size=64, msaa=0)
    assert [p.name for p in run.outputs] == ["tiny.mp4", "tiny.mp4.json"]
    assert (folder / "tiny.mp4").stat().st_size > 0
    with pytest.raises(InputError, match="exists"):              # never overwritten without force
        visemeface.speak("tiny.txt", size=64, msaa=0)
    assert visemeface.speak("tiny.txt", size=64, msaa=0, force=True).frames == 15


def test_bad_input_raises_the_commands_error_and_writes_nothing(folder):
    with pytest.raises(InputError, match="transcript not found"):
        visemeface.speak("missing.txt", "m.mp4")
    with pytest.raises(Exception, match="--fps"):
        visemeface.speak("tiny.txt", "m.mp4", fps=-3)
    with pytest.raises(TypeError, match="unexpected option 'emotions'.*did you mean: emotion"):
        visemeface.speak("tiny.txt", "m.mp4", emotions="happiness")
    with pytest.raises(TypeError, match="takes one value"):
        visemeface.speak("tiny.txt", "m.mp4", fps=[25, 30])
    assert not list(folder.glob("m.mp4*"))


@pytest.mark.slow
def test_lipsync_and_analyze(folder):
    shutil.copy(ROOT / "transcripts" / "set_white_with_p_two_soon.wav", folder / "take.wav")
    run = visemeface.lipsync("take.wav", "take.lab", text="set white with p two soon")
    assert run.outputs == [Path("take.lab")] and run.frames is None
    assert "s" in (folder / "take.lab").read_text().split()
    visemeface.speak("tiny.txt", "v.mp4", size=128, msaa=0)
    profile = visemeface.analyze("v.mp4", "v.csv")
    assert profile.outputs == [Path("v.csv")] and profile.frames == 15


@pytest.mark.slow
def test_the_acceptance_line_runs(tmp_path):
    shutil.copytree(ROOT / "transcripts", tmp_path / "transcripts")
    subprocess.run([sys.executable, "-c", "import visemeface; visemeface.speak("
                    "'transcripts/bob_moves_five_boats.txt', 'bob.mp4')"], cwd=tmp_path, check=True, timeout=300)
    assert (tmp_path / "bob.mp4").stat().st_size > 1000 and (tmp_path / "bob.mp4.json").is_file()


def test_options_become_the_commands_arguments():
    from visemeface.api import command_line

    argv = command_line("simulate", ["open-once"], "z.mp4", lips="seed", glue=0.1, film_corners=False,
                        resume=False, quiet=False)
    assert argv == ["open-once", "-o", "z.mp4", "--lips", "seed", "--glue", "0.1", "--no-film-corners"]
    argv = command_line("speak", ["t.txt"], emotion=["happiness=0.5", "surprise"], physics="sticky")
    assert argv == ["t.txt", "--emotion", "happiness=0.5", "--emotion", "surprise", "--physics", "sticky", "--quiet"]
    with pytest.raises(TypeError, match="takes one value"):
        command_line("speak", ["t.txt"], physics=["sticky"])


def test_an_input_error_quoting_a_file_stays_one_line():
    """A tier name read from a TextGrid with a newline in it made a message of nine lines."""
    from visemeface.errors import InputError

    e = InputError("no phone tier among words, pho\nnes\t2", "a\nb.TextGrid", 3)
    assert str(e) == "a\\nb.TextGrid:3: no phone tier among words, pho\\nnes\\t2" and e.reason.endswith("\\t2")

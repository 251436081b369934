"""Install tiers: the core works without the optional extras, and a command that needs a missing one names it.

The extras' libraries are made absent in a child process by a finder that refuses their import, as Python
does for a package that is not installed; which libraries those are is read from pyproject.toml, so a
dependency moved between tiers is tested where it now lives.
"""

import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from visemeface.errors import DISTRIBUTIONS, MissingExtra, extras_providing, missing_extra

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
EXTRAS = PROJECT["optional-dependencies"]
TRANSCRIPT = ROOT / "transcripts" / "one_five_zero_zero_six.txt"


def _name(requirement: str) -> str:
    return re.split(r"[<>=\[;! ]", requirement.strip(), maxsplit=1)[0].lower()


def _modules(distributions) -> list[str]:
    by_distribution = {d: m for m, d in DISTRIBUTIONS.items()}
    return sorted({by_distribution.get(d, d.replace("-", "_")) for d in distributions})


def _extra_libraries(*extras) -> set[str]:
    return {_name(r) for e in extras for r in EXTRAS[e] if not r.startswith("visemeface")}


def _run_without(modules, *args, cwd):
    """``visemeface ARGS`` in a child process in which ``modules`` cannot be imported."""
    code = textwrap.dedent(f"""
        import importlib.abc, sys
        BLOCKED = {sorted(modules)!r}
        class Absent(importlib.abc.MetaPathFinder):
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in BLOCKED:
                    raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        sys.meta_path.insert(0, Absent())
        from visemeface.cli import main
        sys.exit(main({[str(a) for a in args]!r}))
    """)
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=600)


OPTIONAL = _modules(_extra_libraries("audio", "render", "physics", "batch", "track", "tts", "live"))


def test_the_core_dependencies_are_none_of_the_extras_and_all_gathers_every_tier():
    core = {_name(r) for r in PROJECT["dependencies"]}
    tiers = ("audio", "render", "physics", "batch", "track")
    assert not core & _extra_libraries(*tiers)
    assert EXTRAS["all"] == [f"visemeface[{','.join(tiers)}]"]
    assert any(r.startswith("visemeface[") and "all" in r for r in EXTRAS["test"])   # CI tests every tier


def test_curves_from_a_transcript_and_their_conversion_need_no_extra(tmp_path):
    done = _run_without(OPTIONAL, "speak", TRANSCRIPT, "--arkit", "a.csv", "--no-video", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    header = (tmp_path / "a.csv").read_text().splitlines()[0]
    assert "jawOpen" in header and "mouthClose" in header
    done = _run_without(OPTIONAL, "convert", "a.csv", "c.json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "c.json").stat().st_size > 0


def test_comparing_two_measured_profiles_needs_no_extra(tmp_path):
    rows = ["time,count,area,width,height"] + [f"{i / 30:.6f},1,{a},{a / 2},{a / 3}"
                                                for i, a in enumerate([0, 4, 9, 16, 9, 4, 0, 1, 5, 2])]
    (tmp_path / "p.csv").write_text("\n".join(rows) + "\n")
    done = _run_without(OPTIONAL, "compare", "p.csv", "p.csv", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    header, row = done.stdout.strip().splitlines()
    figures = dict(zip(header.split(), row.split()[3:]))
    assert float(figures["L2_area"]) == 0 and float(figures["r_height"]) == 1


@pytest.mark.parametrize("args, absent, extra", [
    (["speak", TRANSCRIPT, "-o", "v.mp4"], _modules(_extra_libraries("render")), "render"),
    (["simulate", "open-once", "-o", "s.mp4"], _modules(_extra_libraries("physics")), "physics"),
], ids=["video-without-render", "simulate-without-physics"])
def test_a_command_needing_a_missing_extra_names_it_in_one_line_and_writes_nothing(tmp_path, args, absent, extra):
    done = _run_without(absent, *args, cwd=tmp_path)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("visemeface: error: this needs ")
    assert f'pip install "visemeface[{extra}]"' in lines[0] or f"[{extra}]" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_wav_recording_aligns_in_the_core_and_a_video_one_names_the_audio_extra(tmp_path):
    import shutil

    from visemeface.resources import transcripts_path

    for suffix in (".wav", ".txt"):
        shutil.copy(transcripts_path("set_white_with_p_two_soon" + suffix), tmp_path / ("r" + suffix))
    done = _run_without(OPTIONAL, "lipsync", "r.wav", "-o", "r.lab", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    words = [line.split()[-1] for line in (tmp_path / "r.lab").read_text().splitlines()]
    assert {"s", "eh", "t"} <= set(words)
    (tmp_path / "v.mp4").write_bytes(b"\x00\x00\x00\x18ftypmp42")
    done = _run_without(OPTIONAL, "lipsync", "v.mp4", "--text", "set white", "-o", "v.lab", cwd=tmp_path)
    assert done.returncode == 2
    assert '"visemeface[audio]"' in done.stderr and done.stderr.strip().splitlines()[-1].startswith("visemeface: error:")
    assert not (tmp_path / "v.lab").exists()


def test_an_import_error_that_is_not_a_missing_extra_stays_an_error():
    # A typo'd module inside the package must stay a traceback (a bug), not be dressed as a missing extra.
    assert missing_extra(ModuleNotFoundError("No module named 'visemeface.nothere'", name="visemeface.nothere")) is None
    assert missing_extra(ModuleNotFoundError("No module named 'nosuchlib'", name="nosuchlib")) is None
    assert missing_extra(ValueError("numba")) is None


def test_the_extras_of_a_library_come_from_the_installed_metadata():
    assert set(extras_providing("numba")) == {"physics", "render"}
    assert extras_providing("opencv-python-headless")[0] in ("render", "track")
    exc = missing_extra(ModuleNotFoundError("No module named 'cv2'", name="cv2"))
    assert isinstance(exc, MissingExtra) and exc.module == "cv2"
    assert "opencv-python-headless" in str(exc) and exc.command.startswith('pip install "visemeface[')

"""README's commands and the guide's run top to bottom in one fresh folder, none refused for an existing output.

The folder holds a copy of ``transcripts/`` as a fresh clone does. Every ``visemeface`` line of the bash
blocks of README.md, then of each page of ``docs/guide/`` (in the navigation's order: the commands as
``visemeface --help`` lists them, then the other pages by name), runs as written, in order, so a page may
use what an earlier one wrote. The physical simulations (``simulate``, ``--physics``, minutes each) are
covered by tests/physics and tests/cli/test_signals.py and are left out here, but their output names must
still not collide with any other command's. Lines meant to be read, not run, go in ``console`` blocks.
README's Python block runs too, in a fresh folder of its own.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
#: ``../shared`` beside the repository (the real GRID clips a README line analyses; moved with
#: VISEMEFACE_REALDATA like tests/conftest.py's REALDATA).
SHARED = Path(os.environ.get("VISEMEFACE_REALDATA", ROOT.parent / "shared" / "realdata")).parent


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs" / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def documented_pages() -> list[Path]:
    """README.md, then the guide's pages in the navigation's order."""
    return [ROOT / "README.md", *_hooks().guide_pages(ROOT / "docs")]


def _blocks(language: str) -> list[str]:
    return [block for page in documented_pages()
            for block in re.findall(rf"```{language}\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)]


def readme_commands():
    """The ``visemeface ...`` command lines of the bash blocks of README.md and the guide, in order (comments removed)."""
    commands = []
    for block in _blocks("bash"):
        for line in block.replace("\\\n", " ").splitlines():       # continuation lines joined
            argv = shlex.split(line, comments=True)
            if argv and argv[0].endswith("visemeface"):
                commands.append([a.replace("../shared/", str(SHARED) + "/") for a in argv[1:]])
    return commands


def _outputs(argv):
    """The files a command line names after an output option."""
    outs = set()
    for opt, value in zip(argv, argv[1:]):
        if opt in ("-o", "--output", "--export", "--frames", "--obj", "--pc2", "--gltf", "--track", "--measures",
                   "--plot", "--overlay", "--camera-json", "--arkit", "--livelink", "--vrm", "--oculus",
                   "--rhubarb", "--preview", "--save-transcript"):
            outs.add(value)
    video = {"-o", "--output", "--no-video"} & set(argv)
    if argv[0] in ("speak", "say") and not video:           # the default video: TRANSCRIPT.mp4 or say.mp4
        outs.add("say.mp4" if argv[0] == "say" else Path(argv[1]).stem + ".mp4")
    return outs


#: A file or folder name a Python block writes: a quoted name with an output's suffix, or a folder it makes.
_WRITTEN = re.compile(r'"([\w./-]+\.(?:mp4|TextGrid|lab|json|csv|png|glb|tsv|html))"|vb\.run\(.*\), "([^"]+)"')


def _python_outputs():
    """The files and folders the Python blocks write (their first runs must not meet a command's)."""
    outs = set()
    for block in _blocks("python"):
        for line in block.splitlines():
            for name, folder in _WRITTEN.findall(line.split("#")[0]):
                if (name or folder).startswith("transcripts/"):
                    continue
                outs.add(name or folder)
    return outs


def test_readme_python_writes_none_of_the_commands_outputs():
    written = {argv[argv.index("--grid") + 2] for argv in readme_commands() if "--grid" in argv}
    for argv in readme_commands():
        written |= _outputs(argv)
    python = _python_outputs()
    assert {"bob_api.mp4", "take_api.TextGrid", "jobs20.csv"} <= python
    assert not python & written, f"the Python blocks and the commands both write {sorted(python & written)}"


def test_readme_python_runs_in_a_fresh_folder(tmp_path):
    """README's one-call API as shown (the simulation, minutes, left out as for the commands)."""
    shutil.copytree(ROOT / "transcripts", tmp_path / "transcripts")
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.findall(r"```python\n(.*?)```", text, flags=re.S)[0]
    assert "visemeface.simulate(" in block
    script = "\n".join(line for line in block.splitlines() if "visemeface.simulate(" not in line)
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for name in ("bob_api.mp4", "say_api.mp4", "take_api.TextGrid", "bob_api_arkit.json", "bob_api_profile.csv"):
        assert (tmp_path / name).stat().st_size > 0, name
    assert "visemeface speak transcripts/bob_moves_five_boats.txt -o bob_api.mp4" in proc.stdout


def _physics(argv):
    return argv[0] == "simulate" or "--physics" in argv


def test_readme_names_no_output_twice():
    seen = {}
    for argv in readme_commands():
        if "--resume" in argv:
            continue                                  # continues the output of the line before
        for out in _outputs(argv):
            assert out not in seen, f"{out} is written by `{' '.join(seen[out])}` and by `{' '.join(argv)}`"
            seen[out] = argv


def test_readme_commands_run_top_to_bottom_in_a_fresh_folder(tmp_path):
    shutil.copytree(ROOT / "transcripts", tmp_path / "transcripts")
    ran, missing = 0, set()                           # outputs of the lines not run here
    for argv in readme_commands():
        absent = any(str(SHARED) in a for a in argv) and not SHARED.is_dir()   # the real clips are not here
        if _physics(argv) or absent or "--scheduler" in argv or missing & set(argv):
            missing |= _outputs(argv)                 # (simulations: minutes; --scheduler: needs a cluster)
            continue
        quiet = ["-q"] if argv[0] in ("speak", "say") else []      # no progress bars in the log
        proc = subprocess.run([sys.executable, "-m", "visemeface", *argv, *quiet], cwd=tmp_path,
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, f"`visemeface {shlex.join(argv)}` failed: {proc.stderr.strip()}"
        ran += 1
    assert ran >= 20

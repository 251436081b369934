"""README's commands run top to bottom in one fresh folder, none refused for an existing output.

The folder holds a copy of ``transcripts/`` as a fresh clone does. Every ``visemeface`` line of the
README's bash blocks runs as written, in order; the physical simulations (``simulate``, ``--physics``,
minutes each) are covered by tests/physics and tests/cli/test_signals.py and are left out here, but
their output names must still not collide with any other command's.
"""

from __future__ import annotations

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


def readme_commands():
    """The ``visemeface ...`` command lines of README.md's bash blocks, in order (comments removed)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
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
                   "--rhubarb", "--preview"):
            outs.add(value)
    video = {"-o", "--output", "--no-video"} & set(argv)
    if argv[0] in ("speak", "say") and not video:           # the default video: TRANSCRIPT.mp4 or say.mp4
        outs.add("say.mp4" if argv[0] == "say" else Path(argv[1]).stem + ".mp4")
    return outs


def _python_outputs():
    """The files and folders README's Python blocks write (their first runs must not meet a command's)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    outs = set()
    for block in re.findall(r"```python\n(.*?)```", text, flags=re.S):
        outs |= set(re.findall(r'(?:save_png|write_grid_manifest)\("([^"]+)"', block))
        outs |= set(re.findall(r'vb\.run\(.*\), "([^"]+)"', block))
    return outs


def test_readme_python_writes_none_of_the_commands_outputs():
    written = {argv[argv.index("--grid") + 2] for argv in readme_commands() if "--grid" in argv}
    for argv in readme_commands():
        written |= _outputs(argv)
    python = _python_outputs()
    assert {"happy_ah.png"} <= python and len(python) >= 3
    assert not python & written, f"README's Python and its commands both write {sorted(python & written)}"


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

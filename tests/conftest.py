"""Shared fixtures and markers.

Session fixtures build the expensive objects once for the whole run (the default
face, its rig, the FEM face). They are shared: a test must not modify them
(copy first). Tests marked ``slow`` (FEM simulations, end-to-end renders of whole
utterances, real-video runs) are skipped by the fast loop ``pytest -m "not slow"``;
CI runs everything.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

#: The repository root (tests/ lies directly under it).
ROOT = Path(__file__).resolve().parents[1]
#: Real GRID clips shared beside the repository (``../shared/realdata``; see its README).
REALDATA = Path(os.environ.get("VISEMEFACE_REALDATA", ROOT.parent / "shared" / "realdata"))


def pytest_configure(config):
    from visemeface.runtime import configure

    configure()  # as the CLI does: numba's threading layer, OpenMP spin, cache folder
    # A run started in the background by a non-interactive shell (`cmd &`, nohup) inherits SIGINT ignored, and
    # Python then installs no KeyboardInterrupt for it; the tests of what Ctrl-C does need Python's own handler
    # (and the commands they start inherit the default action).
    import signal

    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    config.addinivalue_line("markers", "slow: FEM simulations, whole-utterance renders and real-video runs "
                            "(deselect with -m 'not slow')")
    config.addinivalue_line("markers", "realdata: needs ../shared/realdata (skipped where absent)")


@pytest.fixture(scope="session")
def load_script():
    """``load_script("name")``: import ``scripts/name.py`` (the scripts are no package) as a module."""
    import importlib.util

    def load(name: str):
        spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    return load


def pytest_collection_modifyitems(config, items):
    if REALDATA.is_dir():
        return
    skip = pytest.mark.skip(reason=f"real GRID clips not found at {REALDATA} (set VISEMEFACE_REALDATA)")
    for item in items:
        if "realdata" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def startup_s() -> float:
    """This machine's start of the interpreter importing the command line (``python -c "import
    visemeface.cli"``), the slowest of three, in seconds: the baseline of every bound on time a test sets.
    A bound that matters to users (Ctrl-C ends promptly) is asserted as ``prompt_s``, so the test
    fails when the behaviour is wrong, not because another job shares the machine."""
    import subprocess
    import sys
    import time

    times = []
    for _ in range(3):
        t0 = time.monotonic()
        subprocess.run([sys.executable, "-c", "import visemeface.cli"], check=True)
        times.append(time.monotonic() - t0)
    return max(times)


#: How many interpreter starts (``startup_s``) a prompt reaction may take beyond its idle-machine allowance:
#: 0.04 s idle here, so 2 s + 25 x 0.04 s = 3 s idle; 0.4 s under a load of 4 on 2 cores gives 12 s, which
#: still tells "ended promptly" from the defects these tests guard (a decode running on for 8.6 s idle,
#: a hang until the 30-60 s timeout).
PROMPT_STARTS = 25


@pytest.fixture(scope="session")
def prompt_s(startup_s) -> float:
    """The bound in seconds on a reaction that takes 2 s on an idle machine (``PROMPT_STARTS``)."""
    return 2.0 + PROMPT_STARTS * startup_s


@pytest.fixture(scope="session")
def realdata() -> Path:
    """The folder of real GRID clips (tests using it are marked ``realdata``)."""
    return REALDATA


@pytest.fixture(scope="session")
def default_face():
    """The embedded default face (shared; do not modify)."""
    from visemeface.face.procedural import default_face as make

    return make()


@pytest.fixture(scope="session")
def rig(default_face):
    """The default rig on the default face (shared; do not modify)."""
    from visemeface.muscles.rig import MuscleRig

    return MuscleRig.from_file(default_face)


@pytest.fixture(scope="session")
def fem_face(default_face):
    """The FEM model of the default face (shared; do not modify)."""
    from visemeface.physics.face_model import build_fem_face

    return build_fem_face(default_face)


# ------------------------------------------------------------------ fuzz case counts (tests/fuzz)
#: reader name -> {"read": n, "refused": n, "crashed": n}
FUZZ_COUNTS: dict[str, dict[str, int]] = {}


@pytest.fixture(scope="session")
def fuzz_counts():
    """The session's fuzz case counts (tests/fuzz fills it; printed at the end of the run)."""
    return FUZZ_COUNTS


def pytest_terminal_summary(terminalreporter):
    if not FUZZ_COUNTS:
        return
    terminalreporter.section("fuzzed readers: read, refused with one line, or crashed (a failure)")
    total = {"read": 0, "refused": 0, "crashed": 0}
    for reader, c in sorted(FUZZ_COUNTS.items()):
        terminalreporter.write_line(f"{reader:30s} {sum(c.values()):5d} cases: {c['read']:4d} read, "
                                    f"{c['refused']:4d} refused, {c['crashed']} untyped crashes")
        total = {k: total[k] + c[k] for k in total}
    terminalreporter.write_line(f"{'all readers':30s} {sum(total.values()):5d} cases: {total['read']:4d} read, "
                                f"{total['refused']:4d} refused, {total['crashed']} untyped crashes")
@pytest.fixture(scope="session")
def vowels_wav(tmp_path_factory) -> Path:
    """1.4 s of formant-synthesised speech, "ah" (0.25-0.65 s) and "ee" (0.75-1.15 s), 16 kHz mono WAV.

    A glottal pulse train at 120 Hz through three resonators per vowel (Peterson & Barney's formants),
    between near-silences: enough for pocketsphinx to align the words "ah ee".
    """
    import numpy as np
    import soundfile as sf
    from scipy.signal import lfilter

    rate = 16000

    def vowel(formants, seconds=0.4, f0=120):
        x = np.zeros(int(seconds * rate))
        x[::rate // f0] = 1.0
        for f, bw in formants:
            r = np.exp(-np.pi * bw / rate)
            x = lfilter([1 - r], [1, -2 * r * np.cos(2 * np.pi * f / rate), r * r], x)
        return x / np.abs(x).max() * np.hanning(x.size) ** 0.3 * 0.5

    x = np.r_[np.zeros(4000), vowel([(730, 90), (1090, 110), (2440, 170)]), np.zeros(1600),
              vowel([(270, 60), (2290, 100), (3010, 150)]), np.zeros(4000)]
    x += np.random.default_rng(0).normal(0, 1e-3, x.size)
    path = tmp_path_factory.mktemp("voice") / "vowels.wav"
    sf.write(str(path), x, rate)
    return path

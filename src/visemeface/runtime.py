"""Process-wide settings for the compiled kernels, made by one explicit call.

Importing a visemeface module never changes the environment. The command line
calls :func:`configure` once at start-up (before any kernel is compiled or
run); scripts, benchmarks, notebooks and batch workers that want the same
behaviour call it themselves. What it sets, and why:

- **numba's threading layer: OpenMP** (``omp``), else ``workqueue``. numba
  picks TBB when libtbb is installed; there 2-thread TLED runs were slower
  than 1 thread, processes hung 22–140 s at exit, and forking the video
  encoder after TBB's pool had started spun forever in ``tbb::finalize``
  (numba issue #5983). GNU OpenMP's pool has no fork handler that blocks the
  parent, and our children (ffmpeg) ``exec`` at once. A layer the user chose
  (``NUMBA_THREADING_LAYER``) is kept.
- **GNU OpenMP spin** ``GOMP_SPINCOUNT=1000`` unless set: by default every
  barrier spins ~300,000 times; on a machine shared with other busy processes
  a spinning or pre-empted worker then stalls both parallel regions of each
  step (measured on a loaded 2-core box: 12 ms/step with the default, 0.6–0.7 ms
  with a short spin). It only matters before libgomp is first loaded.
- **numba's cache folder**: numba caches compiled kernels beside the package
  and falls back to ``~/.cache/numba`` when that is read-only; where both are
  read-only (a system install with no home) a folder under the temporary
  directory is used. A ``NUMBA_CACHE_DIR`` the user set is kept.
- **threads**: ``threads`` caps numba's thread count (batch workers, ``--threads``).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from visemeface.errors import InputError

#: Threading layers in order of preference (see the module docstring).
THREADING_LAYERS = ("omp", "workqueue")
#: Barrier spin of GNU OpenMP (see the module docstring).
GOMP_SPINCOUNT = "1000"


def _writable_cache_dir() -> str | None:
    """A folder for numba's cache when neither the package nor the user cache is writable."""
    package = Path(__file__).resolve().parent
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    for candidate in (package, user):
        probe = candidate if candidate.exists() else candidate.parent
        if os.access(probe, os.W_OK):
            return None  # numba's own locators find a writable place
    fallback = Path(tempfile.gettempdir()) / f"visemeface-numba-{os.getuid()}"
    try:
        fallback.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return str(fallback)


def threading_layer() -> str:
    """The threading layer :func:`configure` pins: the user's choice, else the first available."""
    chosen = os.environ.get("NUMBA_THREADING_LAYER")
    if chosen:
        return chosen
    try:
        from numba.np.ufunc import omppool  # noqa: F401  (importable where libgomp loads)
    except ImportError:
        return "workqueue"
    return "omp"


def configure(threads: int | None = None, environ=None) -> dict:
    """Pin numba's threading layer, OpenMP spin, cache folder and thread count.

    Idempotent; call it before the first kernel runs (the CLI does). Values the
    user set in the environment win.

    Parameters
    ----------
    threads : int, optional
        numba threads (1 .. the cores numba sees); None leaves numba's default.
    environ : mapping, optional
        The environment to update (default ``os.environ``; tests pass a dict).

    Returns
    -------
    dict
        ``threading_layer``, ``threads``, ``cache_dir`` (None: numba's default).
    """
    env = os.environ if environ is None else environ
    env.setdefault("GOMP_SPINCOUNT", GOMP_SPINCOUNT)
    layer = threading_layer()
    env.setdefault("NUMBA_THREADING_LAYER", layer)
    if not env.get("NUMBA_CACHE_DIR"):
        cache = _writable_cache_dir()
        if cache is not None:
            env["NUMBA_CACHE_DIR"] = cache
    if environ is None and "numba" in sys.modules:
        # numba read the environment when it was imported: update its live config.
        import numba.core.config as config

        config.THREADING_LAYER = env["NUMBA_THREADING_LAYER"]
        if env.get("NUMBA_CACHE_DIR"):
            config.CACHE_DIR = env["NUMBA_CACHE_DIR"]
    n = set_threads(threads) if threads is not None else None
    return {"threading_layer": env["NUMBA_THREADING_LAYER"], "threads": n,
            "cache_dir": env.get("NUMBA_CACHE_DIR")}


def set_threads(n: int | None) -> int:
    """Set numba's thread count (None: leave it); returns the count in use."""
    import numba

    if n is not None:
        most = numba.config.NUMBA_NUM_THREADS
        if not 1 <= int(n) <= most:
            raise InputError(f"--threads must be from 1 to {most} on this machine, got {n}")
        numba.set_num_threads(int(n))
    return numba.get_num_threads()

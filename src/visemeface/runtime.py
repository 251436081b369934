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
- **GNU OpenMP spin** ``GOMP_SPINCOUNT=10000`` unless set: how long numba's
  worker thread spins at the end of a parallel loop before it sleeps. Each
  step of the FEM face is one compiled call with two parallel loops and about
  0.1 ms of Python around it; a worker that fell asleep in that gap is woken
  for the next step, which on this 2-core virtual machine cost more than the
  second thread gained. Sticky face, 2 threads, idle machine: 435 µs
  a step at 1000, 305 µs at 10,000, 290 µs at 30,000 and 100,000; 1 thread
  345 µs. The default (300,000) is worse under load: with another busy process
  on the 2 cores a spinning worker holds the core the main thread needs (12 ms a
  step measured then; at 10,000 it was 0.9 ms against 0.49 ms at 1000, and one
  thread, 0.42 ms, is then the better choice, which is why a simulation without
  fixed threads times both, :func:`faster_thread_count`). It only matters
  before libgomp is first loaded.
- **BLAS threads: 1** (threadpoolctl). numpy's OpenBLAS pool spins for a while
  after each call; the few matrix products of a run (rig poses, fits, element
  geometry) then left OpenBLAS threads spinning on the core numba's worker
  needs: the sticky face's step took 627 µs on 2 threads against 367 µs with
  the BLAS pool at one thread. The BLAS products here are small, so one
  thread costs them little. A pool size the user set (``OPENBLAS_NUM_THREADS``
  and the like) is kept.
- **numba's cache folder**: numba caches compiled kernels beside the package
  and falls back to ``~/.cache/numba`` when that is read-only; where both are
  read-only (a system install with no home) a folder under the temporary
  directory is used. A ``NUMBA_CACHE_DIR`` the user set is kept.
- **threads**: ``threads`` caps numba's thread count (batch workers, ``--threads``).
"""

from __future__ import annotations

import contextlib
import numbers
import os
import sys
import tempfile
from pathlib import Path

from visemeface.errors import InputError

#: Threading layers in order of preference (see the module docstring).
THREADING_LAYERS = ("omp", "workqueue")
#: Variables by which a user sets the BLAS pool's size; where one is set, :func:`configure` leaves the pool alone.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")

#: Barrier spin of GNU OpenMP (see the module docstring).
GOMP_SPINCOUNT = "10000"
#: Per-frame geometry (normals, the rig's pose) of a mesh with at least this many vertices runs in numba
#: kernels: a process's first kernel costs about 0.5 s (numba's start), paid back within a few frames of a
#: scanned head (5 ms a frame on the ICT head's 24,591 vertices) but never on the default face (under 1 ms).
COMPILED_FROM_VERTICES = 10_000


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
    """The threading layer :func:`configure` pins: the user's choice, else the first available.

    OpenMP is available where numba's ``omppool`` extension loads with its libgomp: the library is loaded
    (``ctypes``, which resolves its dependencies) without importing numba, which costs a fifth of a second
    that a command refusing its input should not pay.
    """
    import ctypes
    import importlib.util

    chosen = os.environ.get("NUMBA_THREADING_LAYER")
    if chosen:
        return chosen
    try:
        spec = importlib.util.find_spec("numba")
    except ImportError:                     # not installed (the [physics] and [render] extras bring it)
        spec = None
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    pools = [p for f in folders for p in (Path(f) / "np" / "ufunc").glob("omppool*.so")]
    for pool in pools:
        try:
            ctypes.CDLL(str(pool))
        except OSError:
            continue
        return "omp"
    return "workqueue"


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
    if environ is None and not any(env.get(k) for k in BLAS_THREAD_VARIABLES):
        limit_blas_threads(1)
    n = set_threads(threads) if threads is not None else None
    return {"threading_layer": env["NUMBA_THREADING_LAYER"], "threads": n,
            "cache_dir": env.get("NUMBA_CACHE_DIR")}


def limit_blas_threads(n: int = 1) -> None:
    """Cap the BLAS libraries loaded in this process (numpy's OpenBLAS) at ``n`` threads (module docstring)."""
    import numpy  # noqa: F401  (loads its BLAS, so there is a pool to cap)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=int(n), user_api="blas")


def faster_thread_count(trial, most: int, repeats: int = 3) -> int:
    """Time ``trial()`` at ``most`` numba threads and at one; leave numba at the faster count and return it.

    For work whose result does not depend on the thread count (the FEM face's steps: each element and
    each node is one thread's, so any count gives the same bits). Two threads win on an idle 2-core
    machine and lose when another process is busy (module docstring), so a run measures rather than
    guesses. Each count's figure is the best of ``repeats`` timed calls after an untimed one.
    """
    import time

    import numba

    most = int(most)
    times = {}
    for n in (most, 1) if most > 1 else (1,):
        numba.set_num_threads(n)
        trial()
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            trial()
            best = min(best, time.perf_counter() - t0)
        times[n] = best
    n = min(times, key=times.get)
    numba.set_num_threads(n)
    return n


def check_threads(n) -> int:
    """``n`` as a numba thread count (1 .. the cores numba sees), or a one-line :class:`InputError`."""
    import numba

    most = numba.config.NUMBA_NUM_THREADS
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or not 1 <= n <= most:
        raise InputError(f"--threads must be from 1 to {most} on this machine, got {n!r}")
    return int(n)


def set_threads(n: int | None) -> int:
    """Set numba's thread count (None: leave it); returns the count in use."""
    import numba

    if n is not None:
        numba.set_num_threads(check_threads(n))
    return numba.get_num_threads()


#: Called in order when a command's outputs are all in place (:func:`landing` with ``final``). The command
#: line adds its own: a signal after that ends a finished run, not an interrupted one.
LANDED: list = []


@contextlib.contextmanager
def signals_deferred(then=None):
    """A context in which Ctrl-C and SIGTERM wait: the first that comes is delivered when the body ends.

    For starting a child process that writes a file (ffmpeg): interrupted half way through its start, the
    child runs on unseen by the code that would end it and writes its file after the interrupted run removed
    its temporaries. Deferred, the interrupt comes after the start, where the child is ended and its file
    removed. ``then`` is called once the body has ended without an error, before the handlers are put back
    (no signal can come between the body and it). Outside the main thread (where signals
    cannot be set) the body runs as it is.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        if then is not None:
            then()
        return
    came = []
    kept = {s: signal.signal(s, lambda signum, frame: came.append(signum)) for s in (signal.SIGINT, signal.SIGTERM)}
    ended = False
    try:
        yield
        ended = True
    finally:
        if ended and then is not None:
            then()                                 # while a signal still waits: it meets what ``then`` did
        for s, handler in kept.items():
            signal.signal(s, handler)
        if came:
            handler = kept[came[0]]
            if callable(handler):
                handler(came[0], None)             # the command's handler: KeyboardInterrupt, or the exit
            elif handler == signal.SIG_DFL:
                signal.raise_signal(came[0])


def _landed() -> None:
    for hook in LANDED:
        hook()


def landing(final: bool = False):
    """A context in which a run's outputs go into place together (their renames): Ctrl-C and SIGTERM wait
    until the body ends, so a run never stops with some of its outputs in place and others not. ``final``:
    these are the command's last outputs; once they are in, :data:`LANDED`'s hooks run (the command line's
    takes a signal from then on as the end of a finished run: its outputs are whole and in place)."""
    return signals_deferred(then=_landed if final else None)

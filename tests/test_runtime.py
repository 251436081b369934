"""Process settings: made by one explicit call, never by importing a module."""

import json
import os
import subprocess
import sys

from visemeface import runtime


def test_importing_every_module_changes_no_environment_variable():
    # Third-party libraries may set variables of their own at import (OpenCV sets
    # LD_LIBRARY_PATH): import them first, then measure what visemeface's modules change.
    code = (
        "import os, json, pkgutil, importlib, visemeface\n"
        "for lib in ('cv2', 'numba', 'numpy', 'scipy', 'pandas', 'matplotlib', 'moderngl', 'trimesh'):\n"
        "    importlib.import_module(lib)\n"
        "before = dict(os.environ)\n"
        "for m in pkgutil.walk_packages(visemeface.__path__, 'visemeface.'):\n"
        "    if not m.name.endswith('__main__'):\n"
        "        importlib.import_module(m.name)\n"
        "after = dict(os.environ)\n"
        "print(json.dumps(sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))))\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "GOMP_"))}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


def test_configure_pins_a_fork_safe_threading_layer_and_a_short_spin():
    env = {}
    got = runtime.configure(environ=env)
    assert env["NUMBA_THREADING_LAYER"] in runtime.THREADING_LAYERS
    assert env["GOMP_SPINCOUNT"] == runtime.GOMP_SPINCOUNT
    assert got["threading_layer"] == env["NUMBA_THREADING_LAYER"]


def test_configure_keeps_what_the_user_set():
    env = {"NUMBA_THREADING_LAYER": "workqueue", "GOMP_SPINCOUNT": "5", "NUMBA_CACHE_DIR": "/somewhere"}
    runtime.configure(environ=env)
    assert env == {"NUMBA_THREADING_LAYER": "workqueue", "GOMP_SPINCOUNT": "5", "NUMBA_CACHE_DIR": "/somewhere"}


def test_cache_folder_falls_back_to_temp_when_package_and_home_are_read_only(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setattr(runtime.tempfile, "gettempdir", lambda: str(tmp_path))
    monkeypatch.setattr(runtime.os, "access", lambda p, mode: str(p).startswith(str(tmp_path / "visemeface-numba")))
    env = {}
    runtime.configure(environ=env)
    assert env["NUMBA_CACHE_DIR"] == str(tmp_path / f"visemeface-numba-{os.getuid()}")
    assert (tmp_path / f"visemeface-numba-{os.getuid()}").is_dir()


def test_the_cli_runs_its_kernels_on_the_pinned_layer(tmp_path):
    code = ("import sys\n"
            "from visemeface.runtime import configure\n"
            "configure()\n"
            "import numpy as np, numba\n"
            "from visemeface.physics.hexmesh import box_mesh\n"
            "from visemeface.physics.materials import SOFT_TISSUE\n"
            "from visemeface.physics.tled import TLEDSolver\n"
            "m = box_mesh((12, 10, 10), (0.012, 0.01, 0.01))\n"
            "s = TLEDSolver(m, SOFT_TISSUE, dt=1e-5, fixed=m.node_sets['xmin'], parallel=True)\n"
            "list(s.run(20, output_every=20))\n"
            "print(numba.threading_layer())\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "GOMP_"))}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True,
                         timeout=120)
    assert out.stdout.strip().splitlines()[-1] in runtime.THREADING_LAYERS


def _blas_threads_after_configure(env):
    code = ("import json\n"
            "from threadpoolctl import threadpool_info, threadpool_limits\n"
            "import visemeface.physics.simulation, numpy\n"
            "threadpool_limits(2, user_api='blas')\n"
            "before = [p['num_threads'] for p in threadpool_info() if p['user_api'] == 'blas']\n"
            "from visemeface.runtime import configure\n"
            "configure()\n"
            "after = [p['num_threads'] for p in threadpool_info() if p['user_api'] == 'blas']\n"
            "print(json.dumps([before, after]))\n")
    env = {**{k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "GOMP_"))
              and k not in runtime.BLAS_THREAD_VARIABLES}, **env}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True,
                         timeout=120)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_configure_caps_the_blas_pool_at_one_thread_and_importing_does_not():
    # An OpenBLAS pool spinning after a matrix product held the core numba's worker needs (issue 17).
    before, after = _blas_threads_after_configure({})
    assert before and all(n == 2 for n in before)
    assert after and all(n == 1 for n in after)


def test_configure_keeps_a_blas_pool_size_the_user_set():
    before, after = _blas_threads_after_configure({"OPENBLAS_NUM_THREADS": "2"})
    assert before == after and all(n == 2 for n in after)


def test_faster_thread_count_keeps_the_count_that_ran_faster():
    import time

    import numba
    most = numba.config.NUMBA_NUM_THREADS
    if most < 2:
        import pytest
        pytest.skip("one core: nothing to choose")
    before = numba.get_num_threads()
    try:
        # a trial that is slower on more threads (a busy machine), then one that is faster
        assert runtime.faster_thread_count(lambda: time.sleep(0.002 * numba.get_num_threads()), most) == 1
        assert numba.get_num_threads() == 1
        assert runtime.faster_thread_count(lambda: time.sleep(0.004 / numba.get_num_threads()), most) == most
        assert numba.get_num_threads() == most
        assert runtime.faster_thread_count(lambda: None, 1) == 1
    finally:
        numba.set_num_threads(before)


def test_the_threading_layer_is_found_without_importing_numba_and_agrees_with_its_import(monkeypatch):
    """Finding OpenMP imported numba (a fifth of a second) in every command, even one refusing its input."""
    monkeypatch.delenv("NUMBA_THREADING_LAYER", raising=False)
    code = ("import sys, json\nfrom visemeface import runtime\nlayer = runtime.threading_layer()\n"
            "seen = 'numba' in sys.modules\ntry:\n    from numba.np.ufunc import omppool\n    real = 'omp'\n"
            "except ImportError:\n    real = 'workqueue'\nprint(json.dumps([layer, real, seen]))")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_THREADING_LAYER"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    layer, real, seen = json.loads(out.stdout.strip().splitlines()[-1])
    assert layer == real and not seen


def test_a_refused_command_imports_neither_the_solver_nor_numba(tmp_path):
    code = ("import sys\nfrom visemeface.cli import main\n"
            "assert main(['speak', 'nothing-here.txt', '-o', 'x.mp4']) == 2\n"
            "print(sorted(m for m in ('numba', 'scipy', 'visemeface.physics.simulation') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout

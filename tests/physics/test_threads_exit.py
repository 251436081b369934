"""A 2-thread run of the compiled kernels ends its process promptly (issue 17).

With numba's TBB layer (picked whenever libtbb is installed, as it is on many
machines) 2-thread processes hung 22-140 s at exit after the work was done;
:func:`visemeface.runtime.configure` pins OpenMP (else workqueue). This runs the
parallel TLED kernels on 2 threads in a fresh process, the way the command line
configures it, and times the gap between the work's last line and the exit.
"""

import subprocess
import sys
import time

import pytest

SCRIPT = r"""
import sys, time
from visemeface.runtime import configure
info = configure(threads=2)
import numba, numpy as np
from visemeface.physics.hexmesh import box_mesh
from visemeface.physics.materials import SOFT_TISSUE
from visemeface.physics.tled import TLEDSolver
m = box_mesh((10, 10, 10), (0.01, 0.01, 0.01))
fixed = m.node_sets["zmin"]
solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-5, damping=80.0, fixed=fixed, parallel=True)
u0 = np.zeros((m.n_nodes, 3)); u0[:, 2] = 0.01 * m.nodes[:, 2]
for frame in solver.run(300, output_every=300, initial_displacement=u0):
    pass
print(numba.threading_layer(), numba.get_num_threads(), info["threading_layer"], flush=True)
print("done", flush=True)
"""


@pytest.mark.slow
def test_a_two_thread_run_exits_promptly_after_finishing_its_work(prompt_s):
    """TBB's pool held processes 22-140 s at exit; bounded relative to this machine's interpreter start."""
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    lines = []
    for line in proc.stdout:
        lines.append(line.strip())
        if line.strip() == "done":
            finished = time.monotonic()
            break
    else:
        proc.wait(60)
        pytest.fail(f"the run failed: {proc.stderr.read()[-2000:]}")
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the process still ran 30 s after finishing its work")
    gap = time.monotonic() - finished
    layer, threads, pinned = lines[-2].split()
    assert proc.returncode == 0, proc.stderr.read()[-2000:]
    assert layer == pinned and layer in ("omp", "workqueue")     # not TBB
    assert int(threads) == 2
    assert gap < prompt_s, f"exit took {gap:.1f} s after the work was done"

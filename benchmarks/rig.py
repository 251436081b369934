"""Muscle rig speed on the default face: poses per second (JSON lines).

Target (issue 3): >= 2,000 poses/s for ``rig.pose(vector)`` so that posing is
never the bottleneck of rendering. Run::

    PYTHONPATH=src python benchmarks/rig.py
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np


def rate(fn, n: int) -> float:
    fn()
    best = 0.0
    for _ in range(3):
        t = time.perf_counter()
        for _ in range(n):
            fn()
        best = max(best, n / (time.perf_counter() - t))
    return best


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig

    face = default_face()
    t = time.perf_counter()
    rig = MuscleRig.from_file(face)
    build = time.perf_counter() - t
    rng = np.random.default_rng(0)
    A = rng.uniform(0, 1, (256, len(rig.names))) * (rig.ranges[:, 1] - rig.ranges[:, 0]) + rig.ranges[:, 0]
    it = iter(range(10**9))
    vec = lambda: rig.pose(A[next(it) % 256])  # noqa: E731
    mapping = {n: float(v) for n, v in zip(rig.names, A[0])}
    common = {"vertices": face.n_vertices, "muscles": len(rig.muscles), "cpus": os.cpu_count()}
    print(json.dumps({"benchmark": "rig_build", "seconds": round(build, 4), **common}))
    r = rate(vec, 2000)
    print(json.dumps({"benchmark": "pose_vector", "poses_per_s": round(r), "target": 2000,
                      "ok": r >= 2000, **common}))
    print(json.dumps({"benchmark": "pose_mapping", "poses_per_s": round(rate(lambda: rig.pose(mapping), 1000)),
                      **common}))
    t = time.perf_counter()
    for _ in range(5):
        rig.poses(A)
    batch = 5 * len(A) / (time.perf_counter() - t)
    print(json.dumps({"benchmark": "poses_batch_256", "poses_per_s": round(batch), **common}))


if __name__ == "__main__":
    main()

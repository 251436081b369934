"""``visemeface batch`` on a local Dask cluster: 20 GRID clips with 1 worker and with 2.

Prints one JSON line per worker count and a summary line with the speed-up::

    PYTHONPATH=src python benchmarks/batch.py [--clips 20] [--workers 1 2] [--size 256] [--outputs video]

Each worker count gets a fresh local cluster (one thread per worker). ``start_s``
is the cluster's start; then one clip per worker is made to warm the workers
(imports, the rig, numba's cache, the GL context), and ``wall_s`` times the
``--clips`` clips alone. ``speedup`` = wall time with the fewest workers /
wall time with the most. Target (issue 19): >= 1.7 for 2 workers vs 1 on an
idle 2-core machine. The 1-minute load average before and after each run is
printed: on a shared machine the figure says more about the neighbours than
about the batch.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))


def one(n_workers: int, clips: int, settings: dict, workdir: Path) -> dict:
    import visemeface.batch as vb

    vb.write_grid_manifest(workdir / "warm.csv", n_workers, seed=1, force=True)
    vb.write_grid_manifest(workdir / "jobs.csv", clips, seed=0, force=True)
    warm = vb.read_manifest(workdir / "warm.csv", settings)
    jobs = vb.read_manifest(workdir / "jobs.csv", settings)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    client = vb.local_client(n_workers)
    start = time.perf_counter() - t0
    try:
        vb.run(warm, workdir / f"warm{n_workers}", client=client, show_progress=False)
        t1 = time.perf_counter()
        rows = vb.run(jobs, workdir / f"out{n_workers}", client=client, show_progress=False)
        wall = time.perf_counter() - t1
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    done = sum(r["status"] == "done" for r in rows)
    frames = sum(json.loads((workdir / f"out{n_workers}" / r["clip"] / "clip.json").read_text())["frames"]
                 for r in rows if r["status"] == "done")
    return {"bench": "batch", "workers": n_workers, "clips": clips, "done": done, "frames": frames,
            "size": settings["size"], "outputs": settings["outputs"], "start_s": round(start, 2),
            "wall_s": round(wall, 2), "clips_per_s": round(done / wall, 3),
            "clip_s_mean": round(sum(float(r["seconds"]) for r in rows) / max(done, 1), 3),
            "load_before": round(load0, 2), "load_after": round(os.getloadavg()[0], 2),
            "cpus": os.cpu_count()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clips", type=int, default=20)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--outputs", default="video")
    args = ap.parse_args()
    from visemeface.runtime import configure

    configure()
    settings = {"size": args.size, "fps": args.fps, "outputs": args.outputs}
    results = []
    with tempfile.TemporaryDirectory(prefix="vf-bench-batch-") as tmp:
        for n in args.workers:
            res = one(n, args.clips, settings, Path(tmp))
            print(json.dumps(res), flush=True)
            results.append(res)
    lo, hi = min(results, key=lambda r: r["workers"]), max(results, key=lambda r: r["workers"])
    print(json.dumps({"bench": "batch", "summary": True, "clips": args.clips,
                      "workers": [lo["workers"], hi["workers"]],
                      "speedup": round(lo["wall_s"] / hi["wall_s"], 3), "target": 1.7}))


if __name__ == "__main__":
    main()

"""Headless rendering speed of the default face: frames per second (JSON lines).

Target (issue 2): >= 200 frames/s at 512x512 with the vertex positions
changing every frame (normals recomputed, vertex buffer rewritten, frame read
back to a numpy array), on the 2-core CI machine with Mesa llvmpipe. Also
reports the parts of a frame and the rate without multisampling. Run::

    PYTHONPATH=src python benchmarks/render.py [--frames 200] [--size 512]

Figures taken while other processes load the CPUs are lower; each line says
the load average at the time, and the CPU time per frame summed over the
process's threads (less disturbed by other load than wall-clock time):
``fps_if_cpu_bound_on_2_cores = 2000 / cpu_ms_per_frame`` is the rate two idle
cores would reach if the work spread over both (an upper estimate).
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np


def _moving(face, n):
    """``n`` distinct poses: the lower lip and jaw swing down and back up."""
    jaw = face.regions["jaw"]
    w = np.exp(-(np.linalg.norm(face.vertices[jaw, :2], axis=1) / 0.05) ** 2)
    for k in range(n):
        v = face.vertices.copy()
        v[jaw, 1] -= 0.012 * w * 0.5 * (1 - np.cos(2 * np.pi * k / 60))
        yield v


def _rate(renderer, poses):
    """(frames per wall-clock second, CPU milliseconds per frame over all threads)."""
    renderer.render(poses[0])
    t, c = time.perf_counter(), time.process_time()
    for v in poses:
        renderer.render(v)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    return len(poses) / wall, 1000 * cpu / len(poses)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--size", type=int, default=512)
    args = parser.parse_args(argv)

    import moderngl

    from visemeface.face.procedural import default_face
    from visemeface.render.culling import draw_sides
    from visemeface.render.renderer import Renderer

    face = default_face()
    poses = list(_moving(face, args.frames))
    common = {"vertices": face.n_vertices, "triangles": len(face.triangles), "size": args.size,
              "frames": args.frames, "cpus": os.cpu_count()}
    for samples in (4, 0):
        with Renderer(face, size=args.size, samples=samples) as r:
            t = time.perf_counter()
            r.render()
            first = time.perf_counter() - t
            fps, cpu_ms = _rate(r, poses)
            with r.ctx:
                gl_renderer = r.ctx.info["GL_RENDERER"]
            rec = {"benchmark": "render_changing_vertices", "msaa_samples": r.samples, "fps": round(fps, 1),
                   "ms_per_frame": round(1000 / fps, 2), "cpu_ms_per_frame": round(cpu_ms, 2),
                   "fps_if_cpu_bound_on_2_cores": round(2000 / cpu_ms, 1), "target_fps": 200, "ok": fps >= 200,
                   "first_frame_s": round(first, 3), "renderer": gl_renderer,
                   "load_avg_1min": round(os.getloadavg()[0], 2), **common}
            print(json.dumps(rec), flush=True)
            if samples:
                # where the time goes (same renderer, same poses)
                n = len(poses)
                t = time.perf_counter()
                for v in poses:
                    r._normals(v, dtype=np.float32)
                normals = (time.perf_counter() - t) / n
                with r.ctx:
                    t = time.perf_counter()
                    for _ in range(n):
                        r.fbo_ms.use()
                        r.ctx.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
                        draw_sides(r.ctx, r.vao, r._split[0], r._split[2], front=r.vao_front)  # as render() does
                        r.ctx.copy_framebuffer(r.fbo, r.fbo_ms)
                    r.ctx.finish()
                    draw = (time.perf_counter() - t) / n
                    t = time.perf_counter()
                    for _ in range(n):
                        r.fbo.read(components=3, alignment=1)
                    read = (time.perf_counter() - t) / n
                print(json.dumps({"benchmark": "render_parts_ms", "normals": round(1000 * normals, 3),
                                  "draw_and_resolve": round(1000 * draw, 3), "readback": round(1000 * read, 3),
                                  "load_avg_1min": round(os.getloadavg()[0], 2), **common}), flush=True)


if __name__ == "__main__":
    main()

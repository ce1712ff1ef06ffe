#!/usr/bin/env python3
"""Ray throughput of strata against Embree (embreex) on the same rays.

    bench_embree.py MESH RAYS.bin [--strata target/release/strata] [--repeats 3]

RAYS.bin comes from `strata rays` (with its RAYS.bin.json naming the kind of
each run of rays). For every kind, both engines answer closest-hit and
occlusion queries on one thread: strata through `strata trace --threads 1`
(its own timing of the trace phase, after load and BVH build), Embree through
embreex after a warm-up query has built its BVH. Each measurement is the
median of --repeats runs, and the table prints Mrays/s per engine and the
ratio strata / Embree (above 1: strata is faster).

These machines are shared and noisy: compare the ratios of one run, not
absolute figures across runs.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
from validate_embree import InputError, load_mesh, read_groups, read_ray_file  # noqa: E402


def embree_scene(vertices, triangles):
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, vertices, triangles.astype(np.int32))
    return scene


def time_embree(scene, rays, query, repeats):
    origins = np.ascontiguousarray(rays[:, 0:3])
    directions = np.ascontiguousarray(rays[:, 3:6])
    times = []
    for _ in range(repeats):
        dists = rays[:, 7].copy()
        start = time.perf_counter()
        if query == "closest":
            scene.run(origins, directions, dists=dists, output=1)
        else:
            scene.run(origins, directions, dists=dists, query="OCCLUDED")
        times.append(time.perf_counter() - start)
    return len(rays) / statistics.median(times) / 1e6


def time_strata(strata, mesh, rays, query, repeats):
    with tempfile.TemporaryDirectory() as tmp:
        rays_path = os.path.join(tmp, "rays.bin")
        rays.astype("<f4").tofile(rays_path)
        args = [strata, "trace", mesh, "--rays", rays_path, "--hits", os.path.join(tmp, "hits.bin"), "--threads", "1"]
        if query == "occlusion":
            args.append("--occlusion")
        rates = []
        for _ in range(repeats):
            out = subprocess.run(args, capture_output=True, text=True)
            if out.returncode != 0:
                raise InputError(mesh, f"strata trace failed: {out.stderr.strip()}")
            # "... in 0.123 s = 4.56 Mrays/s on 1 threads ..."
            rate = out.stdout.split(" Mrays/s")[0].rsplit("= ", 1)[1]
            rates.append(float(rate))
        return statistics.median(rates)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("mesh", help="OBJ mesh (the same file strata traced)")
    p.add_argument("rays", help="RAYS.bin from `strata rays`")
    p.add_argument("--strata", default="target/release/strata", help="the strata executable")
    p.add_argument("--repeats", type=int, default=3, help="runs per measurement; the median is kept")
    a = p.parse_args(argv)
    try:
        vertices, triangles = load_mesh(a.mesh)
        rays = read_ray_file(a.rays)
        groups, _ = read_groups(a.rays, len(rays), None)
        scene = embree_scene(vertices, triangles)
        scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), output=1)  # build the BVH
        print(f"{'kind':<10} {'query':<10} {'rays':>8} {'strata':>10} {'embree':>10} {'strata/embree':>14}")
        for kind, first, count, _ in groups:
            sub = rays[first:first + count]
            for query in ("closest", "occlusion"):
                s = time_strata(a.strata, a.mesh, sub, query, a.repeats)
                e = time_embree(scene, sub, query, a.repeats)
                print(f"{kind:<10} {query:<10} {count:>8} {s:>10.2f} {e:>10.2f} {s / e:>13.2f}x")
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

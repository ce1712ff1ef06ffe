#!/usr/bin/env python3
"""Ray throughput of strata against Embree (embreex) on the same rays.

    bench_embree.py MESH [RAYS.bin] [MESH [RAYS.bin] ...] [-n 100000] [--seed 1]
                    [--strata target/release/strata] [--repeats 3] [--csv embree_bench.csv]

Each MESH (OBJ or PLY) is traced with the rays of the RAYS.bin that follows
it, or, if none follows, with `strata rays all MESH -n N --seed S` (N rays
of each kind: random, camera, grazing, edges, inside); RAYS.bin.json names
the kind of each run of rays. For every mesh, kind and query (closest hit,
occlusion) both engines trace the same rays on one thread: strata through
`strata trace --threads 1 --repeats 3` (its own timing of the trace phase,
after load and BVH build, the median of three passes in one process, as
Embree's passes share one process), Embree through embreex's single-threaded loop after a
warm-up query has built its BVH. Each measurement is the median of
--repeats runs, strata's and Embree's alternating. One row per mesh x kind x query: Mrays/s per engine and the
ratio strata / Embree (above 1: strata is faster), then the geometric mean
of the ratios per mesh; the rows are also saved as CSV.

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


def embree_rate(scene, rays, query):
    """Mrays/s of one embreex pass over `rays`."""
    origins = np.ascontiguousarray(rays[:, 0:3])
    directions = np.ascontiguousarray(rays[:, 3:6])
    dists = rays[:, 7].copy()
    start = time.perf_counter()
    if query == "closest":
        scene.run(origins, directions, dists=dists, output=1)
    else:
        scene.run(origins, directions, dists=dists, query="OCCLUDED")
    return len(rays) / (time.perf_counter() - start) / 1e6


def strata_rate(args, mesh):
    """Mrays/s that one `strata trace` run reports for its trace phase."""
    out = subprocess.run(args, capture_output=True, text=True)
    if out.returncode != 0:
        raise InputError(mesh, f"strata trace failed: {out.stderr.strip()}")
    # "... in 0.123 s = 4.56 Mrays/s on 1 threads ..."
    return float(out.stdout.split(" Mrays/s")[0].rsplit("= ", 1)[1])


def time_both(strata, mesh, scene, rays, query, repeats):
    """Median Mrays/s of strata and of Embree, their runs alternating so
    that a change in the machine's load falls on both."""
    with tempfile.TemporaryDirectory() as tmp:
        rays_path = os.path.join(tmp, "rays.bin")
        rays.astype("<f4").tofile(rays_path)
        args = [strata, "trace", mesh, "--rays", rays_path, "--hits", os.path.join(tmp, "hits.bin"), "--threads", "1", "--repeats", "3"]
        if query == "occlusion":
            args.append("--occlusion")
        s, e = [], []
        for _ in range(repeats):
            s.append(strata_rate(args, mesh))
            e.append(embree_rate(scene, rays, query))
        return statistics.median(s), statistics.median(e)


def make_rays(strata, mesh, n, seed, workdir):
    """RAYS.bin of every kind for `mesh`, written by `strata rays all`."""
    path = os.path.join(workdir, f"rays-{len(os.listdir(workdir))}.bin")
    out = subprocess.run([strata, "rays", "all", mesh, "-n", str(n), "--seed", str(seed), "-o", path, "--quiet"], capture_output=True, text=True)
    if out.returncode != 0:
        raise InputError(mesh, f"strata rays failed: {out.stderr.strip()}")
    return path


def pairs(items):
    """[(MESH, RAYS.bin or None)] from the positional arguments."""
    out = []
    for item in items:
        # Anything but a mesh is a ray file (`strata rays -o` takes any name).
        if not item.lower().endswith((".obj", ".ply")):
            if not out or out[-1][1] is not None:
                raise InputError(item, "a ray file must follow the mesh it was made for")
            out[-1] = (out[-1][0], item)
        else:
            out.append((item, None))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="MESH [RAYS.bin]", help="meshes (OBJ or PLY), each optionally followed by its ray file")
    p.add_argument("-n", type=int, default=100000, help="rays of each kind to make for a mesh without a ray file (default 100000)")
    p.add_argument("--seed", type=int, default=1, help="seed of the rays made here (default 1)")
    p.add_argument("--strata", default="target/release/strata", help="the strata executable")
    p.add_argument("--repeats", type=int, default=3, help="runs per measurement; the median is kept")
    p.add_argument("--csv", default="embree_bench.csv", help="where to save the rows (default embree_bench.csv)")
    a = p.parse_args(argv)
    rows = []
    try:
        jobs = pairs(a.inputs)
        print(f"{'mesh':<18} {'tris':>9} {'kind':<8} {'query':<10} {'rays':>7} {'strata':>8} {'embree':>8} {'strata/embree':>14}")
        with tempfile.TemporaryDirectory() as workdir:
            for mesh, rays_path in jobs:
                vertices, triangles = load_mesh(mesh)
                rays_path = rays_path or make_rays(a.strata, mesh, a.n, a.seed, workdir)
                rays = read_ray_file(rays_path)
                groups, _ = read_groups(rays_path, len(rays), None)
                scene = embree_scene(vertices, triangles)
                scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), output=1)  # build the BVH
                name = os.path.basename(mesh)
                ratios = []
                for kind, first, count, _ in groups:
                    sub = rays[first:first + count]
                    for query in ("closest", "occlusion"):
                        s, e = time_both(a.strata, mesh, scene, sub, query, a.repeats)
                        ratios.append(s / e)
                        rows.append((name, len(triangles), kind, query, count, s, e))
                        print(f"{name:<18} {len(triangles):>9} {kind:<8} {query:<10} {count:>7} {s:>8.2f} {e:>8.2f} {s / e:>13.2f}x", flush=True)
                geomean = float(np.exp(np.mean(np.log(ratios))))
                print(f"{name:<18} {len(triangles):>9} {'all':<8} {'geomean':<10} {'':>7} {'':>8} {'':>8} {geomean:>13.2f}x", flush=True)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    with open(a.csv, "w") as f:
        f.write("mesh,triangles,kind,query,rays,threads,strata_mrays_per_s,embree_mrays_per_s,strata_over_embree\n")
        for name, tris, kind, query, count, s, e in rows:
            f.write(f"{name},{tris},{kind},{query},{count},1,{s:.4f},{e:.4f},{s / e:.4f}\n")
    print(f"-> {a.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

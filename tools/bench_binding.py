#!/usr/bin/env python3
"""What the Python binding costs: strata_rt's queries against `strata trace`
on the same rays, the two alternating round by round.

    tools/.venv/bin/python tools/bench_binding.py [--strata target/release/strata]
        [--mesh assets/dragon.ply] [--rays 1000000] [--threads 2] [--rounds 5]
        [--calls 7]

Issue 59 asks the package to run within 10% of `strata trace` on the same
rays. Both walk the same tree (`--bvh-quality auto`, medium, in both) with
the same code; what the package adds is reading the rays from numpy
arrays, writing its answers into fresh ones, and handing each chunk of
65,536 rays to its threads. This measures that and nothing else:

* the rays are `tools/bench_python.py`'s (--rays random rays about the
  mesh, seed 7), written once to a ray file for `strata trace`;
* each round runs `strata trace MESH --rays R --threads T --repeats CALLS`
  (its own timing of the tracing alone: the median of its passes, the
  load and the build excluded), for closest hits and with `--occlusion`,
  then, in this process, CALLS calls of each query on a `strata_rt.Mesh`
  built once beforehand (the median call, from the call to the returned
  arrays): `intersect` asking for ("t", "prim") and for ("t", "prim",
  "u", "v"), the four quantities the trace writes, and `occluded`;
* rounds alternate, so a change in the machine's load falls on both;
  each ratio is package ÷ trace in Mrays/s within one round, and the
  summary gives each ratio's median over rounds and its range.

Needs strata_rt importable (`maturin develop --release --manifest-path
python/Cargo.toml` into the interpreter that runs this) and a `strata`
binary built from the same checkout (`cargo build --release`).
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from bench_python import cpu_name, random_rays  # noqa: E402

RATE = re.compile(r"= ([0-9.]+) Mrays/s")


def fail(message):
    print(f"bench_binding.py: {message}", file=sys.stderr)
    sys.exit(2)


def trace_rate(strata, mesh, rays, threads, repeats, occlusion):
    """Mrays/s that `strata trace` reports for the ray file."""
    with tempfile.NamedTemporaryFile(suffix=".hits") as hits:
        cmd = [strata, "trace", mesh, "--rays", rays, "--hits", hits.name,
               "--threads", str(threads), "--repeats", str(repeats)]
        if occlusion:
            cmd.append("--occlusion")
        run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        fail(f"{' '.join(cmd)} failed:\n{run.stderr.strip()}")
    found = RATE.search(run.stdout + run.stderr)
    if not found:
        fail(f"no rate in the output of {' '.join(cmd)}:\n{run.stdout}{run.stderr}")
    return float(found.group(1))


def call_rate(query, n, calls):
    """Mrays/s of the median of `calls` calls of `query`."""
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        query()
        times.append(time.perf_counter() - start)
    return n / statistics.median(times) / 1e6


def main():
    ap = argparse.ArgumentParser(
        description="strata_rt's queries against `strata trace` on the same rays "
        "(what the Python binding costs; issue 59's 'within 10%').")
    ap.add_argument("--strata", default=os.path.join(ROOT, "target", "release", "strata"),
                    help="the strata binary (default: target/release/strata)")
    ap.add_argument("--mesh", default=os.path.join(ROOT, "assets", "dragon.ply"),
                    help="the mesh (default: assets/dragon.ply; tools/fetch-assets fetches it)")
    ap.add_argument("--rays", type=int, default=1_000_000,
                    help="random rays about the mesh (default: 1000000)")
    ap.add_argument("--threads", type=int, default=2,
                    help="threads for both (default: 2)")
    ap.add_argument("--rounds", type=int, default=5,
                    help="alternating rounds; medians are taken over them (default: 5)")
    ap.add_argument("--calls", type=int, default=7,
                    help="calls of each query a round, and the trace's --repeats (default: 7)")
    args = ap.parse_args()
    for path, what in [(args.strata, "cargo build --release builds it"),
                       (args.mesh, "tools/fetch-assets fetches the dragon")]:
        if not os.path.exists(path):
            fail(f"{path}: no such file ({what})")
    for name in ["rays", "threads", "rounds", "calls"]:
        if getattr(args, name) < 1:
            fail(f"--{name} must be at least 1")
    try:
        import strata_rt
    except ImportError as e:
        fail(f"cannot import strata_rt ({e}); build it with maturin develop --release "
             "--manifest-path python/Cargo.toml")

    # The mesh as strata's loader numbers it: face i is triangle i of the file
    # for both, so the package's hits are the trace's.
    loaded = strata_rt.Mesh.load(args.mesh)
    mesh = strata_rt.Mesh(loaded.vertices, loaded.faces)
    o, d = random_rays(loaded.vertices, args.rays)
    n, threads, calls = len(o), args.threads, args.calls
    queries = {
        '("t", "prim")': (False, lambda: mesh.intersect(o, d, threads=threads, fields=("t", "prim"))),
        '("t", "prim", "u", "v")': (False, lambda: mesh.intersect(
            o, d, threads=threads, fields=("t", "prim", "u", "v"))),
        "occluded": (True, lambda: mesh.occluded(o, d, threads=threads)),
    }
    print(f"{os.path.basename(args.mesh)}: {len(loaded.faces)} triangles, {n} random rays, "
          f"{threads} threads, {args.rounds} rounds of {calls} calls; CPU {cpu_name()}")
    ratios = {name: [] for name in queries}
    with tempfile.TemporaryDirectory() as work:
        rays = os.path.join(work, "rays.bin")
        records = np.zeros((n, 8), np.float32)
        records[:, :3], records[:, 3:6], records[:, 7] = o, d, np.inf
        records.tofile(rays)
        for query in queries.values():
            query[1]()  # the pools started and the pages touched once
        for r in range(args.rounds):
            trace = {occ: trace_rate(args.strata, args.mesh, rays, threads, calls, occ)
                     for occ in (False, True)}
            cells = []
            for name, (occ, query) in queries.items():
                rate = call_rate(query, n, calls)
                ratios[name].append(rate / trace[occ])
                cells.append(f"{name} {rate:.2f} / {trace[occ]:.2f} = {rate / trace[occ]:.3f}")
            print(f"round {r + 1}: " + "; ".join(cells), flush=True)
    print("\npackage ÷ strata trace (Mrays/s within a round), median over rounds [range]:")
    for name, values in ratios.items():
        print(f"  {name:26s} {statistics.median(values):.3f}  [{min(values):.3f} to {max(values):.3f}]")


if __name__ == "__main__":
    main()

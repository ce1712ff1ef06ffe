#!/usr/bin/env python3
"""Ray throughput of strata against Embree's own C API on the same rays.

    bench_embree.py MESH [RAYS.bin] [MESH [RAYS.bin] ...] [-n 100000] [--seed 1]
                    [--strata target/release/strata] [--threads 1] [--repeats 3]
                    [--mode stream|single|both] [--csv embree_bench.csv]

Each MESH (OBJ or PLY) is traced with the rays of the RAYS.bin that follows
it, or, if none follows, with `strata rays all MESH -n N --seed S` (N rays
of each kind: random, camera, grazing, edges, inside); RAYS.bin.json names
the kind of each run of rays. For every mesh, kind and query (closest hit,
occlusion) the engines trace the same rays on --threads N threads (default
1; 0: every core this process may run on, a count then passed to both):

How the rays are handed over (--mode):

* `stream` (default): each engine is given chunks of 256 rays to trace as
  it finds best: `strata trace`, which sends groups of eight nearly
  parallel rays through one point as packets and keeps several of the
  other rays in flight on each thread on a mesh that outgrows the caches,
  against Embree's stream API
  (rtcIntersect1M / rtcOccluded1M, which traces each eight consecutive
  rays with its packet kernel, dropping to single rays as they part);
* `single`: one ray at a time, `strata trace --one-at-a-time` against
  rtcIntersect1 / rtcOccluded1 in a plain loop;
* `both`: each row measured both ways, one at a time and in streams, with
  a geometric mean per mode.

Before its rows, a line names the kernel strata walks rays in (avx2 or
avx512: `STRATA_SIMD`, docs/cli.md), and each mesh gets a line saying
which tree and which one-ray kernel Embree chose on this CPU (its verbose output: BVH8 or BVH4, and the
ISA of the kernel, avx2 or avx512), since a ratio is against that choice.

The engines:

* strata through `strata trace --threads N --repeats 3` (its own timing of
  the trace phase, after load and BVH build: the median of three passes in
  one process), with RAYON_NUM_THREADS=N so that its BVH build runs on N
  threads too;
* Embree through tools/embree/embree_trace (compiled here on demand with
  `make -C tools/embree`, into target/embree/), a C program on Embree 3's
  API on N threads taking chunks of 256 rays, the scene built at RTC_BUILD_QUALITY_HIGH on N
  threads, once in default mode and once with RTC_SCENE_FLAG_ROBUST. Each
  harness builds once and then answers pass requests (--serve); a
  measurement is the median of three passes, as strata's is.

strata's 8-ray packets against rtcIntersect8 / rtcOccluded8 are compared
by `strata bench`.

Each row's figure is the median of --repeats such measurements, strata's and
Embree's alternating, so that a change in the machine's load falls on all.
One row per mesh x kind x query: Mrays/s per engine and the ratios
strata / Embree (above 1: strata is faster), then the geometric mean of the
ratios per mesh, and per mesh the BVH build times (strata's, Embree's
high-quality build in each mode) and Embree's bytes per triangle (its own
allocations, through its memory monitor). The rows are saved as CSV, with
the thread count; with N other than 1 the table's first line says it too.

If the harness cannot be built (no C compiler or no libembree-dev), one line
says so and only strata's column is measured. embreex is not used here: it
serves tools/validate_embree.py, which checks answers, not speed.

These machines are shared and noisy: compare the ratios of one run, not
absolute figures across runs.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
from validate_embree import InputError, load_mesh, read_groups, read_ray_file  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PASSES = 3
KERNELS_SEEN = set()


def build_harness():
    """Path of the compiled harness, or None after one line saying why not."""
    out = os.path.join(ROOT, "target", "embree")
    try:
        r = subprocess.run(["make", "-s", "-C", os.path.join(ROOT, "tools", "embree"), f"OUT={out}"], capture_output=True, text=True)
    except OSError as e:
        r = None
        why = f"cannot run make: {e.strerror}"
    if r is not None and r.returncode == 0:
        return os.path.join(out, "embree_trace")
    if r is not None:
        text = (r.stderr + r.stdout).splitlines()
        lines = [line for line in text if "error" in line.lower() and not line.startswith("make")] or text or ["make failed"]
        why = lines[0].strip()
    print(f"Embree column skipped: tools/embree/embree_trace does not build (apt-get install libembree-dev): {why}", flush=True)
    return None


def write_tris(vertices, triangles, path):
    """MESH.tris for the harness: u32 vertex and triangle counts, f32 xyz, u32 indices."""
    with open(path, "wb") as f:
        np.array([len(vertices), len(triangles)], "<u4").tofile(f)
        np.ascontiguousarray(vertices, "<f4").tofile(f)
        np.ascontiguousarray(triangles, "<u4").tofile(f)


def threads_word(n):
    return f"{n} thread" + ("" if n == 1 else "s")


class Harness:
    """One embree_trace --serve process: the scene built once, passes on request."""

    def __init__(self, exe, tris, rays, robust, threads):
        self.threads = threads
        args = [exe, tris, rays, "--serve", "--verbose", "--threads", str(threads)] + (["--robust"] if robust else [])
        # Embree's verbose report of its build goes to stderr (--serve --verbose).
        with tempfile.TemporaryFile("w+") as report:
            self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=report, text=True)
            ready = self.proc.stdout.readline().split()
            report.seek(0)
            self.tree = embree_tree(report.read())
        if not ready or ready[0] != "ready":
            raise InputError(tris, f"embree_trace did not start ({' '.join(args)})")
        self.triangles = int(ready[1])
        self.build_s = float(ready[2])
        self.bytes = int(ready[3])

    def rate(self, first, count, query, mode):
        """Mrays/s: the median of PASSES passes (`mode`: single or stream) over rays first..first + count."""
        times = []
        for _ in range(PASSES):
            self.proc.stdin.write(f"{first} {count} {query} {mode} {self.threads}\n")
            self.proc.stdin.flush()
            reply = self.proc.stdout.readline().split()
            if len(reply) != 2:
                raise InputError("embree_trace", f"unexpected reply {reply}")
            times.append(float(reply[0]))
        return count / statistics.median(times) / 1e6

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def embree_tree(report):
    """'BVH8<triangle4> (SAH 16.42: nodes 12.68, leaves 3.74), one-ray kernel
    avx512::BVH8Triangle4Intersector1Moeller' from Embree's verbose report:
    the tree, its statistics (what `strata trace --tree` prints in the same
    measure) and the kernel."""
    tree = kernel = "?"
    sah = {}
    for line in report.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "building":
            tree = words[1]
        if len(words) == 3 and words[0] == "intersector1" and words[1] == "=":
            kernel = words[2]
        # "  total            : sah =  16.418 (100.00%), ..."
        if len(words) >= 5 and words[0] in ("total", "getAABBNodes", "leaves") and words[2:4] == ["sah", "="]:
            sah.setdefault(words[0], words[4])
    if "total" in sah:
        tree += f" (SAH {float(sah['total']):.2f}: nodes {float(sah.get('getAABBNodes', 'nan')):.2f}, " \
                f"leaves {float(sah.get('leaves', 'nan')):.2f})"
    return f"{tree}, one-ray kernel {kernel}"


def strata_rate(args, mesh, threads):
    """(Mrays/s, BVH seconds) that one `strata trace` run on `threads` threads
    reports; a run with `--tree` has its tree line printed (strata's tree in
    the measure of Embree's own statistics, `embree_tree`)."""
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    out = subprocess.run(args, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise InputError(mesh, f"strata trace failed: {out.stderr.strip()}")
    # "... in 0.123 s = 4.56 Mrays/s on 1 thread (load 0.12 s, BVH 0.34 s) -> ..."
    if f" Mrays/s on {threads_word(threads)} (" not in out.stdout:
        raise InputError(mesh, f"strata trace did not run on {threads_word(threads)}: {out.stdout.strip()}")
    rate = float(out.stdout.split(" Mrays/s")[0].rsplit("= ", 1)[1])
    build = float(out.stdout.split("BVH ")[1].split(" s")[0])
    # "..., kernel avx2)": the instruction set strata walked in (STRATA_SIMD);
    # embree_trace, whose line this parses too, names none.
    kernel = out.stdout.split("kernel ")[1].split(")")[0] if "kernel " in out.stdout else None
    if kernel is not None and kernel not in KERNELS_SEEN:
        KERNELS_SEEN.add(kernel)
        print(f"# strata walks rays with its {kernel} kernel (STRATA_SIMD picks another)", flush=True)
    for line in out.stdout.splitlines():
        if line.startswith("tree: "):
            print(f"# {os.path.basename(mesh)}: strata built {line.removeprefix('tree: ')}", flush=True)
    return rate, build


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


def geomean(xs):
    return float(np.exp(np.mean(np.log(xs)))) if xs else float("nan")


def fmt(x, width, digits=2):
    return f"{x:>{width}.{digits}f}" if x is not None else f"{'-':>{width}}"


def bench_mesh(a, exe, mesh, rays_path, workdir, rows):
    vertices, triangles = load_mesh(mesh)
    rays_path = rays_path or make_rays(a.strata, mesh, a.n, a.seed, workdir)
    rays = read_ray_file(rays_path)
    groups, _ = read_groups(rays_path, len(rays), None)
    name = os.path.basename(mesh)
    harnesses = []
    if exe:
        tris = os.path.join(workdir, "mesh.tris")
        write_tris(vertices, triangles, tris)
        harnesses = [Harness(exe, tris, rays_path, robust, a.threads) for robust in (False, True)]
    modes = ("single", "stream") if a.mode == "both" else (a.mode,)
    ratios = {mode: ([], []) for mode in modes}
    builds = []
    try:
        if harnesses:
            print(f"# {name}: Embree built {harnesses[0].tree} (default mode); {harnesses[1].tree} (robust)", flush=True)
        tree = ["--tree"]  # strata's tree, shown by its first run
        for kind, first, count, _ in groups:
            sub = os.path.join(workdir, "kind.rays")
            rays[first:first + count].astype("<f4").tofile(sub)
            for query in ("closest", "occlusion"):
                for mode in modes:
                    args = [a.strata, "trace", mesh, "--rays", sub, "--hits", os.path.join(workdir, "hits.bin"), "--threads", str(a.threads), "--repeats", str(PASSES)]
                    if query == "occlusion":
                        args.append("--occlusion")
                    if mode == "single":
                        args.append("--one-at-a-time")
                    s, e = [], ([], [])
                    for _ in range(a.repeats):
                        rate, build = strata_rate(args + tree, mesh, a.threads)
                        tree = []
                        s.append(rate)
                        builds.append(build)
                        for h, out in zip(harnesses, e):
                            out.append(h.rate(first, count, query, mode))
                    s = statistics.median(s)
                    ed, er = (statistics.median(x) if x else None for x in e)
                    if ed:
                        ratios[mode][0].append(s / ed)
                        ratios[mode][1].append(s / er)
                    rows.append((name, len(triangles), kind, query, mode, count, s, ed, er))
                    print(f"{name:<16} {len(triangles):>8} {kind:<8} {query:<10} {mode:<6} {count:>8} {s:>7.2f} {fmt(ed, 7)} {fmt(er, 7)} "
                          f"{fmt(ed and s / ed, 8)}x {fmt(er and s / er, 8)}x", flush=True)
        if harnesses:
            for mode in modes:
                print(f"{name:<16} {len(triangles):>8} {'all':<8} {'geomean':<10} {mode:<6} {'':>8} {'':>7} {'':>7} {'':>7} "
                      f"{geomean(ratios[mode][0]):>7.2f}x {geomean(ratios[mode][1]):>7.2f}x", flush=True)
        line = f"# {name}: BVH build on {threads_word(a.threads)}: strata {statistics.median(builds):.2f} s"
        if harnesses:
            d, r = harnesses
            line += (f", Embree high quality {d.build_s:.2f} s (default mode), {r.build_s:.2f} s (robust); "
                     f"Embree {d.bytes / d.triangles:.1f} B/tri (default), {r.bytes / r.triangles:.1f} B/tri (robust); "
                     f"strata's B/tri: `strata bench`")
        print(line, flush=True)
    finally:
        for h in harnesses:
            h.close()


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="MESH [RAYS.bin]", help="meshes (OBJ or PLY), each optionally followed by its ray file")
    p.add_argument("-n", type=int, default=100000, help="rays of each kind to make for a mesh without a ray file (default 100000)")
    p.add_argument("--seed", type=int, default=1, help="seed of the rays made here (default 1)")
    p.add_argument("--strata", default="target/release/strata", help="the strata executable")
    p.add_argument("--threads", type=int, default=1, help="threads each engine traces (and builds) on; 0: all cores (default 1)")
    p.add_argument("--repeats", type=int, default=3, help="measurements per row; the median is kept")
    p.add_argument("--mode", choices=("stream", "single", "both"), default="stream",
                   help="stream: chunks of 256 rays (strata trace, rtcIntersect1M); single: one ray at a time "
                        "(strata trace --one-at-a-time, rtcIntersect1); both: each row both ways (default stream)")
    p.add_argument("--csv", default="embree_bench.csv", help="where to save the rows (default embree_bench.csv)")
    a = p.parse_args(argv)
    if a.threads < 0:
        p.error("--threads must be 0 (all cores) or more")
    # 0 becomes one count for both engines: the cores this process may run on.
    a.threads = a.threads or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count())
    rows = []
    try:
        jobs = pairs(a.inputs)
        exe = build_harness()
        how = {"stream": "streams of 256 rays (strata trace, rtcIntersect1M)",
               "single": "one ray at a time (strata trace --one-at-a-time, rtcIntersect1)",
               "both": "one ray at a time (single: strata trace --one-at-a-time, rtcIntersect1) and "
                       "streams of 256 rays (stream: strata trace, rtcIntersect1M)"}[a.mode]
        print(f"# {how} on {threads_word(a.threads)} per engine")
        print(f"{'mesh':<16} {'tris':>8} {'kind':<8} {'query':<10} {'mode':<6} {'rays':>8} {'strata':>7} {'embree':>7} {'robust':>7} {'s/embree':>8} {'s/robust':>8}")
        with tempfile.TemporaryDirectory() as workdir:
            for mesh, rays_path in jobs:
                bench_mesh(a, exe, mesh, rays_path, workdir, rows)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    with open(a.csv, "w") as f:
        f.write("mesh,triangles,kind,query,rays,threads,mode,strata_mrays_per_s,embree_mrays_per_s,embree_robust_mrays_per_s,"
                "strata_over_embree,strata_over_embree_robust\n")
        for name, tris, kind, query, mode, count, s, ed, er in rows:
            cols = [f"{x:.4f}" if x else "" for x in (ed, er, ed and s / ed, er and s / er)]
            f.write(f"{name},{tris},{kind},{query},{count},{a.threads},{mode},{s:.4f},{','.join(cols)}\n")
    print(f"-> {a.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""A huge mesh's first image: strata against Mitsuba 3 (issue 58's target,
docs/performance.md, "Memory asked for ahead").

    tools/bench_first_image.py [--strata target/release/strata] [--before OTHER]
        [--mitsuba-python PYTHON] [--rounds 5] [--threads 2]

strata renders scenes/large/dragon-sub2.toml (the 13.9M-triangle dragon:
`tools/fetch-assets --subdivide 2`) at 320 x 240 and 1 spp; each run is
timed from just before its process starts to the PNG's rename (the issue's
"process start to PNG") and to the process's exit. Mitsuba runs
tools/first_image_mitsuba.py on the same PLY (its `load_dict` and first
render, Python's start and Mitsuba's import not counted) with
--mitsuba-python, a Python that has `mitsuba` (tools/requirements-mitsuba.txt;
its llvm variant needs DRJIT_LIBLLVM_PATH or libLLVM 19). With --before, a
second strata binary runs in each round too. Rounds alternate the runs, so
that a change in the machine's load falls on all; the table gives each
run's times and the medians, and strata's median over Mitsuba's.

The page cache should hold the PLY (run once before timing); the machine
should be quiet: these are wall-clock figures.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENE = os.path.join(ROOT, "scenes", "large", "dragon-sub2.toml")
MESH = os.path.join(ROOT, "assets", "dragon-sub2.ply")


def fail(message):
    print(f"bench_first_image.py: {message}", file=sys.stderr)
    sys.exit(2)


def strata_run(binary, threads, png):
    """Seconds from just before the process starts to the PNG's rename,
    and to its exit."""
    if os.path.exists(png):
        os.remove(png)
    cmd = [binary, "render", SCENE, "--spp", "1", "--width", "320", "--height", "240",
           "--threads", str(threads), "--quiet", "-o", png]
    start = time.time_ns()
    subprocess.run(cmd, check=True, cwd=ROOT)
    end = time.time_ns()
    return (os.stat(png).st_mtime_ns - start) / 1e9, (end - start) / 1e9


def mitsuba_run(python):
    out = subprocess.run([python, os.path.join(HERE, "first_image_mitsuba.py"), MESH],
                         check=True, capture_output=True, text=True, cwd=ROOT).stdout
    found = re.search(r"first image ([0-9.]+) s", out)
    if not found:
        fail(f"first_image_mitsuba.py printed no time:\n{out}")
    return float(found.group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--strata", default=os.path.join(ROOT, "target", "release", "strata"))
    ap.add_argument("--before", help="a second strata binary, run in each round too")
    ap.add_argument("--mitsuba-python", default=sys.executable,
                    help="a Python with mitsuba installed (default: this one)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    binaries = [("strata", args.strata)] + ([("before", args.before)] if args.before else [])
    for _, b in binaries:
        if not os.access(b, os.X_OK):
            fail(f"{b}: no such program (cargo build --release)")
    if not os.path.exists(MESH):
        fail(f"{MESH}: no such file (tools/fetch-assets --subdivide 2)")
    if args.rounds < 1:
        fail("--rounds must be at least 1")

    times = {name: [] for name, _ in binaries}
    mitsuba = []
    with tempfile.TemporaryDirectory() as tmp:
        png = os.path.join(tmp, "first.png")
        for r in range(args.rounds):
            for name, b in binaries:
                to_png, to_exit = strata_run(b, args.threads, png)
                times[name].append((to_png, to_exit))
                print(f"round {r + 1}: {name:<6} to the PNG {to_png:.3f} s, to exit {to_exit:.3f} s", flush=True)
            mitsuba.append(mitsuba_run(args.mitsuba_python))
            print(f"round {r + 1}: mitsuba load_dict + first render {mitsuba[-1]:.3f} s", flush=True)

    m = statistics.median(mitsuba)
    print(f"\nmitsuba: median {m:.3f} s ({min(mitsuba):.3f} to {max(mitsuba):.3f})")
    for name, runs in times.items():
        png_med = statistics.median(t for t, _ in runs)
        exit_med = statistics.median(t for _, t in runs)
        by_round = ", ".join(f"{t / mi:.3f}" for (t, _), mi in zip(runs, mitsuba))
        print(f"{name}: to the PNG median {png_med:.3f} s, to exit {exit_med:.3f} s; "
              f"ratio to Mitsuba {png_med / m:.3f} (PNG), {exit_med / m:.3f} (exit); by round (PNG) {by_round}")


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""RMSE of `strata render --noise E` against a reference EXR, over seeds,
for each sampler: how much the sample sequence a noise target draws from
matters (docs/converge.md, "Adaptive sampling to a noise target").

    python3 -m venv tools/.venv-noise
    tools/.venv-noise/bin/pip install numpy OpenEXR
    tools/.venv-noise/bin/python tools/noise_seeds.py scenes/seed-mc.toml \\
        seed-mc.reference.exr --noise 0.05 --seeds 6

The reference is a linear EXR of the scene at its own size, for example
the one `strata converge` saves beside its CSV. Each seed renders once per
sampler (alternating, so that load on the machine falls on both alike);
the table gives the mean and median RMSE and the mean samples per pixel.
"""

import argparse
import re
import statistics
import subprocess
import sys
import tempfile


def read_exr(path):
    import numpy as np
    import Imath
    import OpenEXR

    f = OpenEXR.InputFile(path)
    window = f.header()["dataWindow"]
    w = window.max.x - window.min.x + 1
    h = window.max.y - window.min.y + 1
    kind = Imath.PixelType(Imath.PixelType.FLOAT)
    channels = [np.frombuffer(f.channel(c, kind), np.float32).reshape(h, w) for c in "RGB"]
    return np.stack(channels, -1)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("reference", help="linear EXR of the scene at its own size")
    p.add_argument("--noise", default="0.05", help="the noise target E (default 0.05)")
    p.add_argument("--spp", default="512", help="the ceiling (default 512)")
    p.add_argument("--seeds", type=int, default=4, help="seeds 1..N (default 4)")
    p.add_argument("--samplers", default="sobol,stratified")
    p.add_argument("--threads", default="2")
    p.add_argument("--strata", default="target/release/strata")
    a = p.parse_args()
    import numpy as np

    reference = read_exr(a.reference)
    results = {s: [] for s in a.samplers.split(",")}
    with tempfile.TemporaryDirectory() as tmp:
        out = f"{tmp}/render.exr"
        for seed in range(1, a.seeds + 1):
            for sampler in results:
                cmd = [a.strata, "render", a.scene, "--noise", a.noise, "--spp", a.spp,
                       "--sampler", sampler, "--seed", str(seed), "--threads", a.threads,
                       "-o", out]
                run = subprocess.run(cmd, capture_output=True, text=True)
                if run.returncode != 0:
                    sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr}")
                spp = float(re.search(r"([\d.]+) spp on average", run.stdout + run.stderr)[1])
                image = read_exr(out)
                if image.shape != reference.shape:
                    sys.exit(f"{a.reference}: {reference.shape[1]}x{reference.shape[0]}, "
                             f"the render is {image.shape[1]}x{image.shape[0]}")
                rmse = float(np.sqrt(np.mean((image - reference) ** 2)))
                results[sampler].append((rmse, spp))
    print(f"{a.scene}, --noise {a.noise}, seeds 1..{a.seeds}")
    print("sampler     mean RMSE  median RMSE  mean spp")
    for sampler, rows in results.items():
        errors = [r for r, _ in rows]
        spp = statistics.fmean(s for _, s in rows)
        print(f"{sampler:<11} {statistics.fmean(errors):.3e}  {statistics.median(errors):.3e}    {spp:.1f}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Samples a noise target takes against uniform sampling at the same RMSE:
the spp ratio of docs/converge.md ("What changed the dragon's figure").

    tools/.venv-noise/bin/python tools/adaptive_ratio.py scenes/large/dragon-rect.toml \\
        dragon.reference.exr --noise 0.1,0.05,0.025 --seeds 2

(the environment as tools/noise_seeds.py makes it). Uniform renders at
--uniform spp give the curve MSE = A·N^-b + c, fitted on log-log axes with
c, the reference's own noise, taken as the curve's value at the
reference's spp (--reference-spp); each noise target's MSE, less c, is
read off it as the N uniform sampling would need, and the ratio is the
target's mean spp over N. Samples, not seconds: the ratio says what the
method saves whatever the machine's load; a noise render's samples cost
more on average than uniform ones (they go to the pixels whose rays cost
most), so its time ratio is higher (`strata converge` measures that).
"""

import argparse
import re
import subprocess
import sys

from noise_seeds import read_exr


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("reference", help="linear EXR of the scene at its own size")
    p.add_argument("--noise", default="0.1,0.05,0.025", help="noise targets (default 0.1,0.05,0.025)")
    p.add_argument("--uniform", default="16,32,64,128,256", help="uniform spp of the curve")
    p.add_argument("--spp", default="512", help="the noise renders' ceiling (default 512)")
    p.add_argument("--reference-spp", type=float, default=1024)
    p.add_argument("--seeds", type=int, default=2, help="seeds 1..N, averaged (default 2)")
    p.add_argument("--threads", default="2")
    p.add_argument("--strata", default="target/release/strata")
    a = p.parse_args()
    import numpy as np
    import tempfile

    reference = read_exr(a.reference)

    def mse(args):
        """Mean over seeds of the MSE and of the mean spp."""
        errors, spps = [], []
        with tempfile.TemporaryDirectory() as tmp:
            for seed in range(1, a.seeds + 1):
                cmd = [a.strata, "render", a.scene, "--seed", str(seed), "--threads", a.threads,
                       "-o", f"{tmp}/render.exr", *args]
                run = subprocess.run(cmd, capture_output=True, text=True)
                if run.returncode != 0:
                    sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr}")
                m = re.search(r"([\d.]+) spp on average", run.stdout + run.stderr)
                spps.append(float(m[1]) if m else float(args[args.index("--spp") + 1]))
                errors.append(float(np.mean((read_exr(f"{tmp}/render.exr") - reference) ** 2)))
        return float(np.mean(errors)), float(np.mean(spps))

    uniform = [(n, mse(["--spp", str(n)])[0]) for n in map(int, a.uniform.split(","))]
    logn = np.log([n for n, _ in uniform])
    m = np.array([e for _, e in uniform])
    c = 0.0
    for _ in range(50):
        slope, log_a = np.polyfit(logn, np.log(np.maximum(m - c, 1e-30)), 1)
        c = float(np.exp(log_a) * a.reference_spp ** slope)
    b = -slope
    print(f"{a.scene}: uniform MSE = {np.exp(log_a):.3g}·N^-{b:.3f} + {c:.3g}, seeds 1..{a.seeds}")
    for n, e in uniform:
        print(f"  uniform {n:5d} spp  RMSE {e ** 0.5:.3e}")
    for target in a.noise.split(","):
        e, spp = mse(["--noise", target, "--spp", a.spp])
        need = (np.exp(log_a) / max(e - c, 1e-30)) ** (1 / b)
        print(f"  --noise {target:<7} RMSE {e ** 0.5:.3e}  {spp:6.1f} spp on average; "
              f"uniform needs {need:6.1f}: ratio {spp / need:.2f}")


if __name__ == "__main__":
    main()

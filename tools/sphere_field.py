#!/usr/bin/env python3
"""A scene of many spheres on a floor, for measuring trees over analytic
shapes (docs/performance.md, "Leaves of shapes and instances").

    python3 tools/sphere_field.py [--count 3000] [--seed 3] [--out assets/spheres.toml]

Spheres of radius 0.2 to 1 rest on the floor at random in an 80 x 80
square, seen from above at an angle under a directional light; 320x240 at
16 spp. The same seed writes the same scene.
"""

import argparse
import os
import random


def scene(count, seed):
    rng = random.Random(seed)
    lines = [
        "# Written by tools/sphere_field.py.",
        "[render]", "width = 320", "height = 240", "spp = 16", "",
        "[camera]", 'type = "perspective"', "position = [0.0, 30.0, 60.0]",
        "look_at = [0.0, 0.0, 0.0]", "fov = 40.0", "",
        "[materials.clay]", "diffuse = [0.6, 0.5, 0.4]", "",
        "[[lights]]", 'type = "directional"', "direction = [0.3, -1.0, -0.4]",
        "irradiance = [1.5, 1.5, 1.5]", "",
        "[[objects]]", "plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] }",
        'material = "clay"',
    ]
    for _ in range(count):
        x, z, r = rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(0.2, 1.0)
        lines += ["", "[[objects]]", f"sphere = {{ center = [{x:.4f}, {r:.4f}, {z:.4f}], radius = {r:.4f} }}", 'material = "clay"']
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--out", default="assets/spheres.toml")
    a = ap.parse_args()
    if a.count < 1:
        ap.error("--count must be at least 1")
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    with open(a.out, "w") as f:
        f.write(scene(a.count, a.seed))
    print(f"wrote {a.out}: {a.count} spheres")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Write a field of N instances of one mesh: a scene file and its instances file.

    tools/instance_field.py [--count 10000] [--mesh assets/dragon.ply]
        [--out assets/field] [--seed 1] [--tumble] [--single]

The instances stand on a square grid on the floor, spaced by the mesh's
largest horizontal extent x 1.25, each turned about the vertical axis by
a random angle and scaled by a random factor in [0.8, 1.2] (with
--tumble: turned by a uniformly random rotation instead). The camera
looks over the whole field from above one edge; one rect light and one
directional light (Mitsuba 3 reads both; tools/bench_mitsuba.py
translates the field into its `shapegroup` and `instance`s). Writes
OUT/field-N.toml and OUT/field-N.csv (one row-major 3x4
object-to-world matrix per line, the format of `instances =`). With
--single, also OUT/single.toml: the same mesh once, under the same kind
of light and a camera framing it, the baseline of docs/performance.md's
instancing figures. Standard library only.
"""

import argparse
import math
import os
import random
import struct
import sys


def mesh_bounds(path):
    """The (min, max) corners of a PLY (binary or ASCII) or OBJ mesh's vertices."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3

    def grow(p):
        for i in range(3):
            lo[i], hi[i] = min(lo[i], p[i]), max(hi[i], p[i])

    if path.lower().endswith(".obj"):
        with open(path, encoding="latin-1") as f:
            for line in f:
                if line.startswith("v "):
                    grow([float(x) for x in line.split()[1:4]])
        return lo, hi
    with open(path, "rb") as f:
        header, props, count, fmt = [], [], 0, "ascii"
        while True:
            line = f.readline().decode("latin-1").strip()
            header.append(line)
            words = line.split()
            if words[:1] == ["format"]:
                fmt = words[1]
            elif words[:2] == ["element", "vertex"]:
                count, props = int(words[2]), []
            elif words[:1] == ["element"]:
                props = props if props else None
            elif words[:1] == ["property"] and count and props is not None and "list" not in words:
                props.append((words[1], words[2]))
            if line == "end_header":
                break
        sizes = {"float": ("f", 4), "float32": ("f", 4), "double": ("d", 8), "float64": ("d", 8),
                 "uchar": ("B", 1), "uint8": ("B", 1), "char": ("b", 1), "int8": ("b", 1),
                 "short": ("h", 2), "int16": ("h", 2), "ushort": ("H", 2), "uint16": ("H", 2),
                 "int": ("i", 4), "int32": ("i", 4), "uint": ("I", 4), "uint32": ("I", 4)}
        names = [n for _, n in props]
        xyz = [names.index(a) for a in "xyz"]
        if fmt == "ascii":
            for _ in range(count):
                values = f.readline().split()
                grow([float(values[i]) for i in xyz])
        else:
            order = "<" if fmt == "binary_little_endian" else ">"
            record = struct.Struct(order + "".join(sizes[t][0] for t, _ in props))
            data = f.read(record.size * count)
            for values in record.iter_unpack(data):
                grow([values[i] for i in xyz])
    return lo, hi


def rotation_y(angle):
    c, s = math.cos(angle), math.sin(angle)
    return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]


def random_rotation(rng):
    """A uniformly random rotation (Shoemake's quaternion method)."""
    u1, u2, u3 = rng.random(), rng.random(), rng.random()
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    x, y, z, w = (a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2),
                  b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3))
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def scene_text(mesh_rel, instances, camera, look_at, fov, floor_y, light_y, light_half, spp):
    inst = f'instances = "{instances}"\n' if instances else ""
    return f"""# Written by tools/instance_field.py.
[render]
width = 320
height = 240
spp = {spp}
shadow_samples = 1

[camera]
type = "perspective"
position = {camera}
look_at = {look_at}
fov = {fov}

[materials.jade]
diffuse = [0.3, 0.6, 0.4]

[materials.floor]
diffuse = [0.75, 0.75, 0.7]

[[lights]]
type = "rect"
corner = [{-light_half}, {light_y}, {-light_half}]
edge_u = [{2 * light_half}, 0.0, 0.0]
edge_v = [0.0, 0.0, {2 * light_half}]
radiance = [40.0, 40.0, 40.0]

[[lights]]
type = "directional"
direction = [0.3, -1.0, -0.4]
irradiance = [1.5, 1.5, 1.5]

[[objects]]
plane = {{ point = [0.0, {floor_y}, 0.0], normal = [0.0, 1.0, 0.0] }}
material = "floor"

[[objects]]
mesh = "{mesh_rel}"
material = "jade"
{inst}"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, default=10000)
    ap.add_argument("--mesh", default="assets/dragon.ply")
    ap.add_argument("--out", default="assets/field")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tumble", action="store_true")
    ap.add_argument("--single", action="store_true")
    ap.add_argument("--spp", type=int, default=16)
    args = ap.parse_args()
    if args.count < 1:
        sys.exit("error: --count must be at least 1")
    if not os.path.exists(args.mesh):
        sys.exit(f"error: {args.mesh}: no such file (tools/fetch-assets fetches the dragon)")
    os.makedirs(args.out, exist_ok=True)
    lo, hi = mesh_bounds(args.mesh)
    centre = [(lo[i] + hi[i]) / 2 for i in range(3)]
    extent = max(hi[0] - lo[0], hi[2] - lo[2], hi[1] - lo[1])
    spacing = 1.25 * extent
    side = math.ceil(math.sqrt(args.count))
    rng = random.Random(args.seed)
    rows = []
    for k in range(args.count):
        gx, gz = k % side, k // side
        x = (gx - (side - 1) / 2) * spacing
        z = (gz - (side - 1) / 2) * spacing
        s = rng.uniform(0.8, 1.2)
        r = random_rotation(rng) if args.tumble else rotation_y(rng.uniform(0, 2 * math.pi))
        # Rotate and scale about the mesh's centre, standing on the floor
        # (its lowest point at lo.y), then move to the grid point.
        m = [[s * r[i][j] for j in range(3)] for i in range(3)]
        c = [sum(m[i][j] * centre[j] for j in range(3)) for i in range(3)]
        t = [x - c[0] + centre[0], -c[1] + centre[1], z - c[2] + centre[2]]
        if not args.tumble:
            t[1] += (lo[1] - centre[1]) * (1 - s)  # its lowest point on the floor
        rows.append(",".join(f"{v:.9g}" for i in range(3) for v in (*m[i], t[i])))
    name = f"field-{args.count}"
    csv = os.path.join(args.out, name + ".csv")
    with open(csv, "w") as f:
        f.write("# row-major 3x4 object-to-world matrices, one instance per line\n")
        f.write("\n".join(rows) + "\n")
    mesh_rel = os.path.relpath(os.path.abspath(args.mesh), os.path.abspath(args.out))
    half = side * spacing / 2
    camera = [0.0, centre[1] + 0.9 * half, 2.2 * half]
    text = scene_text(mesh_rel, name + ".csv", camera, [0.0, centre[1], 0.15 * half], 40.0,
                      lo[1] - 1e-3 * extent, 4 * half, 0.2 * half, args.spp)
    with open(os.path.join(args.out, name + ".toml"), "w") as f:
        f.write(text)
    print(f"wrote {os.path.join(args.out, name + '.toml')} and {csv}: {args.count} instances, "
          f"spacing {spacing:.4g}, field {2 * half:.4g} wide")
    if args.single:
        d = extent
        cam = [centre[0], centre[1] + 0.4 * d, centre[2] + 2.2 * d]
        text = scene_text(mesh_rel, None, cam, centre, 35.0, lo[1] - 1e-3 * extent, centre[1] + 2 * d,
                          0.5 * d, args.spp)
        with open(os.path.join(args.out, "single.toml"), "w") as f:
            f.write(text)
        print(f"wrote {os.path.join(args.out, 'single.toml')}")


if __name__ == "__main__":
    main()

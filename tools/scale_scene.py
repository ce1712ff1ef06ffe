#!/usr/bin/env python3
"""A scene file with every length times FACTOR: the same image in other units.

    python tools/scale_scene.py scenes/large/dragon-gold.toml 50 /tmp/x50/dragon-gold-x50.toml
    python tools/bench_mitsuba.py /tmp/x50/dragon-gold-x50.toml --threads 2 --ref-spp 4096 --spp 16

Positions, edges, radii and the camera's focus distance and aperture are
scaled; radiance is not (a surface's radiance does not depend on the
units), and point and spot intensities are scaled by FACTOR² so that the
irradiance they give, I/r², stays the same. PLY meshes, read as strata
reads them (validate_embree.py's reader: float32 positions, polygons
fanned), are written scaled beside the output as NAME-xFACTOR.ply; an OBJ
is refused (its materials would be lost).

What it is for: a renderer whose ray offsets are absolute (Mitsuba 3
spawns rays (1 + max|p|)·1500·2⁻²⁴ off a surface) shows them less in
larger units, so the scaled scene tells an offset apart from a
difference in the light transport (docs/mitsuba.md, "dragon-gold's last
percent"). A key this tool does not know is refused, naming it, rather
than left unscaled.
"""

import argparse
import json
import math
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
from validate_embree import InputError, load_ply  # noqa: E402

CAMERA_LENGTHS = {"position", "look_at", "focus_distance", "aperture", "height"}
CAMERA_OTHER = {"type", "fov", "up"}
LIGHT_LENGTHS = {"position", "corner", "edge_u", "edge_v", "center", "radius"}
LIGHT_OTHER = {"type", "radiance", "direction", "irradiance", "inner_angle", "outer_angle",
               "normal", "map", "scale", "rotate"}
SHAPE_LENGTHS = {"plane": {"point"}, "sphere": {"center", "radius"}, "triangle": {"v"}}
SHAPE_OTHER = {"plane": {"normal"}, "sphere": set(), "triangle": set()}


def refuse(where, key):
    sys.exit(f"scale_scene.py: {where}: cannot scale '{key}'")


def scaled(value, factor):
    if isinstance(value, list):
        return [scaled(v, factor) for v in value]
    return value * factor


def scale_table(table, lengths, other, factor, where):
    out = {}
    for key, value in table.items():
        if key in lengths:
            out[key] = scaled(value, factor)
        elif key in other:
            out[key] = value
        else:
            refuse(where, key)
    return out


def files_absolute(table, here):
    """`table` with each string value that names a file beside the scene
    (a texture, an environment map) made absolute, so that the copy,
    written elsewhere, still finds it."""
    def fix(v):
        if isinstance(v, str) and not os.path.isabs(v) and os.path.isfile(os.path.join(here, v)):
            return os.path.join(here, v)
        return v
    return {k: fix(v) for k, v in table.items()}


def write_ply(path, v, faces):
    with open(path + ".tmp", "wb") as out:
        out.write(b"ply\nformat binary_little_endian 1.0\n")
        out.write(f"element vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n"
                  f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
                  "end_header\n".encode())
        out.write(v.astype("<f4").tobytes())
        rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
        rec["n"], rec["i"] = 3, faces
        out.write(rec.tobytes())
    os.replace(path + ".tmp", path)


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"


def toml_text(doc):
    lines = []
    for key, value in doc.items():
        if isinstance(value, list) and value and isinstance(value[0], dict):
            for item in value:
                lines.append(f"\n[[{key}]]")
                lines += [f"{k} = {toml_value(x)}" for k, x in item.items()]
        elif isinstance(value, dict) and value and all(isinstance(x, dict) for x in value.values()):
            for name, table in value.items():
                lines.append(f"\n[{key}.{name}]")
                lines += [f"{k} = {toml_value(x)}" for k, x in table.items()]
        elif isinstance(value, dict):
            lines.append(f"\n[{key}]")
            lines += [f"{k} = {toml_value(x)}" for k, x in value.items()]
        else:
            lines.insert(0, f"{key} = {toml_value(value)}")
    return "\n".join(lines).lstrip("\n") + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("factor", type=float)
    p.add_argument("out", help="the scaled scene file; its meshes are written beside it")
    a = p.parse_args()
    if not (math.isfinite(a.factor) and a.factor > 0):
        sys.exit(f"scale_scene.py: factor {a.factor} must be a positive number")
    with open(a.scene, "rb") as f:
        doc = tomllib.load(f)
    here, there = os.path.dirname(os.path.abspath(a.scene)), os.path.dirname(os.path.abspath(a.out))
    k = a.factor
    out = {}
    for key, value in doc.items():
        if key == "render":
            out[key] = value
        elif key == "materials":
            out[key] = {name: files_absolute(m, here) for name, m in value.items()}
        elif key == "camera":
            out[key] = scale_table(value, CAMERA_LENGTHS, CAMERA_OTHER, k, "camera")
        elif key == "lights":
            out[key] = []
            for i, light in enumerate(value):
                s = scale_table(files_absolute(light, here), LIGHT_LENGTHS | {"intensity"},
                                LIGHT_OTHER, k, f"lights[{i}]")
                if "intensity" in light:
                    s["intensity"] = scaled(light["intensity"], k * k)
                out[key].append(s)
        elif key == "objects":
            out[key] = []
            for i, obj in enumerate(value):
                s = {}
                for field, x in obj.items():
                    if field in SHAPE_LENGTHS:
                        s[field] = scale_table(x, SHAPE_LENGTHS[field], SHAPE_OTHER[field], k,
                                               f"objects[{i}].{field}")
                    elif field == "mesh":
                        src = x if os.path.isabs(x) else os.path.join(here, x)
                        if not src.lower().endswith(".ply"):
                            sys.exit(f"scale_scene.py: objects[{i}].mesh: {x}: only PLY meshes are scaled")
                        name = f"{os.path.splitext(os.path.basename(src))[0]}-x{a.factor:g}.ply"
                        try:
                            v, faces = load_ply(src)
                        except InputError as e:
                            sys.exit(f"scale_scene.py: {e}")
                        write_ply(os.path.join(there, name), v.astype(np.float64) * k, faces)
                        s[field] = name
                    elif field in ("material", "name"):
                        s[field] = x
                    else:
                        refuse(f"objects[{i}]", field)
                out[key].append(s)
        else:
            refuse("the scene", key)
    with open(a.out, "w") as f:
        f.write(f"# {os.path.relpath(a.scene, there)} with every length times {a.factor:g} "
                "(tools/scale_scene.py)\n")
        f.write(toml_text(out))
    print(a.out)


if __name__ == "__main__":
    main()

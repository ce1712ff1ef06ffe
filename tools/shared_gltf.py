#!/usr/bin/env python3
"""Write a GLB whose N nodes share one mesh, read from an ASCII PLY.

    tools/shared_gltf.py [--mesh assets/dragon.ply] [--count 100]
        [--out assets/field/dragon-100.glb] [--seed 1]

The nodes stand on a square grid, spaced by the mesh's largest extent
x 1.25, each turned about +Y by a random angle; every node names mesh 0,
so strata stores the mesh once and places it by one instance per node
(docs/scene-format.md, "glTF"). Measures glTF instancing: compare
`strata render OUT --stats` with a build that bakes every node. The PLY
must be ASCII with x, y, z first among its vertex properties and
triangles for faces (assets/dragon.ply is). Standard library only.
"""

import argparse
import json
import math
import os
import random
import struct


def read_ascii_ply(path):
    """The vertices (flat x, y, z floats) and triangles (flat indices)."""
    with open(path, encoding="latin-1") as f:
        counts = {}
        while True:
            line = f.readline()
            if not line:
                raise SystemExit(f"{path}: no end_header")
            words = line.split()
            if words[:1] == ["format"] and words[1] != "ascii":
                raise SystemExit(f"{path}: only ASCII PLY is read here")
            if words[:1] == ["element"]:
                counts[words[1]] = int(words[2])
            if words[:1] == ["end_header"]:
                break
        positions = []
        for _ in range(counts["vertex"]):
            positions.extend(float(x) for x in f.readline().split()[:3])
        indices = []
        for _ in range(counts["face"]):
            words = f.readline().split()
            if words[0] != "3":
                raise SystemExit(f"{path}: a face that is not a triangle")
            indices.extend(int(i) for i in words[1:4])
    return positions, indices


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="assets/dragon.ply")
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--out", default="assets/field/dragon-100.glb")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    positions, indices = read_ascii_ply(args.mesh)
    lo = [min(positions[k::3]) for k in range(3)]
    hi = [max(positions[k::3]) for k in range(3)]
    spacing = 1.25 * max(h - l for l, h in zip(lo, hi))
    side = math.ceil(math.sqrt(args.count))
    rng = random.Random(args.seed)
    nodes = []
    for i in range(args.count):
        angle = rng.uniform(0.0, 2.0 * math.pi)
        nodes.append({
            "mesh": 0,
            "rotation": [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)],
            "translation": [(i % side) * spacing, 0.0, (i // side) * spacing],
        })
    vertex_bytes = struct.pack(f"<{len(positions)}f", *positions)
    index_bytes = struct.pack(f"<{len(indices)}I", *indices)
    doc = {
        "asset": {"version": "2.0", "generator": "strata tools/shared_gltf.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(args.count))}],
        "nodes": nodes,
        "meshes": [{"name": os.path.basename(args.mesh),
                    "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(positions) // 3,
             "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(indices),
             "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(vertex_bytes)},
            {"buffer": 0, "byteOffset": len(vertex_bytes), "byteLength": len(index_bytes)},
        ],
        "buffers": [{"byteLength": len(vertex_bytes) + len(index_bytes)}],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary = vertex_bytes + index_bytes
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(binary), b"BIN\0") + binary)
    print(f"wrote {args.out}: {args.count} nodes sharing {len(indices) // 3} triangles")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Write the shadow rays a render of a mesh scene traces, as a ray file.

    tools/.venv/bin/python tools/shadow_rays.py SCENE.toml -o SHADOW.rays
                          [--camera-rays CAMERA.rays] [--spp 16] [--seed 1]
                          [--strata target/release/strata]

For a scene like scenes/large/dragon-rect.toml (one mesh, a floor plane,
one rect light, a perspective camera), this makes the rays its render
traces towards the light: the camera's rays in the renderer's order
(its default passes, within each a pixel's samples one after another,
pixels row by row), their closest hits on the mesh (from `strata trace`) or the floor
(in closed form), and from each hit that faces the light one segment to a
uniform point of the light, stopping just short of it. The rays start a
little off the surface (1e-5 of the mesh's size, along the normal facing
the camera) and head for one light from neighbouring pixels, as the
renderer's do; they come in the same order and the same numbers (at 16
spp on dragon-rect: 1,228,800 camera rays, about 0.9 million shadow rays).
The renderer samples the light by solid angle rather than area, so the
directions differ a little; `strata trace` and tools/bench_embree.py take
the file (`shadow` rays in its .json). With --camera-rays the camera
rays are written too, in the renderer's order.

Needs numpy (tools/.venv) and a built strata.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from validate_embree import InputError, load_mesh, read_hit_file  # noqa: E402


def pass_ranges(spp):
    """The sample ranges of a render's default passes, as strata splits them
    (render::schedule: up to 16 passes of at least 32 samples a pixel)."""
    passes = max(1, min(16, spp // 32))
    return [(i * spp // passes, (i + 1) * spp // passes) for i in range(passes)]


def camera_rays(cam, width, height, spp, rng):
    """Pinhole rays, pass by pass (each pixel's samples of the pass in a row), pixels row by row."""
    pos, look = np.array(cam["position"], float), np.array(cam["look_at"], float)
    up = np.array(cam.get("up", [0.0, 1.0, 0.0]), float)
    f = (look - pos) / np.linalg.norm(look - pos)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    half = np.tan(np.radians(cam.get("fov", 45.0)) / 2)
    ys, xs = np.mgrid[0:height, 0:width]
    batches = []
    for lo, hi in pass_ranges(spp):
        k = hi - lo
        x = np.repeat(xs.reshape(-1), k) + rng.random(xs.size * k)
        y = np.repeat(ys.reshape(-1), k) + rng.random(xs.size * k)
        sx = (x / width * 2 - 1) * half * width / height
        sy = (1 - y / height * 2) * half
        d = f + sx[:, None] * r + sy[:, None] * u
        batches.append(d / np.linalg.norm(d, axis=1)[:, None])
    d = np.concatenate(batches)
    rays = np.zeros((len(d), 8), np.float32)
    rays[:, 0:3], rays[:, 3:6], rays[:, 7] = pos, d, np.inf
    return rays


def write_rays(path, rays, kind):
    rays.astype("<f4").tofile(path)
    group = {"kind": kind, "first": 0, "count": len(rays), "target_t": None}
    with open(path + ".json", "w") as f:
        json.dump({"format": "strata-rays", "groups": [group]}, f, indent=2)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene")
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--camera-rays", help="also write the camera rays here")
    p.add_argument("--spp", type=int, default=None)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--strata", default="target/release/strata")
    a = p.parse_args()
    try:
        with open(a.scene, "rb") as f:
            scene = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise InputError(a.scene, f"cannot read the scene: {e}")
    objects, lights = scene.get("objects", []), scene.get("lights", [])
    meshes = [o["mesh"] for o in objects if "mesh" in o]
    rects = [lt for lt in lights if lt.get("type") == "rect"]
    if not meshes or not rects or "camera" not in scene:
        raise InputError(a.scene, "needs a mesh object, a rect light and a camera")
    mesh = os.path.join(os.path.dirname(a.scene), meshes[0])
    plane = next((o["plane"] for o in objects if "plane" in o), None)
    light, cam, render = rects[0], scene["camera"], scene.get("render", {})
    if cam.get("type", "perspective") != "perspective":
        raise InputError(a.scene, "camera: only a perspective camera is supported")
    rng = np.random.default_rng(a.seed)
    spp = a.spp or render.get("spp", 16)
    cams = camera_rays(cam, render.get("width", 320), render.get("height", 240), spp, rng)
    vertices, triangles = load_mesh(mesh)
    if a.camera_rays:
        write_rays(a.camera_rays, cams, "camera")
    with tempfile.TemporaryDirectory() as tmp:
        cam_path, hits_path = os.path.join(tmp, "camera.rays"), os.path.join(tmp, "camera.hits")
        write_rays(cam_path, cams, "camera")
        subprocess.run([a.strata, "trace", mesh, "--rays", cam_path, "--hits", hits_path, "--quiet"], check=True)
        hits = read_hit_file(hits_path, len(cams))
    o, d = cams[:, 0:3].astype(float), cams[:, 3:6].astype(float)
    t = hits["t"].astype(float)
    tri = vertices[triangles[np.minimum(hits["prim"], len(triangles) - 1)]].astype(float)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if plane is not None:
        pp, pn = np.array(plane["point"], float), np.array(plane["normal"], float)
        with np.errstate(divide="ignore", invalid="ignore"):
            tp = ((pp - o) @ pn) / (d @ pn)
        on_plane = (tp > 0) & (tp < t)
        t, n = np.where(on_plane, tp, t), np.where(on_plane[:, None], pn, n)
    hit = np.isfinite(t)
    n = n / np.maximum(np.linalg.norm(n, axis=1), 1e-30)[:, None]
    n = np.where(((n * d).sum(1) > 0)[:, None], -n, n)
    size = np.linalg.norm(vertices.max(0) - vertices.min(0))
    corner, eu, ev = (np.array(light[k], float) for k in ("corner", "edge_u", "edge_v"))
    uv = rng.random((len(cams), 2))
    target = corner + uv[:, :1] * eu + uv[:, 1:] * ev
    with np.errstate(invalid="ignore"):  # the misses' infinite t
        origin = o + t[:, None] * d + 1e-5 * size * n
        to = target - origin
        faces = hit & ((to * n).sum(1) > 0) & ((to @ np.cross(eu, ev)) < 0)
    shadow = np.zeros((int(faces.sum()), 8), np.float32)
    shadow[:, 0:3], shadow[:, 3:6], shadow[:, 7] = origin[faces], to[faces], 1 - 1e-4
    write_rays(a.output, shadow, "shadow")
    print(f"wrote {len(shadow)} shadow rays from {int(hit.sum())} hits of {len(cams)} camera rays -> {a.output}")


if __name__ == "__main__":
    try:
        main()
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)

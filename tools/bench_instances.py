#!/usr/bin/env python3
"""Camera rays over a field of instances against the same rays over one
mesh, in strata and in Embree 3's own instances, to tell what an instanced
scene costs per ray from what instancing costs.

    bench_instances.py [--field assets/field] [--count 10000]
                       [--strata target/release/strata] [--threads 2]
                       [--rounds 5] [--spp 4] [--keep DIR]

The field and the single-mesh scene are `tools/instance_field.py`'s (run
first: `python3 tools/instance_field.py --count N --single --out DIR`).
From each scene's own camera, this writes spp jittered pinhole rays a pixel
(a fixed seed) and traces them, closest hit:

* strata: `strata trace SCENE.toml` over a scene of the mesh object alone
  (its `instances` file for the field; no floor, no lights), --repeats 3,
  its own timing of the tracing alone;
* Embree: `tools/embree/embree_trace MESH.tris` (with `--instances FILE.csv`
  for the field: one Embree instance a line over one scene of the mesh),
  built at Embree's high quality, --repeats 3.

With --keep DIR the ray files (single.bin, field.bin) and the scenes
`strata trace` reads (single.toml, field.toml) stay in DIR, for runs of
one's own (two binaries alternating, `--occlusion`), beside Embree's
triangles (mesh.tris) and the last run's hits.bin; else all of them are
written to a temporary folder and removed.

Rounds alternate the four runs so that a change in the machine's load
falls on all; each figure is the median over rounds. The table gives
Mrays/s, the field's rate over the single mesh's for each engine (what the
scene costs), and strata over Embree for each scene (what the engine
costs). Both engines report the same hits for the same rays
(`tests/suite/embree_instances.rs` checks that).
"""

import argparse
import math
import os
import statistics
import sys
import tempfile
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
from bench_embree import build_harness, strata_rate, write_tris  # noqa: E402
from validate_embree import InputError, load_mesh  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def camera_rays(scene, spp, seed):
    """spp jittered rays a pixel of the scene's perspective camera, as RAYS.bin records."""
    cam, render = scene["camera"], scene["render"]
    w, h = render["width"], render["height"]
    eye = np.array(cam["position"], np.float64)
    forward = np.array(cam["look_at"], np.float64) - eye
    forward /= np.linalg.norm(forward)
    up = np.array(cam.get("up", [0.0, 1.0, 0.0]), np.float64)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    half_h = math.tan(math.radians(cam.get("fov", 40.0)) / 2)
    half_w = half_h * w / h
    rng = np.random.default_rng(seed)
    ys, xs = np.mgrid[0:h, 0:w]
    xs = np.repeat(xs.reshape(-1), spp) + rng.random(w * h * spp)
    ys = np.repeat(ys.reshape(-1), spp) + rng.random(w * h * spp)
    sx = (2 * xs / w - 1) * half_w
    sy = (1 - 2 * ys / h) * half_h
    d = forward[None, :] + sx[:, None] * right[None, :] + sy[:, None] * true_up[None, :]
    d /= np.linalg.norm(d, axis=1)[:, None]
    rays = np.zeros((len(d), 8), np.float32)
    rays[:, 0:3] = eye
    rays[:, 3:6] = d
    rays[:, 7] = np.inf
    return rays


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--field", default="assets/field", help="folder of instance_field.py's scenes")
    ap.add_argument("--count", type=int, default=10000, help="the field's instance count (field-N.toml)")
    ap.add_argument("--strata", default=os.path.join(ROOT, "target", "release", "strata"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--spp", type=int, default=4, help="rays a pixel")
    ap.add_argument("--keep", metavar="DIR", help="write the rays and trace scenes to DIR and keep them")
    a = ap.parse_args(argv)
    try:
        if a.keep:
            try:
                os.makedirs(a.keep, exist_ok=True)
            except OSError as e:
                raise InputError(a.keep, f"cannot make the folder: {e.strerror}")
            run(a, a.keep)
        else:
            # The rays and the mesh for Embree: tens of MB, removed after.
            with tempfile.TemporaryDirectory(prefix="bench_instances.") as work:
                run(a, work)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


def run(a, work):
    field_toml = os.path.join(a.field, f"field-{a.count}.toml")
    single_toml = os.path.join(a.field, "single.toml")
    for path in (field_toml, single_toml):
        if not os.path.exists(path):
            raise InputError(path, f"missing: run python3 tools/instance_field.py --count {a.count} --single --out {a.field}")
    embree = build_harness()
    runs = {}
    for name, path in (("single", single_toml), ("field", field_toml)):
        scene = tomllib.load(open(path, "rb"))
        obj = next(o for o in scene["objects"] if "mesh" in o)
        mesh = os.path.normpath(os.path.join(a.field, obj["mesh"]))
        rays = os.path.join(work, f"{name}.bin")
        camera_rays(scene, a.spp, seed=1).tofile(rays)
        trace_scene = os.path.join(work, f"{name}.toml")
        with open(trace_scene, "w") as f:
            f.write(f'[[objects]]\nmesh = "{os.path.abspath(mesh)}"\n')
            if "instances" in obj:
                csv = os.path.abspath(os.path.join(a.field, obj["instances"]))
                f.write(f'instances = "{csv}"\n')
        hits = os.path.join(work, "hits.bin")
        common = ["--threads", str(a.threads), "--repeats", "3"]
        runs[(name, "strata")] = [a.strata, "trace", trace_scene, "--rays", rays, "--hits", hits] + common
        if embree:
            tris = os.path.join(work, "mesh.tris")
            if not os.path.exists(tris):
                write_tris(*load_mesh(mesh), tris)
            extra = ["--instances", csv] if "instances" in obj else []
            runs[(name, "embree")] = [embree, tris, rays, "--hits", hits] + common + extra
    figures = {k: [] for k in runs}
    for r in range(a.rounds):
        for k, args in runs.items():
            # embree_trace prints its line in `strata trace`'s format: one parser.
            figures[k].append(strata_rate(args, k[0], a.threads)[0])
        print(f"round {r + 1}: " + ", ".join(f"{k[0]} {k[1]} {v[-1]:.2f}" for k, v in figures.items()), flush=True)
    med = {k: statistics.median(v) for k, v in figures.items()}
    print(f"\nMrays/s, closest hit, {a.spp} camera rays a pixel, {a.threads} threads, medians of {a.rounds} rounds")
    print(f"{'engine':<8} {'single':>8} {'field':>8} {'field/single':>13}")
    for engine in ("strata", "embree"):
        if ("single", engine) in med:
            s, f = med[("single", engine)], med[("field", engine)]
            print(f"{engine:<8} {s:8.2f} {f:8.2f} {f / s:13.2f}")
    if embree:
        for name in ("single", "field"):
            print(f"strata/embree on {name}: {med[(name, 'strata')] / med[(name, 'embree')]:.2f}")


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""strata_rt against embreex and Open3D, from Python, on the same rays.

    tools/.venv-bench/bin/python tools/bench_python.py [--mesh assets/dragon.ply]
        [--rays 1000000] [--list-rays 200000] [--points 200000] [--runs 3]
        [--threads N] [--engines strata,embreex,open3d] [--write-rays RAYS.bin]

The environment (once; strata_rt built from this checkout):

    python3 -m venv tools/.venv-bench
    tools/.venv-bench/bin/pip install -r tools/requirements-bench.txt
    tools/.venv-bench/bin/pip install ./python

Every engine gets the same float32 arrays and answers into numpy arrays:
what a user's code pays, the conversion into each engine's types included,
each scene's build excluded (timed apart, once). Rays: --rays random rays,
origins uniform in the mesh's bounding box grown by 10% on each side,
directions uniform on the sphere (seed 7); the list and count queries take
the first --list-rays of them. Each query runs --runs times, the engines
interleaved round by round; the table gives the median in Mrays/s (Mpoints/s
for points). embreex runs on one thread (its loop holds the GIL); Open3D
and strata on --threads (default: all of the machine's).

`--engines strata,open3d,strata.open3d` adds strata_rt's drop-in for Open3D
(`strata_rt.open3d.RaycastingScene`, called exactly as the open3d engine
calls Open3D's, on numpy arrays): what the drop-in costs an Open3D user
beside `strata_rt.Mesh`.

Agreement: the hit fraction and the mean hit distance of each first-hit
engine are printed, so that a fast wrong answer shows.

Watertightness: on an icosphere subdivided three times (642 vertices,
1,920 edges), a ray from outside aimed through the centre at each vertex,
and at each edge midpoint, crosses the surface exactly twice. Printed for
each engine: how many of those rays it counts a number other than 2
(missed: fewer; doubled: more). embreex has no count query, so it is
counted as trimesh counts with it (trimesh.ray.ray_pyembree: re-querying
from just past each hit).
"""

import argparse
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def fail(message):
    print(f"bench_python.py: {message}", file=sys.stderr)
    sys.exit(2)


def load_mesh(path):
    """Vertices (float32) and faces (int32), faces in file order, read by
    strata's loader (its triangles, indexed again by exact position)."""
    import strata_rt

    corners = strata_rt.Mesh.load(path).triangles.reshape(-1, 3)
    vertices, index = np.unique(corners, axis=0, return_inverse=True)
    return vertices.astype(np.float32), index.reshape(-1, 3).astype(np.int32)


def random_rays(vertices, n, seed=7):
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    grow = 0.1 * (hi - lo)
    origins = rng.uniform(lo - grow, hi + grow, size=(n, 3)).astype(np.float32)
    d = rng.normal(size=(n, 3))
    directions = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    return origins, directions


def random_points(vertices, n, seed=8):
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    grow = 0.1 * (hi - lo)
    return rng.uniform(lo - grow, hi + grow, size=(n, 3)).astype(np.float32)


# ------------------------------------------------------------------ engines
# Each engine: build(vertices, faces) -> state, and query functions taking
# (state, origins, directions) -> numpy answers.


class Strata:
    name = "strata_rt"

    def __init__(self, threads):
        import strata_rt

        self.module = strata_rt
        self.threads = threads

    def build(self, v, f):
        self.mesh = self.module.Mesh(v, f)

    def intersect(self, o, d):
        # The row's quantities, the ones Open3D's cast_rays answers (the
        # float64 hit point, which Open3D does not give, left out).
        hit = self.mesh.intersect(o, d, threads=self.threads, fields=INTERSECT_FIELDS)
        return hit.t, hit.prim

    def occluded(self, o, d):
        return self.mesh.occluded(o, d, threads=self.threads)

    def all_hits(self, o, d):
        return self.mesh.all_hits(o, d, threads=self.threads)

    def count_hits(self, o, d):
        return self.mesh.count_hits(o, d, threads=self.threads)

    def closest_point(self, p):
        return self.mesh.closest_point(p, threads=self.threads).distance

    def contains(self, p):
        return self.mesh.contains(p, threads=self.threads)


class Embreex:
    name = "embreex"

    def __init__(self, threads):
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh

        self.rtcs, self.TriangleMesh = rtcs, TriangleMesh

    def build(self, v, f):
        # Robust mode, as validating users run it (it costs Embree little).
        self.scene = self.rtcs.EmbreeScene(robust=True)
        self.TriangleMesh(self.scene, v, f)
        self.v, self.f = v, f
        # Embree commits (builds) the scene at the first query: do it here.
        self.scene.run(v[:1], np.ones((1, 3), np.float32))

    def intersect_ids(self, o, d):
        return self.scene.run(o, d)

    def intersect(self, o, d):
        out = self.scene.run(o, d, output=1)
        prim = out["primID"]
        return np.where(prim >= 0, out["tfar"], np.inf), prim

    def occluded(self, o, d):
        return self.scene.run(o, d, query="OCCLUDED") == 0

    def count_hits(self, o, d):
        """As trimesh counts with embreex (trimesh.ray.ray_pyembree): it
        re-queries from just past each hit, embreex having no such query."""
        import trimesh
        from trimesh.ray.ray_pyembree import RayMeshIntersector

        if getattr(self, "trimesh_for", None) is not self.f:
            mesh = trimesh.Trimesh(self.v, self.f, process=False)
            self.intersector, self.trimesh_for = RayMeshIntersector(mesh), self.f
        _, rays = self.intersector.intersects_id(o, d, multiple_hits=True)
        return np.bincount(rays, minlength=len(o))


def numpy_of(x):
    """An Open3D tensor's numpy array (a numpy array as it is)."""
    return x.numpy() if hasattr(x, "numpy") else x


class Open3D:
    name = "open3d"

    def __init__(self, threads):
        import open3d as o3d

        self.module = o3d.t.geometry
        self.tensor = o3d.core.Tensor
        self.threads = 0 if threads is None else threads

    def build(self, v, f):
        self.scene = self.module.RaycastingScene(nthreads=self.threads)
        self.scene.add_triangles(self.tensor(v), self.tensor(f.astype(np.uint32)))
        # Open3D builds its Embree scene at the first query: do it here.
        self.scene.cast_rays(self.rays(v[:1], np.ones((1, 3), np.float32)))

    def rays(self, o, d):
        return self.tensor(np.hstack([o, d]))

    def intersect(self, o, d):
        ans = self.scene.cast_rays(self.rays(o, d), nthreads=self.threads)
        prim = numpy_of(ans["primitive_ids"]).astype(np.int64)
        prim[prim == self.scene.INVALID_ID] = -1
        # Every output as numpy, as strata hands them over.
        for k in ("primitive_uvs", "primitive_normals"):
            numpy_of(ans[k])
        return numpy_of(ans["t_hit"]), prim

    def occluded(self, o, d):
        return numpy_of(self.scene.test_occlusions(self.rays(o, d), nthreads=self.threads))

    def all_hits(self, o, d):
        ans = self.scene.list_intersections(self.rays(o, d), nthreads=self.threads)
        return numpy_of(ans["ray_splits"]), numpy_of(ans["t_hit"]), numpy_of(ans["primitive_ids"])

    def count_hits(self, o, d):
        return numpy_of(self.scene.count_intersections(self.rays(o, d), nthreads=self.threads))

    def closest_point(self, p):
        ans = self.scene.compute_closest_points(self.tensor(p), nthreads=self.threads)
        return np.linalg.norm(numpy_of(ans["points"]) - p, axis=1)

    def contains(self, p):
        return numpy_of(self.scene.compute_occupancy(self.tensor(p), nthreads=self.threads)) > 0.5


class StrataOpen3D(Open3D):
    """strata_rt's drop-in for Open3D's RaycastingScene, called as an Open3D
    user calls Open3D's (one (n, 6) array of rays, Open3D's result keys), on
    numpy arrays: what the drop-in itself costs beside strata_rt.Mesh."""

    name = "strata.open3d"

    def __init__(self, threads):
        import strata_rt.open3d

        self.module = strata_rt.open3d
        self.tensor = np.asarray
        self.threads = 0 if threads is None else threads


# What the first-hit row asks strata_rt for: what Open3D's cast_rays answers.
INTERSECT_FIELDS = ("t", "prim", "u", "v", "normal")

ENGINES = {"strata": Strata, "embreex": Embreex, "open3d": Open3D, "strata.open3d": StrataOpen3D}

# (query, input kind, engines' method names)
QUERIES = [
    ("intersect (t, prim, u, v, normal)", "rays", "intersect"),
    ("intersect (ids only)", "rays", "intersect_ids"),
    ("occluded", "rays", "occluded"),
    ("all_hits", "list", "all_hits"),
    ("count_hits", "list", "count_hits"),
    ("closest_point", "points", "closest_point"),
    ("contains", "points", "contains"),
]


def timed(fn, *args):
    start = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - start, out


def icosphere_rays():
    """Rays from outside through the centre at each vertex and each edge
    midpoint of an icosphere subdivided three times (made by strata_rt's
    test helper-free construction below)."""
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(3):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                mid[key] = len(verts) - 1
            return mid[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    vertices = np.array(verts, np.float32)
    faces = np.array(faces, np.int32)
    edges = {tuple(sorted(e)) for tri in faces for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))}
    edges = np.array(sorted(edges))
    targets = {
        "vertices": vertices,
        "edge midpoints": ((vertices[edges[:, 0]] + vertices[edges[:, 1]]) * np.float32(0.5)).astype(np.float32),
    }
    return vertices, faces, targets


def watertightness(engines):
    vertices, faces, targets = icosphere_rays()
    print(f"\nWatertightness: icosphere of {len(vertices)} vertices, {len(faces)} triangles; "
          "rays from outside through the centre, 2 crossings expected")
    print(f"| engine | target | rays | missed (<2) | doubled (>2) |")
    print("|---|---|---|---|---|")
    for e in engines:
        if not hasattr(e, "count_hits"):
            continue
        e.build(vertices, faces)
        for name, points in targets.items():
            # Origin 2p, direction -p: exact in float32, through p at t = 1.
            o, d = (2 * points).astype(np.float32), (-points).astype(np.float32)
            n = np.asarray(e.count_hits(o, d))
            print(f"| {e.name} | {name} | {len(o)} | {(n < 2).sum()} | {(n > 2).sum()} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default=os.path.join(ROOT, "assets", "dragon.ply"))
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--list-rays", type=int, default=200_000)
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=None, help="strata and Open3D threads (default: all)")
    ap.add_argument("--engines", default="strata,embreex,open3d")
    ap.add_argument("--write-rays", metavar="RAYS.bin",
                    help="write the --rays rays as a ray file for `strata trace` "
                         "(8 float32 a ray: origin, direction, t_min 0, t_max inf) and stop")
    args = ap.parse_args()

    if not os.path.exists(args.mesh):
        fail(f"{args.mesh}: no such file (tools/fetch-assets fetches the dragon)")
    engines = []
    for name in args.engines.split(","):
        if name not in ENGINES:
            fail(f"--engines: unknown engine {name!r} (known: {', '.join(ENGINES)})")
        try:
            engines.append(ENGINES[name](args.threads))
        except ImportError as err:
            print(f"{name}: not installed ({err}); skipped")

    v, f = load_mesh(args.mesh)
    o, d = random_rays(v, args.rays)
    if args.write_rays:
        records = np.zeros((len(o), 8), np.float32)
        records[:, :3], records[:, 3:6], records[:, 7] = o, d, np.inf
        records.tofile(args.write_rays)
        print(f"{args.write_rays}: {len(o)} rays (strata trace {args.mesh} --rays {args.write_rays} ...)")
        return
    p = random_points(v, args.points)
    lo, ld = o[: args.list_rays], d[: args.list_rays]
    inputs = {"rays": (o, d), "list": (lo, ld), "points": (p,)}
    print(f"{os.path.basename(args.mesh)}: {len(f)} triangles; {args.rays} rays, "
          f"{args.list_rays} for lists and counts, {args.points} points; "
          f"threads {args.threads or os.cpu_count()}; CPU {cpu_name()}")
    for e in engines:
        secs, _ = timed(e.build, v, f)
        print(f"{e.name}: build {secs:.2f} s")

    times = {}
    answers = {}
    for _ in range(args.runs):
        for label, kind, method in QUERIES:
            for e in engines:
                fn = getattr(e, method, None)
                if fn is None:
                    continue
                secs, out = timed(fn, *inputs[kind])
                times.setdefault((label, e.name), []).append(secs)
                answers[(label, e.name)] = out

    print("\n| query | " + " | ".join(e.name for e in engines) + " |")
    print("|---|" + "---|" * len(engines))
    for label, kind, _ in QUERIES:
        n = len(inputs[kind][0])
        cells = []
        for e in engines:
            ts = times.get((label, e.name))
            cells.append(f"{n / statistics.median(ts) / 1e6:.2f}" if ts else "")
        print(f"| {label} | " + " | ".join(cells) + " |")

    print("\nAgreement (first hit):")
    for e in engines:
        out = answers.get(("intersect (t, prim, u, v, normal)", e.name))
        if out is not None:
            t = np.asarray(out[0])
            hit = np.isfinite(t)
            print(f"  {e.name}: {hit.mean():.4f} of rays hit, mean t {t[hit].mean():.6f}")
    counts = {e.name: answers.get(("count_hits", e.name)) for e in engines}
    counts = {k: np.asarray(c) for k, c in counts.items() if c is not None}
    if len(counts) > 1:
        names = list(counts)
        for other in names[1:]:
            differ = (counts[names[0]] != counts[other]).sum()
            print(f"  count_hits: {names[0]} and {other} differ on {differ} of {len(lo)} rays")
    watertightness(engines)


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


if __name__ == "__main__":
    main()

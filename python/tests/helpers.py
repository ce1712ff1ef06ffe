"""Meshes, rays and float64 brute force for the strata_rt tests.

Every reference answer here is computed in float64 from the float32
vertices strata stores, with no BVH: Möller and Trumbore (1997), "Fast,
minimum storage ray-triangle intersection", for rays, and Ericson (2005),
"Real-Time Collision Detection" §5.1.5, for the closest point on a
triangle.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]


def bunny_path() -> Path | None:
    """assets/bunny.obj (or $STRATA_RT_BUNNY), if it is there."""
    path = Path(os.environ.get("STRATA_RT_BUNNY", REPO / "assets" / "bunny.obj"))
    return path if path.exists() else None


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (float64) and triangles of a plain OBJ file (fan-split polygons)."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(w.split("/")[0]) for w in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(vertices) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
    return np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)


def as_stored(vertices: np.ndarray) -> np.ndarray:
    """The vertices as strata holds them: rounded to float32, back in float64."""
    return np.asarray(vertices, dtype=np.float32).astype(np.float64)


# ---------------------------------------------------------------- meshes


def box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box, 12 triangles wound outward (closed)."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64)
    vertices = lo + corners * (hi - lo)
    # Corner index = 4x + 2y + z.
    quads = [
        (0, 1, 3, 2),  # x = lo
        (4, 6, 7, 5),  # x = hi
        (0, 4, 5, 1),  # y = lo
        (2, 3, 7, 6),  # y = hi
        (0, 2, 6, 4),  # z = lo
        (1, 5, 7, 3),  # z = hi
    ]
    faces = []
    for a, b, c, d in quads:
        faces += [[a, b, c], [a, c, d]]
    return vertices, np.array(faces, dtype=np.int64)


def cube() -> tuple[np.ndarray, np.ndarray]:
    """The cube [-1, 1]³."""
    return box([-1, -1, -1], [1, 1, 1])


def icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere: an icosahedron split 1-to-4 `subdivisions` times,
    midpoints shared and pushed to the sphere (closed; 642 vertices and
    1,280 faces at 3)."""
    t = (1 + 5**0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    vertices = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(subdivisions):
        midpoint = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                p = vertices[a] + vertices[b]
                vertices.append(p / np.linalg.norm(p))
                midpoint[key] = len(vertices) - 1
            return midpoint[key]

        split = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            split += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = split
    return np.array(vertices), np.array(faces, dtype=np.int64)


def bumpy_sphere(stacks: int = 40, slices: int = 80, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """A closed UV sphere with a smooth random radius (about 0.7 to 1.3):
    poles shared, seam shared, so it is watertight and not convex."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0, np.pi, stacks + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, slices, endpoint=False)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    k = rng.normal(size=(4, 3))
    bump = sum(0.08 * np.sin(dirs @ k[i] * (i + 2) + i) for i in range(4))
    ring = (dirs * (1 + bump)[..., None]).reshape(-1, 3)
    vertices = np.vstack([[0, 0, 1], ring, [0, 0, -1]])
    top, bottom = 0, len(vertices) - 1

    def at(i, j):
        return 1 + i * slices + j % slices

    faces = []
    for j in range(slices):
        faces.append([top, at(0, j), at(0, j + 1)])
        faces.append([bottom, at(stacks - 2, j + 1), at(stacks - 2, j)])
    for i in range(stacks - 2):
        for j in range(slices):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            faces += [[a, b, c], [a, c, d]]
    return vertices, np.array(faces, dtype=np.int64)


def boundary_loops(faces: np.ndarray) -> list[list[int]]:
    """The mesh's holes: each loop of edges used by one face only, in order."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    open_edges = edges[counts[inverse.ravel()] == 1]
    nxt = {int(a): int(b) for a, b in open_edges}
    loops, seen = [], set()
    for start in list(nxt):
        if start in seen:
            continue
        loop, v = [], start
        while v not in seen:
            seen.add(v)
            loop.append(v)
            v = nxt[v]
        loops.append(loop)
    return loops


def close_holes(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each hole filled by a fan from a new vertex at its centroid, wound
    against the open edges so that the mesh becomes closed. Asserts every
    edge is then used by exactly two faces."""
    vertices, faces = list(vertices), [list(f) for f in faces]
    for loop in boundary_loops(np.array(faces)):
        centre = len(vertices)
        vertices.append(np.mean([vertices[i] for i in loop], axis=0))
        for a, b in zip(loop, loop[1:] + loop[:1]):
            faces.append([b, a, centre])
    faces = np.array(faces, dtype=np.int64)
    assert not boundary_loops(faces), "holes left after closing"
    return np.array(vertices), faces


# ---------------------------------------------------------------- rays


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_directions(rng, n: int) -> np.ndarray:
    return unit(rng.normal(size=(n, 3)))


def random_rays(rng, vertices: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Half: origins uniform in the bounding box grown by half its size,
    directions uniform; half: from outside the box, aimed at a random
    point of a random triangle (so that most of them hit)."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    size = hi - lo
    m = n // 2
    o1 = lo - size / 4 + rng.random((m, 3)) * size * 1.5
    d1 = random_directions(rng, m)
    centre, radius = (lo + hi) / 2, np.linalg.norm(size)
    o2 = centre + random_directions(rng, n - m) * radius * 1.5
    return np.vstack([o1, o2]), np.vstack([d1, unit(centre + (rng.random((n - m, 3)) - 0.5) * size * 0.8 - o2)])


# ---------------------------------------------------------------- brute force


def ray_triangle_pairs(tris: np.ndarray, origins: np.ndarray, directions: np.ndarray, rays, prims):
    """Rays `rays` against triangles `prims` (pairs) in float64: (t, u, v);
    t is NaN where the ray is parallel to the plane. u, v are the
    barycentrics of the second and third vertex, not clipped."""
    tri = np.asarray(tris, dtype=np.float64)[prims]
    v0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    o = np.asarray(origins, dtype=np.float64)[rays]
    d = np.asarray(directions, dtype=np.float64)[rays]
    p = np.cross(d, e2)
    det = (p * e1).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tv = o - v0
        u = (tv * p).sum(-1) * inv
        q = np.cross(tv, e1)
        v = (d * q).sum(-1) * inv
        t = (e2 * q).sum(-1) * inv
    t[det == 0] = np.nan
    return t, u, v


def candidates(tris: np.ndarray, origins: np.ndarray, directions: np.ndarray, chunk: int = 64):
    """Every (ray, triangle) pair whose line passes within the triangle's
    bounding sphere (grown by 1%) in front of the origin: a superset of the
    pairs that hit or nearly miss, so culling by it loses nothing."""
    tris = np.asarray(tris, dtype=np.float64)
    centre = tris.mean(axis=1)
    radius = np.linalg.norm(tris - centre[:, None], axis=-1).max(axis=1) * 1.01 + 1e-12
    unit_d = unit(np.asarray(directions, dtype=np.float64))
    rays, prims = [], []
    for s in range(0, len(origins), chunk):
        w = centre[None] - np.asarray(origins[s:s + chunk], dtype=np.float64)[:, None]
        along = np.einsum("ijk,ik->ij", w, unit_d[s:s + chunk])
        off2 = np.einsum("ijk,ijk->ij", w, w) - along**2
        near = (off2 <= radius[None] ** 2) & (along >= -radius[None])
        r, p = np.nonzero(near)
        rays.append(r + s)
        prims.append(p)
    return np.concatenate(rays), np.concatenate(prims)


def margin(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """How far inside its triangle a plane hit lies: the smallest
    barycentric (negative outside)."""
    return np.minimum(np.minimum(u, v), 1 - u - v)


class BruteHits:
    """Brute-force hits of rays on triangles (float64, every pair that
    bounding spheres do not rule out), with which rays are clear: no
    triangle along the ray is hit or missed within `edge` (barycentric) of
    its border, and no two of its hits lie within `gap` (relative) of each
    other. On a clear ray any correct float32 engine gives the same first
    hit and the same list of crossings.

    Per ray: `first_prim` (-1 on a miss), `first_t`, `first_u`, `first_v`,
    `clear`, and `crossings(i)`, its hits sorted by t.
    """

    def __init__(self, tris, origins, directions, edge=1e-4, gap=1e-4):
        n = len(origins)
        rays, prims = candidates(tris, origins, directions)
        t, u, v = ray_triangle_pairs(tris, origins, directions, rays, prims)
        m = margin(u, v)
        forward = np.nan_to_num(t, nan=-1.0) > 0
        near = forward & (m > -edge)  # hit, or missed by a hair
        rays, prims, t, u, v, m = rays[near], prims[near], t[near], u[near], v[near], m[near]
        hit = m >= 0
        # Group by ray, nearest first.
        order = np.lexsort((t, rays))
        rays, prims, t, u, v, m, hit = (a[order] for a in (rays, prims, t, u, v, m, hit))
        starts = np.searchsorted(rays, np.arange(n + 1))
        self.first_prim = np.full(n, -1, dtype=np.int64)
        self.first_t = np.full(n, np.inf)
        self.first_u = np.full(n, np.nan)
        self.first_v = np.full(n, np.nan)
        self.clear = np.ones(n, dtype=bool)
        self._hits = []
        for i in range(n):
            a, b = starts[i], starts[i + 1]
            h = np.flatnonzero(hit[a:b]) + a
            self._hits.append((t[h], prims[h]))
            if len(h):
                j = h[0]
                self.first_prim[i], self.first_t[i] = prims[j], t[j]
                self.first_u[i], self.first_v[i] = u[j], v[j]
            edgy = (np.abs(m[a:b]) < edge).any()
            ts = t[a:b]
            close = (np.diff(ts) < gap * np.maximum(np.abs(ts[1:]), 1.0)).any()
            self.clear[i] = not edgy and not close

    def crossings(self, i):
        """Ray i's hits sorted by t: (t, prim)."""
        return self._hits[i]

    def counts(self):
        return np.array([len(p) for _, p in self._hits], dtype=np.int64)


def closest_pairs(points: np.ndarray, tris: np.ndarray):
    """The point of triangle `tris[i]` nearest to `points[i]` (Ericson's
    region test, float64), and its distance."""
    p = np.asarray(points, dtype=np.float64)
    a, b, c = (np.asarray(tris[:, k], dtype=np.float64) for k in range(3))
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = 1.0 / (va + vb + vc)
        res = a + ab * (vb * denom)[:, None] + ac * (vc * denom)[:, None]
        # Edge regions, then vertex regions (later assignments win).
        w_ab = d1 / (d1 - d3)
        res = np.where(((vc <= 0) & (d1 >= 0) & (d3 <= 0))[:, None], a + ab * w_ab[:, None], res)
        w_ac = d2 / (d2 - d6)
        res = np.where(((vb <= 0) & (d2 >= 0) & (d6 <= 0))[:, None], a + ac * w_ac[:, None], res)
        w_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        res = np.where(((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[:, None], b + (c - b) * w_bc[:, None], res)
    res = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, res)
    res = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, res)
    res = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, res)
    return np.linalg.norm(res - p, axis=-1), res


def closest_on_triangles(points: np.ndarray, tris: np.ndarray, chunk: int = 64):
    """The nearest surface point to each point, over every triangle that
    bounding spheres do not rule out: (distance (n,), prim (n,), point
    (n, 3), and the distance to the nearest triangle whose nearest point is
    elsewhere (n,), to tell clear answers from near ties; inf where none
    lies within 1e-4 of the extent past the nearest). Where triangles share
    the nearest point (an edge or a vertex), prim may be any of them."""
    tris = np.asarray(tris, dtype=np.float64)
    centre = tris.mean(axis=1)
    radius = np.linalg.norm(tris - centre[:, None], axis=-1).max(axis=1)
    slack = 1e-4 * float(np.ptp(tris.reshape(-1, 3), axis=0).max() if len(tris) else 1.0)
    out = ([], [], [], [])
    for s in range(0, len(points), chunk):
        p = np.asarray(points[s:s + chunk], dtype=np.float64)
        gap = np.linalg.norm(p[:, None] - centre[None], axis=-1)
        upper = (gap + radius[None]).min(axis=1)
        i, j = np.nonzero(gap - radius[None] <= upper[:, None] + slack)
        dist, res = closest_pairs(p[i], tris[j])
        for k in range(len(p)):
            mine = np.flatnonzero(i == k)
            order = mine[np.lexsort((j[mine], dist[mine]))]
            best = order[0]
            elsewhere = np.linalg.norm(res[order] - res[best], axis=1) > 1e-9
            out[0].append(dist[best])
            out[1].append(j[best])
            out[2].append(res[best])
            out[3].append(dist[order][elsewhere].min() if elsewhere.any() else np.inf)
    return np.array(out[0]), np.array(out[1], dtype=np.int64), np.array(out[2]).reshape(-1, 3), np.array(out[3])


def parity_inside(tris: np.ndarray, points: np.ndarray, rng, edge=1e-4):
    """Inside by the parity of crossings along a random ray per point, in
    float64, and whether that ray is clear of every edge (else the answer
    is not trusted and the point is left out)."""
    directions = random_directions(rng, len(points))
    brute = BruteHits(tris, points, directions, edge=edge)
    return brute.counts() % 2 == 1, brute.clear

#!/usr/bin/env python3
"""Check strata's ray-triangle intersection against Intel Embree (embreex).

    validate_embree.py MESH RAYS.bin HITS.bin [--occlusion OCC.bin] [--json REPORT.json]

MESH is an OBJ or PLY file, read here independently of strata but in
strata's triangle order (file order, polygons fan-triangulated). RAYS.bin comes from
`strata rays`, HITS.bin from `strata trace` and OCC.bin from `strata trace
--occlusion`. Embree traces the same rays against the same triangles
(closest hit and occlusion) and every ray is compared: hit or miss,
primitive id, t, barycentrics and occlusion.

Every disagreement is judged against the exact geometry, computed in double
precision from the same float32 vertices and rays:

* For the triangle an answer names, the ray is a *robust hit* if it crosses
  the triangle and passes no nearer to any of its edges than EDGE_TOL (1e-6)
  times the distance from the ray's origin to the triangle's farthest vertex;
  a *robust miss* if it misses by more than that; otherwise an *edge case*.
  The distance is between the ray's line and the edge segment, so the rule
  is the same at any scale and any offset from the origin: it is an angle
  seen from the ray's origin, which is what float rounding in a
  ray-centred triangle test depends on.
* A hit or miss answer is *valid* unless it names a robust miss, or the
  other answer names a robust hit nearer by more than T_TOL (1e-5)
  relative, or it is a miss and the other answer a robust hit. Two hits at
  equal t (coincident triangles) are both valid.
* Where both hit the same triangle, t is compared by how far off the
  surface the difference puts the hit point, and the barycentrics by how
  far across the ray they put it, both over the distance from the origin to
  the farthest vertex. These are the directions in which float32 can be
  accurate: along a grazing ray t is ill-conditioned (by 1/sin of the angle
  to the plane) for any implementation. An answer is valid within T_TOL and
  BARY_TOL (1e-5) of the exact value. The plain relative difference of t is
  reported too.
* An occlusion answer is valid if a triangle that either side reported backs
  it: occluded needs one that is not a robust miss, unoccluded needs none
  that is a robust hit.

A disagreement is *ambiguous* if both answers are valid, and *real*
otherwise. Real ones are split into "strata wrong" (strata's answer is
invalid; Embree's may be too) and "only Embree wrong".

For `edges` rays (aimed at a shared edge or vertex, reached at t = 1) the
table counts, for each side, rays whose first hit is beyond t = 1 + 1e-4:
rays that went through a crack. For `inside` rays it counts rays that
escaped without a hit. On a closed mesh both should be zero.

One table row per ray kind (from RAYS.bin.json, written by `strata rays`),
and a JSON report with per-kind counts and examples. Exit status: 0 if
strata is never wrong, 1 if it is, 2 for bad input.
"""

import argparse
import json
import os
import sys
import time
from fractions import Fraction

try:
    import numpy as np
except ImportError:
    print(
        "error: validate_embree.py needs numpy and embreex; create the environment with: "
        "python3 -m venv tools/.venv && tools/.venv/bin/pip install -r tools/requirements.txt "
        "and run it with tools/.venv/bin/python",
        file=sys.stderr,
    )
    sys.exit(2)

EDGE_TOL = 1e-6
T_TOL = 1e-5
BARY_TOL = 1e-5
# A ray "went through" its target if its first hit is beyond t_target by more than this (relative).
TARGET_TOL = 1e-4

EXIT_OK, EXIT_REAL, EXIT_INPUT = 0, 1, 2

ROBUST_MISS, EDGE_CASE, ROBUST_HIT = 0, 1, 2

HIT_DTYPE = np.dtype([("t", "<f4"), ("prim", "<u4"), ("u", "<f4"), ("v", "<f4")])
MISS_PRIM = np.uint32(0xFFFFFFFF)


class InputError(Exception):
    """Bad input: printed as one line, exit status 2."""

    def __init__(self, path, message):
        super().__init__(f"{path}: {message}")


# ---------------------------------------------------------------- reading


def parse_f32(tokens):
    """Decimal strings to float32, correctly rounded like Rust's `str::parse::<f32>`.

    Parsing to float64 and then rounding to float32 rounds twice, which is
    wrong only when the float64 lands exactly halfway between two float32
    values; those few are settled exactly with fractions.
    """
    wide = np.array(tokens, dtype=np.float64)
    narrow = wide.astype(np.float32)
    back = narrow.astype(np.float64)
    toward = np.nextafter(narrow, np.where(wide > back, np.inf, -np.inf).astype(np.float32))
    halfway = (wide != back) & (wide == (back + toward.astype(np.float64)) / 2)
    for i in np.flatnonzero(halfway):
        exact = Fraction(tokens[i])
        mid = Fraction(float(wide[i]))
        if exact != mid:
            lo, hi = sorted((narrow[i], toward[i]))
            narrow[i] = hi if exact > mid else lo
    return narrow


def load_obj(path):
    """Vertices (float32, (n, 3)) and triangles (int64, (m, 3)) in strata's order.

    `v` lines give positions (extra numbers, such as colours, are ignored);
    `f` lines are fan-triangulated and may use v, v/vt, v//vn or v/vt/vn with
    negative (relative) indices. Everything else is ignored, as strata does.
    """
    try:
        with open(path, "r", encoding="utf-8-sig") as f:
            lines = f.read().split("\n")
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}")
    except UnicodeDecodeError:
        raise InputError(path, "not UTF-8 text (is this really an OBJ file?)")
    coords = []
    faces = []
    nv = 0
    for number, line in enumerate(lines, 1):
        words = line.split()
        if not words:
            continue
        if words[0] == "v":
            if len(words) < 4:
                raise InputError(path, f"line {number}: a vertex needs 3 coordinates")
            coords.extend(words[1:4])
            nv += 1
        elif words[0] == "f":
            corners = []
            for token in words[1:]:
                try:
                    i = int(token.split("/")[0])
                except ValueError:
                    raise InputError(path, f"line {number}: '{token}' is not a face vertex")
                i = i - 1 if i > 0 else nv + i
                corners.append(i)
            if len(corners) < 3:
                raise InputError(path, f"line {number}: a face needs at least 3 vertices")
            for k in range(1, len(corners) - 1):
                faces.append((corners[0], corners[k], corners[k + 1]))
    try:
        vertices = parse_f32(coords).reshape(-1, 3)
    except ValueError:
        raise InputError(path, "a vertex coordinate is not a number")
    triangles = np.array(faces, dtype=np.int64).reshape(-1, 3)
    if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
        raise InputError(path, "a face refers to a vertex that does not exist")
    if not np.isfinite(vertices).all():
        raise InputError(path, "a vertex coordinate is not finite")
    return vertices, triangles


PLY_SCALARS = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def ply_header(path, data):
    """(format, [(element, count, [(name, type) or (name, (count type, item type))])], body offset)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise InputError(path, "not a PLY file (no 'ply' magic or no end_header)")
    body = data.index(b"\n", end) + 1
    fmt, elements = None, []
    for line in data[:end].decode("ascii", "replace").splitlines()[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format":
            fmt = w[1]
        elif w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property" and elements:
            if w[1] == "list":
                elements[-1][2].append((w[4], (PLY_SCALARS[w[2]], PLY_SCALARS[w[3]])))
            else:
                elements[-1][2].append((w[2], PLY_SCALARS[w[1]]))
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise InputError(path, f"unknown PLY format '{fmt}'")
    return fmt, elements, body


def fan(faces):
    """Fan-triangulate index lists as strata does: (p0, pk, pk+1)."""
    return [(f[0], f[k], f[k + 1]) for f in faces for k in range(1, len(f) - 1)]


def load_ply(path):
    """Vertices (float32, (n, 3)) and triangles (int64, (m, 3)) of a PLY file in strata's order.

    `vertex` x, y, z and the `face` vertex_indices (or vertex_index) list,
    fan-triangulated; other elements and properties are skipped. Binary
    faces that are all triangles with no other property are read in one
    numpy pass, the rest face by face.
    """
    try:
        data = open(path, "rb").read()
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}")
    try:
        fmt, elements, pos = ply_header(path, data)
    except (KeyError, IndexError, ValueError) as e:
        raise InputError(path, f"bad PLY header: {e}")
    vertices, faces = np.zeros((0, 3), np.float32), []
    triangles = None
    if fmt == "ascii":
        lines = data[pos:].decode("ascii", "replace").split("\n")
        row = 0
        for name, count, props in elements:
            rows = [l.split() for l in lines[row : row + count]]
            row += count
            if name == "vertex":
                cols = [i for i, (p, _) in enumerate(props) if p in ("x", "y", "z")]
                vertices = parse_f32([r[i] for r in rows for i in cols]).reshape(-1, 3)
            elif name == "face":
                faces = []
                for r in rows:
                    # Only a leading list is supported in ASCII, as written by every tool we know.
                    n = int(r[0])
                    faces.append([int(x) for x in r[1 : 1 + n]])
                triangles = np.array(fan(faces), dtype=np.int64).reshape(-1, 3)
    else:
        end = "<" if fmt == "binary_little_endian" else ">"
        for name, count, props in elements:
            lists = [p for p in props if isinstance(p[1], tuple)]
            if not lists:
                dtype = np.dtype([(p, end + t) for p, t in props])
                table = np.frombuffer(data, dtype, count, pos)
                pos += dtype.itemsize * count
                if name == "vertex":
                    vertices = np.stack([table[c] for c in "xyz"], axis=1).astype(np.float32)
                continue
            if name == "face" and len(props) == 1:
                n_type, i_type = props[0][1]
                tri = np.dtype([("n", end + n_type), ("v", end + i_type, (3,))])
                if pos + tri.itemsize * count <= len(data):
                    table = np.frombuffer(data, tri, count, pos)
                    if (table["n"] == 3).all():
                        triangles = table["v"].astype(np.int64)
                        pos += tri.itemsize * count
                        continue
            # General case: one record at a time.
            rows = []
            for _ in range(count):
                record = {}
                for p, t in props:
                    if isinstance(t, tuple):
                        n = int(np.frombuffer(data, end + t[0], 1, pos)[0])
                        pos += np.dtype(t[0]).itemsize
                        record[p] = np.frombuffer(data, end + t[1], n, pos).astype(np.int64).tolist()
                        pos += np.dtype(t[1]).itemsize * n
                    else:
                        pos += np.dtype(t).itemsize
                rows.append(record.get("vertex_indices", record.get("vertex_index", [])))
            if name == "face":
                triangles = np.array(fan(rows), dtype=np.int64).reshape(-1, 3)
    if triangles is None:
        triangles = np.zeros((0, 3), np.int64)
    if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
        raise InputError(path, "a face refers to a vertex that does not exist")
    if not np.isfinite(vertices).all():
        raise InputError(path, "a vertex coordinate is not finite")
    return vertices, triangles


def load_mesh(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return load_obj(path)
    if ext == ".ply":
        return load_ply(path)
    raise InputError(path, f"validate_embree.py reads .obj and .ply meshes only, not '{ext}'")


def read_records(path, dtype, what):
    try:
        data = open(path, "rb").read()
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}")
    if len(data) % dtype.itemsize:
        raise InputError(
            path,
            f"truncated {what} file: {len(data)} bytes is not a whole number of "
            f"{dtype.itemsize}-byte records",
        )
    return np.frombuffer(data, dtype=dtype)


def read_ray_file(path):
    data = read_records(path, np.dtype((np.dtype("<f4"), (8,))), "ray")
    rays = np.ascontiguousarray(data, dtype=np.float32).reshape(-1, 8)
    bad = ~np.isfinite(rays[:, :7]).all(axis=1) | (np.abs(rays[:, 3:6]).max(axis=1) == 0)
    bad |= np.isnan(rays[:, 7]) | (rays[:, 7] < rays[:, 6])
    if bad.any():
        raise InputError(path, f"ray {int(np.flatnonzero(bad)[0])}: not a usable ray")
    if (rays[:, 6] != 0).any():
        raise InputError(
            path,
            f"ray {int(np.flatnonzero(rays[:, 6] != 0)[0])}: tmin is not 0; "
            "embreex always starts rays at t = 0, so only such rays can be compared",
        )
    return rays


def read_hit_file(path, n):
    hits = read_records(path, HIT_DTYPE, "hit")
    if len(hits) != n:
        raise InputError(path, f"has {len(hits)} records for {n} rays")
    return hits


def read_groups(rays_path, n, kind):
    """(kind, first, count, target_t) runs from RAYS.bin.json, or one run of `kind`."""
    meta_path = rays_path + ".json"
    if kind is None and os.path.exists(meta_path):
        try:
            meta = json.load(open(meta_path))
            groups = [(g["kind"], g["first"], g["count"], g.get("target_t")) for g in meta["groups"]]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise InputError(meta_path, f"not a strata ray description: {e}")
        if sum(g[2] for g in groups) != n:
            raise InputError(meta_path, f"describes {sum(g[2] for g in groups)} rays, the ray file has {n}")
        return groups, bool(meta.get("closed", False))
    target = 1.0 if kind in ("edges", "grazing") else None
    return [(kind or "all", 0, n, target)], False


# ---------------------------------------------------------------- Embree


def trace_embree(vertices, triangles, rays, robust):
    """Closest hit and occlusion for every ray, with Embree."""
    try:
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
    except ImportError as e:
        raise InputError(
            sys.executable,
            f"cannot import embreex ({e}); create the environment with: python3 -m venv "
            "tools/.venv && tools/.venv/bin/pip install -r tools/requirements.txt",
        )

    scene = rtcs.EmbreeScene(robust=robust)
    if len(triangles):
        TriangleMesh(scene, vertices, triangles.astype(np.int32))
    origins = np.ascontiguousarray(rays[:, 0:3])
    directions = np.ascontiguousarray(rays[:, 3:6])
    # embreex writes each ray's tfar back into `dists`, so give it copies.
    closest = scene.run(origins, directions, dists=rays[:, 7].copy(), output=1)
    occluded = scene.run(origins, directions, dists=rays[:, 7].copy(), query="OCCLUDED")
    prim = closest["primID"]
    hit = prim >= 0
    return {
        "hit": hit,
        "prim": np.where(hit, prim, -1).astype(np.int64),
        "t": np.where(hit, closest["tfar"], np.inf).astype(np.float32),
        "u": np.where(hit, closest["u"], 0).astype(np.float32),
        "v": np.where(hit, closest["v"], 0).astype(np.float32),
        "occluded": occluded == 0,
    }


def strata_answers(hits, occlusion):
    hit = hits["prim"] != MISS_PRIM
    answers = {
        "hit": hit,
        "prim": np.where(hit, hits["prim"].astype(np.int64), -1),
        "t": hits["t"].copy(),
        "u": hits["u"].copy(),
        "v": hits["v"].copy(),
        "occluded": hit.copy() if occlusion is None else occlusion["prim"] != MISS_PRIM,
    }
    return answers


# ---------------------------------------------------------------- geometry in f64


def dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def line_segment_distance(o, d, a, b):
    """Distance between the line o + s d and the segment [a, b], and the s of the closest point."""
    e = b - a
    r = a - o
    dd = dot(d, d)
    ee = dot(e, e)
    de = dot(d, e)
    dr = dot(d, r)
    er = dot(e, r)
    denom = dd * ee - de * de
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(denom > 1e-300 * np.maximum(dd * ee, 1e-300), (de * dr - dd * er) / denom, 0.0)
    w = np.clip(np.nan_to_num(w), 0.0, 1.0)
    q = a + w[:, None] * e
    s = dot(q - o, d) / dd
    dist = np.linalg.norm(o + s[:, None] * d - q, axis=1)
    return dist, s


def oracle(tris, prim, rays):
    """The truth, in f64, about ray i and triangle prim[i] (prim < 0: none).

    Returns a dict of arrays: status (ROBUST_MISS, EDGE_CASE or ROBUST_HIT),
    t, u, v, scale (the distance from the origin to the farthest vertex) and
    thin (the triangle's inradius is below EDGE_TOL * scale, so every point
    of it is an edge case: it is degenerate at float32 precision).
    """
    n = len(prim)
    result = {
        "status": np.full(n, ROBUST_MISS, dtype=np.int8),
        "t": np.full(n, np.inf),
        "u": np.zeros(n),
        "v": np.zeros(n),
        "scale": np.ones(n),
        "thin": np.zeros(n, dtype=bool),
    }
    idx = np.flatnonzero((prim >= 0) & (prim < len(tris)))
    if len(idx) == 0:
        return result
    tri = tris[prim[idx]]
    o = rays[idx, 0:3].astype(np.float64)
    d = rays[idx, 3:6].astype(np.float64)
    tmin = rays[idx, 6].astype(np.float64)
    tmax = rays[idx, 7].astype(np.float64)
    v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
    scale = np.max(np.stack([np.linalg.norm(x - o, axis=1) for x in (v0, v1, v2)]), axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    tol = EDGE_TOL * scale

    # Moller-Trumbore in double precision.
    e1 = v1 - v0
    e2 = v2 - v0
    p = np.cross(d, e2)
    det = dot(e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - v0
        bu = dot(s, p) * inv
        q = np.cross(s, e1)
        bv = dot(d, q) * inv
        tt = dot(e2, q) * inv
        # A crossing within rounding of either end of the interval is an
        # edge case too: strata's interval is open, Embree's closed, and a
        # ray that starts on a surface may or may not hit it at t = 0.
        slack = tol / np.linalg.norm(d, axis=1)
    inside = (det != 0) & (bu >= 0) & (bv >= 0) & (bu + bv <= 1)
    crossing = inside & (tt > tmin + slack) & (tt < tmax - slack)
    at_end = inside & ~crossing & (tt >= tmin - slack) & (tt <= tmax + slack)

    # Nearest approach to any edge, as a fraction of the scale.
    near = np.zeros(len(idx), dtype=bool)
    t_near = np.full(len(idx), np.inf)
    best = np.full(len(idx), np.inf)
    for a, b in ((v0, v1), (v1, v2), (v2, v0)):
        dist, s_edge = line_segment_distance(o, d, a, b)
        ok = (dist <= tol) & (s_edge >= tmin - slack) & (s_edge <= tmax + slack)
        near |= ok
        closer = ok & (dist < best)
        best = np.where(closer, dist, best)
        t_near = np.where(closer, s_edge, t_near)
    edge = near | at_end
    perimeter = np.linalg.norm(e1, axis=1) + np.linalg.norm(e2, axis=1) + np.linalg.norm(v2 - v1, axis=1)
    inradius = np.linalg.norm(np.cross(e1, e2), axis=1) / np.where(perimeter > 0, perimeter, 1.0)

    result["status"][idx] = np.where(edge, EDGE_CASE, np.where(crossing, ROBUST_HIT, ROBUST_MISS))
    t_plane = np.where(np.isfinite(tt) & (det != 0), tt, t_near)
    result["t"][idx] = np.where(crossing | edge, t_plane, np.inf)
    result["u"][idx] = np.nan_to_num(bu)
    result["v"][idx] = np.nan_to_num(bv)
    result["scale"][idx] = scale
    result["thin"][idx] = inradius <= tol
    return result


# ---------------------------------------------------------------- comparison

# What a mismatch is: a disagreement beyond tolerance, judged against the f64 truth.
CHECKS = ("hitmiss", "prim", "t", "bary", "occlusion")


def validity(a, b, oa, ob):
    """Whether answer a's hit or miss is valid, given the other answer b and
    the oracle's results oa, ob for the triangles they name."""
    status_a, t_a = oa["status"], oa["t"]
    status_b, t_b = ob["status"], ob["t"]
    ok = np.where(a["hit"], status_a != ROBUST_MISS, True)
    b_nearer = b["hit"] & (status_b == ROBUST_HIT) & (~a["hit"] | (t_b < t_a * (1 - T_TOL)))
    return ok & ~b_nearer


def hit_errors(tris, rays, ans, truth, prim):
    """t and barycentric errors of `ans` against `truth` for triangle `prim`,
    as backward errors: times the cosine of the angle between the ray and the
    triangle's normal, over the distance from the origin to the farthest
    vertex. A ray-triangle test in float32 rounds the vertices (relative to
    the origin) by about 1e-7 of that distance; a grazing ray turns such a
    rounding into a large move of the hit point along the surface, by
    1/cos. Dividing that out judges every answer by what float32 can do.

    t: the distance between the two hit points along the ray; barycentrics:
    the distance between the points they give. Returns (t_err, bary_err).
    """
    corners = tris[np.where(prim >= 0, prim, 0)] if len(tris) else np.zeros((len(prim), 3, 3))
    d = rays[:, 3:6].astype(np.float64)
    dlen = np.linalg.norm(d, axis=1)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    scale = truth["scale"]

    def point(u, v):
        u = np.asarray(u, dtype=np.float64)[:, None]
        v = np.asarray(v, dtype=np.float64)[:, None]
        return (1 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]

    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(dot(d, normal)) / (dlen * np.linalg.norm(normal, axis=1))
        t_err = np.abs(ans["t"] - truth["t"]) * dlen * cos / scale
        gap = np.linalg.norm(point(ans["u"], ans["v"]) - point(truth["u"], truth["v"]), axis=1)
        bary_err = gap * cos / scale
    ok = prim >= 0
    return (
        np.where(ok, np.nan_to_num(t_err, nan=np.inf), 0.0),
        np.where(ok, np.nan_to_num(bary_err, nan=np.inf), 0.0),
    )


def compare(tris, rays, s, e):
    """For each check, per-ray masks: `mismatch`, `strata` (strata's answer
    is invalid) and `embree` (only Embree's is); plus error arrays."""
    os_ = oracle(tris, s["prim"], rays)
    oe = oracle(tris, e["prim"], rays)
    out = {}

    # Hit or miss, and which triangle.
    valid_s = validity(s, e, os_, oe)
    valid_e = validity(e, s, oe, os_)
    hitmiss = s["hit"] != e["hit"]
    prim = s["hit"] & e["hit"] & (s["prim"] != e["prim"])
    for name, mask in (("hitmiss", hitmiss), ("prim", prim)):
        out[name] = {"mismatch": mask, "strata": mask & ~valid_s, "embree": mask & valid_s & ~valid_e}

    # t and barycentrics, where both hit the same triangle.
    same = s["hit"] & e["hit"] & (s["prim"] == e["prim"])
    prim_same = np.where(same, s["prim"], -1)
    t_s, bary_s = hit_errors(tris, rays, s, os_, prim_same)
    t_e, bary_e = hit_errors(tris, rays, e, os_, prim_same)
    t_se, bary_se = hit_errors(tris, rays, s, {**os_, "t": e["t"], "u": e["u"], "v": e["v"]}, prim_same)
    # The plain relative difference of t (for information), where it means
    # something: not at t = 0, not on a triangle degenerate in float32.
    plain = same & ~os_["thin"] & (e["t"] > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        t_rel = np.where(plain, np.abs(s["t"] - e["t"].astype(np.float64)) / np.abs(e["t"]), 0.0)
    # On a triangle degenerate at float32 precision t and the barycentrics
    # mean nothing: there, both answers are valid.
    judged = same & ~os_["thin"]
    for name, between, err_s, err_e, tol in (("t", t_se, t_s, t_e, T_TOL), ("bary", bary_se, bary_s, bary_e, BARY_TOL)):
        mask = same & (between > tol)
        out[name] = {
            "mismatch": mask,
            "strata": mask & judged & (err_s > tol),
            "embree": mask & judged & (err_s <= tol) & (err_e > tol),
        }

    # Occlusion: an answer is valid if the triangles either side reported back it.
    occ = s["occluded"] != e["occluded"]
    any_robust = (s["hit"] & (os_["status"] == ROBUST_HIT)) | (e["hit"] & (oe["status"] == ROBUST_HIT))
    any_possible = (s["hit"] & (os_["status"] != ROBUST_MISS)) | (e["hit"] & (oe["status"] != ROBUST_MISS))
    occ_valid_s = np.where(s["occluded"], any_possible, ~any_robust)
    occ_valid_e = np.where(e["occluded"], any_possible, ~any_robust)
    out["occlusion"] = {"mismatch": occ, "strata": occ & ~occ_valid_s, "embree": occ & occ_valid_s & ~occ_valid_e}

    out["errors"] = {
        "same": same,
        "t_rel": np.nan_to_num(t_rel, nan=np.inf),
        "t_strata": t_s,
        "t_embree": t_e,
        "bary_strata": bary_s,
        "bary_embree": bary_e,
        "status_strata": os_["status"],
        "status_embree": oe["status"],
    }
    return out


def summarize(kind, sl, target_t, s, e, c):
    """One table row (a dict) for rays sl."""

    def n(mask):
        return int(np.count_nonzero(mask[sl]))

    def largest(x):
        return float(x[sl].max(initial=0.0))

    err = c["errors"]
    row = {
        "kind": kind,
        "rays": sl.stop - sl.start,
        "hits_strata": n(s["hit"]),
        "hits_embree": n(e["hit"]),
        "same_prim_hits": n(err["same"]),
    }
    for check in CHECKS:
        m = c[check]
        row[check] = {
            "mismatches": n(m["mismatch"]),
            "ambiguous": n(m["mismatch"] & ~m["strata"] & ~m["embree"]),
            "real_strata": n(m["strata"]),
            "real_embree": n(m["embree"]),
        }
    row["t_rel_max"] = largest(err["t_rel"])
    row["t_err_strata_max"] = largest(err["t_strata"])
    row["t_err_embree_max"] = largest(err["t_embree"])
    row["bary_err_strata_max"] = largest(err["bary_strata"])
    row["bary_err_embree_max"] = largest(err["bary_embree"])
    if kind == "edges" and target_t is not None:
        limit = np.float32(target_t * (1 + TARGET_TOL))
        row["through_strata"] = n(s["t"] > limit)
        row["through_embree"] = n(e["t"] > limit)
    if kind == "inside":
        row["escaped_strata"] = n(~s["hit"])
        row["escaped_embree"] = n(~e["hit"])
    row["real"] = sum(row[check]["real_strata"] for check in CHECKS)
    row["real_embree"] = sum(row[check]["real_embree"] for check in CHECKS)
    return row


STATUS_NAMES = {ROBUST_MISS: "robust miss", EDGE_CASE: "edge case", ROBUST_HIT: "robust hit"}


def answer(a, i, status):
    if not a["hit"][i]:
        return {"hit": False, "occluded": bool(a["occluded"][i])}
    return {
        "hit": True,
        "prim": int(a["prim"][i]),
        "t": float(a["t"][i]),
        "u": float(a["u"][i]),
        "v": float(a["v"][i]),
        "occluded": bool(a["occluded"][i]),
        "f64": STATUS_NAMES[int(status)],
    }


def examples(sl, rays, s, e, c, side, limit):
    """Up to `limit` real mismatches in rays sl where `side` is wrong."""
    err = c["errors"]
    wrong = np.zeros(len(rays), dtype=bool)
    for check in CHECKS:
        wrong |= c[check][side]
    out = []
    for i in np.flatnonzero(wrong[sl])[:limit] + sl.start:
        i = int(i)
        out.append(
            {
                "ray": i,
                "checks": [check for check in CHECKS if c[check][side][i]],
                "ray_record": [float(x) for x in rays[i]],
                "strata": answer(s, i, err["status_strata"][i]),
                "embree": answer(e, i, err["status_embree"][i]),
                "t_rel": float(err["t_rel"][i]),
                "t_err_strata": float(err["t_strata"][i]),
                "t_err_embree": float(err["t_embree"][i]),
                "bary_err_strata": float(err["bary_strata"][i]),
                "bary_err_embree": float(err["bary_embree"][i]),
            }
        )
    return out


# ---------------------------------------------------------------- output


def json_safe(x):
    """The report with non-finite floats as strings ("inf"), so it is strict JSON."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, list):
        return [json_safe(v) for v in x]
    if isinstance(x, float) and not np.isfinite(x):
        return str(x)
    return x


HEADER = [
    "kind",
    "rays",
    "hits S/E",
    "hit/miss a/S/E",
    "prim a/S/E",
    "occl a/S/E",
    "t a/S/E",
    "bary a/S/E",
    "t rel max",
    "t err S/E",
    "bary err S/E",
    "through S/E",
    "escaped S/E",
]


def cells(row):
    def split(check):
        r = row[check]
        return f"{r['ambiguous']}/{r['real_strata']}/{r['real_embree']}"

    def pair(a, b, fmt="{}"):
        return (fmt + "/" + fmt).format(row[a], row[b]) if a in row else "-"

    return [
        row["kind"],
        str(row["rays"]),
        pair("hits_strata", "hits_embree"),
        split("hitmiss"),
        split("prim"),
        split("occlusion"),
        split("t"),
        split("bary"),
        f"{row['t_rel_max']:.1e}",
        pair("t_err_strata_max", "t_err_embree_max", "{:.0e}"),
        pair("bary_err_strata_max", "bary_err_embree_max", "{:.0e}"),
        pair("through_strata", "through_embree"),
        pair("escaped_strata", "escaped_embree"),
    ]


def print_table(title, rows, out=sys.stdout):
    table = [HEADER] + [cells(r) for r in rows]
    widths = [max(len(line[k]) for line in table) for k in range(len(HEADER))]
    print(title, file=out)
    for line in table:
        print("  " + "  ".join(x.rjust(w) if k else x.ljust(w) for k, (x, w) in enumerate(zip(line, widths))), file=out)
    print(
        "  a/S/E: ambiguous (both answers valid) / real, strata wrong / real, only Embree wrong; "
        "errors are against f64 (see --help)",
        file=out,
    )


def main(argv=None):
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("mesh", help="OBJ or PLY mesh that strata traced")
    ap.add_argument("rays", help="ray file from `strata rays` (RAYS.bin; RAYS.bin.json names the kinds)")
    ap.add_argument("hits", help="hit file from `strata trace` (closest hits)")
    ap.add_argument("--occlusion", metavar="OCC.bin", help="hit file from `strata trace --occlusion`; without it strata's occlusion answers are taken from HITS.bin")
    ap.add_argument("--json", metavar="REPORT.json", help="write the report here (default: HITS.bin.report.json)")
    ap.add_argument("--kind", help="treat every ray as this kind, ignoring RAYS.bin.json")
    ap.add_argument("--examples", type=int, default=5, metavar="N", help="real mismatches per kind to list in the report (default 5)")
    ap.add_argument("--no-robust", action="store_true", help="build Embree's scene without RTC_SCENE_FLAG_ROBUST (embreex sets it by default)")
    ap.add_argument("--quiet", action="store_true", help="no table")
    args = ap.parse_args(argv)

    start = time.time()
    try:
        vertices, triangles = load_mesh(args.mesh)
        rays = read_ray_file(args.rays)
        hits = read_hit_file(args.hits, len(rays))
        occ = read_hit_file(args.occlusion, len(rays)) if args.occlusion else None
        groups, closed = read_groups(args.rays, len(rays), args.kind)
    except InputError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_INPUT
    loaded = time.time()

    s = strata_answers(hits, occ)
    bad_prim = s["hit"] & (s["prim"] >= len(triangles))
    if bad_prim.any():
        print(f"error: {args.hits}: ray {int(np.flatnonzero(bad_prim)[0])} names primitive "
              f"{int(s['prim'][bad_prim][0])}, but the mesh has {len(triangles)} triangles", file=sys.stderr)
        return EXIT_INPUT
    try:
        e = trace_embree(vertices, triangles, rays, robust=not args.no_robust)
    except InputError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_INPUT
    traced = time.time()
    tris = vertices.astype(np.float64)[triangles] if len(triangles) else np.zeros((0, 3, 3))
    c = compare(tris, rays, s, e)

    rows, report_examples = [], {}
    for kind, first, count, target_t in groups:
        sl = slice(first, first + count)
        rows.append(summarize(kind, sl, target_t, s, e, c))
        report_examples[kind] = {
            "strata_wrong": examples(sl, rays, s, e, c, "strata", args.examples),
            "embree_wrong": examples(sl, rays, s, e, c, "embree", args.examples),
        }
    total_real = sum(r["real"] for r in rows)
    total_embree = sum(r["real_embree"] for r in rows)

    from embreex import rtcore

    report = {
        "mesh": args.mesh,
        "triangles": int(len(triangles)),
        "closed": closed,
        "rays": int(len(rays)),
        "embree": "Embree " + repr(rtcore.EmbreeDevice()).split(":")[-1].strip(),
        "embree_robust": not args.no_robust,
        "tolerances": {"edge": EDGE_TOL, "t": T_TOL, "bary": BARY_TOL, "target": TARGET_TOL},
        "kinds": rows,
        "real": total_real,
        "real_embree": total_embree,
        "examples": report_examples,
        "seconds": {"load": loaded - start, "embree": traced - loaded, "compare": time.time() - traced},
    }
    json_path = args.json or args.hits + ".report.json"
    try:
        with open(json_path, "w") as f:
            json.dump(json_safe(report), f, indent=1, allow_nan=False)
    except OSError as err:
        print(f"error: {json_path}: cannot write: {err.strerror}", file=sys.stderr)
        return EXIT_INPUT
    if not args.quiet:
        print_table(f"{args.mesh}: {len(triangles)} triangles, {len(rays)} rays, strata (S) vs {report['embree']} (E)", rows)
        print(f"  {total_real} real mismatches where strata is wrong, {total_embree} where only Embree is; report -> {json_path}")
    return EXIT_REAL if total_real else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())

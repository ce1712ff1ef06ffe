#!/usr/bin/env python3
"""strata_rt.open3d.RaycastingScene against Open3D's own, query by query.

Usage: python tools/compare_open3d.py [MESH ...]   (default assets/bunny.obj)

Needs Open3D (``pip install open3d``; Debian's libusb-1.0-0) and strata_rt
in the same interpreter. Each mesh is added to both scenes twice (the
second copy moved along x, so geometry ids matter), and both answer the
same rays and points: random chords through the bounding box, a pinhole
camera in both of Open3D's forms, and random points. It prints, per
query, how many answers agree and the largest difference; what differs
on purpose (Open3D counts a ray through a shared edge or vertex twice or
not at all, strata once) shows as a few rays in the counts and lists.
Not a test: the suite checks strata_rt's answers without Open3D.
"""

import sys
from pathlib import Path

import numpy as np
import open3d as o3d

from strata_rt.open3d import RaycastingScene

REPO = Path(__file__).resolve().parents[1]


def load(path):
    m = o3d.io.read_triangle_mesh(str(path))
    return np.asarray(m.vertices, dtype=np.float32), np.asarray(m.triangles, dtype=np.uint32)


def report(name, agree, n, extra=""):
    print(f"  {name:<34} {agree:>8}/{n:<8} {100.0 * agree / max(n, 1):8.4f}%  {extra}")


def compare(path, n_rays=200_000, n_points=50_000, seed=5):
    v, f = load(path)
    shift = np.float32([1.5 * (v[:, 0].max() - v[:, 0].min()), 0, 0])
    ours, theirs = RaycastingScene(), o3d.t.geometry.RaycastingScene()
    for vv in (v, v + shift):
        assert ours.add_triangles(vv, f) == theirs.add_triangles(vv, f)
    rng = np.random.default_rng(seed)
    lo, hi = v.min(0), (v + shift).max(0)
    grow = 0.1 * (hi - lo)
    o = rng.uniform(lo - grow, hi + grow, (n_rays, 3))
    d = rng.normal(size=(n_rays, 3))
    rays = np.hstack([o, d]).astype(np.float32)
    print(f"{path.name}: {len(f)} triangles x 2, {n_rays} rays, {n_points} points")

    a, b = ours.cast_rays(rays), {k: x.numpy() for k, x in theirs.cast_rays(rays).items()}
    both = np.isfinite(a["t_hit"]) & np.isfinite(b["t_hit"])
    report("cast_rays: hit or miss", int((np.isfinite(a["t_hit"]) == np.isfinite(b["t_hit"])).sum()), n_rays)
    same = both & (a["geometry_ids"] == b["geometry_ids"]) & (a["primitive_ids"] == b["primitive_ids"])
    report("cast_rays: geometry and primitive", int(same.sum()), int(both.sum()))
    rel = np.abs(a["t_hit"][both] - b["t_hit"][both]) / np.maximum(b["t_hit"][both], 1e-30)
    report("cast_rays: t_hit within 1e-5", int((rel < 1e-5).sum()), int(both.sum()), f"max rel {rel.max():.2e}")
    du = np.abs(a["primitive_uvs"][same] - b["primitive_uvs"][same]).max()
    dn = np.abs(a["primitive_normals"][same] - b["primitive_normals"][same]).max()
    report("cast_rays: uvs, normals", int(same.sum()), int(same.sum()), f"max diff {du:.2e}, {dn:.2e}")
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
    occ_a, occ_b = ours.test_occlusions(rays), theirs.test_occlusions(rays).numpy()
    report("test_occlusions", int((occ_a == occ_b).sum()), n_rays)
    occ_a = ours.test_occlusions(rays, tnear=0.5, tfar=2.0)
    occ_b = theirs.test_occlusions(rays, tnear=0.5, tfar=2.0).numpy()
    report("test_occlusions tnear 0.5 tfar 2", int((occ_a == occ_b).sum()), n_rays)
    c_a, c_b = ours.count_intersections(rays), theirs.count_intersections(rays).numpy()
    assert c_a.dtype == c_b.dtype
    report("count_intersections", int((c_a == c_b).sum()), n_rays)
    la = ours.list_intersections(rays[:20_000])
    lb = {k: x.numpy() for k, x in theirs.list_intersections(rays[:20_000]).items()}
    for k in la:
        assert la[k].dtype == lb[k].dtype, k
    same_rays = np.flatnonzero(np.diff(la["ray_splits"]) == np.diff(lb["ray_splits"]))
    report("list_intersections: counts", len(same_rays), 20_000)
    if len(la["t_hit"]) == len(lb["t_hit"]):
        ok = (la["primitive_ids"] == lb["primitive_ids"]) & (la["geometry_ids"] == lb["geometry_ids"])
        report("list_intersections: ids", int(ok.sum()), len(ok),
               f"uv max diff {np.abs(la['primitive_uvs'][ok] - lb['primitive_uvs'][ok]).max():.2e}")

    p = rng.uniform(lo - grow, hi + grow, (n_points, 3)).astype(np.float32)
    ca = ours.compute_closest_points(p)
    cb = {k: x.numpy() for k, x in theirs.compute_closest_points(p).items()}
    for k in ca:
        assert ca[k].dtype == cb[k].dtype and ca[k].shape == cb[k].shape, k
    same = (ca["geometry_ids"] == cb["geometry_ids"]) & (ca["primitive_ids"] == cb["primitive_ids"])
    report("closest: same face", int(same.sum()), n_points)
    dp = np.linalg.norm(ca["points"] - cb["points"], axis=1)
    report("closest: point within 1e-5", int((dp < 1e-5).sum()), n_points, f"max {dp.max():.2e}")
    da, db = ours.compute_distance(p), theirs.compute_distance(p).numpy()
    report("compute_distance within 1e-6", int((np.abs(da - db) < 1e-6).sum()), n_points)
    sa, sb = ours.compute_signed_distance(p), theirs.compute_signed_distance(p).numpy()
    report("compute_signed_distance: sign", int((np.sign(sa) == np.sign(sb)).sum()), n_points)
    oa, ob = ours.compute_occupancy(p, nsamples=3), theirs.compute_occupancy(p, nsamples=3).numpy()
    report("compute_occupancy nsamples=3", int((oa == ob).sum()), n_points)

    k = np.array([[300.0, 0, 160], [0, 300, 120], [0, 0, 1]])
    e = np.eye(4)
    e[:3, 3] = -(v.mean(0) + np.float32([0, 0, 3 * (hi - lo).max()]))
    # With open3d imported, strata_rt answers tensors here, as Open3D does.
    ra = RaycastingScene.create_rays_pinhole(k, e, 320, 240).numpy()
    rb = o3d.t.geometry.RaycastingScene.create_rays_pinhole(k, e, 320, 240).numpy()
    print(f"  create_rays_pinhole (matrices): max diff {np.abs(ra - rb).max():.2e}")
    args = dict(fov_deg=60, center=v.mean(0), eye=v.mean(0) + 2 * (hi - lo), up=[0, 1, 0], width_px=320, height_px=240)
    ra = RaycastingScene.create_rays_pinhole(**args).numpy()
    rb = o3d.t.geometry.RaycastingScene.create_rays_pinhole(**args).numpy()
    print(f"  create_rays_pinhole (fov):      max diff {np.abs(ra - rb).max():.2e}")
    ta, tb = ours.cast_rays(ra)["t_hit"], theirs.cast_rays(rb)["t_hit"].numpy()
    report("pinhole image: hit or miss", int((np.isfinite(ta) == np.isfinite(tb)).sum()), ta.size)


if __name__ == "__main__":
    paths = [Path(p) for p in sys.argv[1:]] or [REPO / "assets" / "bunny.obj"]
    for path in paths:
        compare(path)

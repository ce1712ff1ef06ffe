"""strata_rt.open3d.RaycastingScene: Open3D's interface, strata's answers.

Without Open3D: analytic boxes and spheres, float64 brute force, the keys,
dtypes, shapes and invalid ids Open3D documents, and Open3D tensors
played by a stand-in module (tools/compare_open3d.py compares the answers
with Open3D's own where it is installed). The few tests that take the
``o3d`` fixture compare with Open3D itself and skip without it: its
tutorial, non-finite query points, a ray from a surface.
"""

import math
import sys
import types

import numpy as np
import pytest

import helpers
import strata_rt
from strata_rt.open3d import INVALID_ID, RaycastingScene

#: The real Open3D module once a test has imported it.
_OPEN3D = {}


@pytest.fixture(autouse=True)
def open3d_unloaded(monkeypatch):
    """Open3D as not imported, for the test's length: create_rays_pinhole
    answers in Open3D tensors where it is (sys.modules), and the tests
    that do not ask for it (the ``o3d`` fixture) check numpy answers."""
    loaded = sys.modules.get("open3d")
    if getattr(loaded, "__file__", None):  # the real one, not a stand-in
        _OPEN3D.setdefault("module", loaded)
    monkeypatch.delitem(sys.modules, "open3d", raising=False)


@pytest.fixture
def o3d(open3d_unloaded):
    """The real Open3D, imported for the test's length (skips where it is
    not installed); the tests after it, here and in other files (the docs'
    numpy examples), find it as they would have: not imported."""
    module = _OPEN3D.get("module")
    if module is None:
        # ImportError too: an Open3D that is installed but cannot load (it needs libusb) skips.
        module = pytest.importorskip(
            "open3d", reason="Open3D (tools/requirements-bench.txt) to compare with", exc_type=ImportError
        )
        _OPEN3D["module"] = module
    sys.modules["open3d"] = module
    yield module
    # Before the autouse fixture's undo, which puts it back where it was.
    sys.modules.pop("open3d", None)


CAST_KEYS = {"t_hit": np.float32, "geometry_ids": np.uint32, "primitive_ids": np.uint32,
             "primitive_uvs": np.float32, "primitive_normals": np.float32}


def two_boxes():
    """The unit cube [0, 1]³ (geometry 0) and the same moved by 3 along x (1)."""
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    scene = RaycastingScene()
    assert scene.add_triangles(v.astype(np.float32), f.astype(np.uint32)) == 0
    assert scene.add_triangles(v + [3, 0, 0], f) == 1
    return scene, v, f


def test_cast_rays_keys_dtypes_shapes_and_misses():
    scene, v, f = two_boxes()
    rays = np.array([
        [0.25, 0.5, 5, 0, 0, -1],    # box 0, top face, t = 4
        [3.5, 0.25, -2, 0, 0, 2],    # box 1, bottom face, t = 1 (direction length 2)
        [10, 10, 10, 0, 0, -1],      # nothing
        [np.nan, 0, 0, 1, 0, 0],     # a NaN origin: a miss, as in Open3D
        [0.5, 0.5, 5, 0, 0, 0],      # a zero direction: a miss
    ], dtype=np.float32)
    ans = scene.cast_rays(rays)
    assert {k: a.dtype.type for k, a in ans.items()} == CAST_KEYS
    assert ans["t_hit"].shape == (5,) and ans["primitive_uvs"].shape == (5, 2) and ans["primitive_normals"].shape == (5, 3)
    np.testing.assert_allclose(ans["t_hit"][:2], [4.0, 1.0], rtol=1e-6)
    assert np.isinf(ans["t_hit"][2:]).all()
    assert ans["geometry_ids"].tolist() == [0, 1, INVALID_ID, INVALID_ID, INVALID_ID]
    assert (ans["primitive_ids"][2:] == INVALID_ID).all()
    # Faces 10, 11 are z = hi (outward +z), 8, 9 z = lo (-z), per geometry.
    assert ans["primitive_ids"][0] in (10, 11) and ans["primitive_ids"][1] in (8, 9)
    np.testing.assert_allclose(ans["primitive_normals"][:2], [[0, 0, 1], [0, 0, -1]], atol=1e-7)
    assert (ans["primitive_normals"][2:] == 0).all() and (ans["primitive_uvs"][2:] == 0).all()
    # The uvs weigh the face's corners to the hit point.
    for i, g in [(0, 0), (1, 1)]:
        tri = (v + [3 * g, 0, 0])[f[ans["primitive_ids"][i]]]
        u, w = ans["primitive_uvs"][i]
        point = (1 - u - w) * tri[0] + u * tri[1] + w * tri[2]
        np.testing.assert_allclose(point, rays[i, :3] + ans["t_hit"][i] * rays[i, 3:], atol=1e-6)
    assert RaycastingScene.INVALID_ID == INVALID_ID == 2**32 - 1


def test_one_geometry_s_ids_are_its_own_faces_and_invalid_on_a_miss():
    """A scene of one geometry takes a shortcut to its ids (its faces are
    the scene's): the same ids as a scene of two gives its first box."""
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    one = RaycastingScene()
    assert one.add_triangles(v.astype(np.float32), f.astype(np.uint32)) == 0
    two, *_ = two_boxes()
    rays = np.array([
        [0.25, 0.5, 5, 0, 0, -1],    # the top face, then the bottom one
        [0.5, -3, 0.75, 0, 1, 0],    # front face, then the back face
        [10, 10, 10, 0, 0, -1],      # nothing
        [np.nan, 0, 0, 1, 0, 0],     # a NaN origin: a miss
    ], dtype=np.float32)
    for query in ("cast_rays", "list_intersections"):
        mine, theirs = getattr(one, query)(rays), getattr(two, query)(rays)
        for key in ("geometry_ids", "primitive_ids"):
            assert mine[key].dtype == np.uint32
            np.testing.assert_array_equal(mine[key], theirs[key])
    ans = one.cast_rays(rays)
    assert ans["geometry_ids"].tolist() == [0, 0, INVALID_ID, INVALID_ID]
    assert (ans["primitive_ids"][2:] == INVALID_ID).all() and (ans["primitive_ids"][:2] < len(f)).all()
    assert one.list_intersections(rays)["geometry_ids"].tolist() == [0, 0, 0, 0]  # in and out of the box


def test_rays_of_any_leading_shape_answer_in_that_shape():
    scene, *_ = two_boxes()
    rays = RaycastingScene.create_rays_pinhole(fov_deg=60, center=[2, 0.5, 0.5], eye=[2, -6, 0.5],
                                               up=[0, 0, 1], width_px=8, height_px=6)
    ans = scene.cast_rays(rays)
    assert ans["t_hit"].shape == (6, 8) and ans["primitive_uvs"].shape == (6, 8, 2)
    flat = scene.cast_rays(rays.reshape(-1, 6))
    for k in ans:
        np.testing.assert_array_equal(ans[k].reshape(flat[k].shape), flat[k])
    deep = scene.count_intersections(rays.reshape(2, 3, 8, 6))
    assert deep.shape == (2, 3, 8) and deep.dtype == np.int32
    assert scene.test_occlusions(rays[0, 0]).shape == ()
    assert scene.compute_distance(np.zeros((2, 2, 2, 3))).shape == (2, 2, 2)


def test_occlusions_between_tnear_and_tfar():
    scene, *_ = two_boxes()
    # Along +x at y = z = 0.5 from x = -1: box 0 over t in [1, 2], box 1 over [4, 5].
    rays = np.tile([-1, 0.5, 0.5, 1, 0, 0], (6, 1))
    cases = [(0, np.inf, True), (0, 0.5, False), (2.5, 3.5, False), (2.5, 4.5, True), (5.5, np.inf, False), (0.5, 1.0, True)]
    for ray, (near, far, blocked) in zip(rays, cases):
        got = scene.test_occlusions(ray[None], tnear=near, tfar=far)
        assert got.dtype == np.bool_ and bool(got[0]) == blocked, (near, far)
    with pytest.raises(ValueError, match="tnear"):
        scene.test_occlusions(rays, tnear=-1)


def test_counts_and_lists_agree_with_each_other_and_with_brute_force(bumpy):
    v, f = bumpy
    scene = RaycastingScene()
    scene.add_triangles(v, f)
    scene.add_triangles(v + [2.5, 0, 0], f)
    tris = np.concatenate([v[f], (v + [2.5, 0, 0])[f]])
    rng = np.random.default_rng(2)
    o, d = helpers.random_rays(rng, np.vstack([v, v + [2.5, 0, 0]]), 400)
    rays = np.hstack([o, d])
    counts = scene.count_intersections(rays)
    lx = scene.list_intersections(rays)
    assert {k: a.dtype for k, a in lx.items()} == {
        "ray_splits": np.uint32, "ray_ids": np.uint32, "t_hit": np.float32,
        "geometry_ids": np.uint32, "primitive_ids": np.uint32, "primitive_uvs": np.float32}
    splits = lx["ray_splits"].astype(np.int64)
    np.testing.assert_array_equal(np.diff(splits), counts)
    np.testing.assert_array_equal(lx["ray_ids"], np.repeat(np.arange(len(rays)), counts))
    # Each ray's crossings nearest first; some rays cross both spheres.
    assert counts.max() >= 4
    for a, b in zip(splits[:-1], splits[1:]):
        assert (np.diff(lx["t_hit"][a:b]) >= 0).all()
    # Each crossing is on the face it names: brute force of that pair.
    face = lx["primitive_ids"].astype(np.int64) + len(f) * lx["geometry_ids"]
    t, u, w = helpers.ray_triangle_pairs(tris, o, d, lx["ray_ids"], face)
    np.testing.assert_allclose(lx["t_hit"], t, rtol=1e-5, atol=1e-6)
    # (strata traces the rays rounded to float32: uvs to that rounding,
    # which the slivers at the bumpy sphere's poles magnify)
    np.testing.assert_allclose(lx["primitive_uvs"], np.stack([u, w], 1).clip(0, 1), atol=2e-4)
    assert np.median(np.abs(lx["primitive_uvs"] - np.stack([u, w], 1).clip(0, 1))) < 1e-5
    # The count is the brute-force count on rays clear of every edge.
    r, p = helpers.candidates(tris, o, d)
    t, u, w = helpers.ray_triangle_pairs(tris, o, d, r, p)
    m = helpers.margin(u, w)
    clear = np.ones(len(rays), bool)
    clear[r[np.abs(m) < 1e-5]] = False
    brute = np.bincount(r[(m > 0) & (t > 0)], minlength=len(rays))
    np.testing.assert_array_equal(counts[clear], brute[clear])
    # And the first hit is the first crossing.
    first = scene.cast_rays(rays)
    hit = counts > 0
    np.testing.assert_allclose(first["t_hit"][hit], lx["t_hit"][splits[:-1][hit]], rtol=1e-6)


def test_closest_points_distances_signs_and_occupancy():
    scene, v, f = two_boxes()
    points = np.array([[0.5, 0.5, 2.0], [0.5, 0.5, 0.4], [1.5, 0.5, 0.5], [3.2, 0.9, -1], [-1, -1, -1]])
    near = scene.compute_closest_points(points)
    assert {k: a.dtype.type for k, a in near.items()} == {
        "points": np.float32, "geometry_ids": np.uint32, "primitive_ids": np.uint32,
        "primitive_uvs": np.float32, "primitive_normals": np.float32}
    expected = np.array([[0.5, 0.5, 1.0], [0.5, 0.5, 0.0], [1.0, 0.5, 0.5], [3.2, 0.9, 0.0], [0, 0, 0]])
    np.testing.assert_allclose(near["points"], expected, atol=1e-6)
    assert near["geometry_ids"].tolist() == [0, 0, 0, 1, 0]
    np.testing.assert_allclose(near["primitive_normals"][:4], [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, 0, -1]], atol=1e-7)
    # uvs weigh the face's corners to the point.
    for i in range(len(points)):
        tri = (v + [3 * near["geometry_ids"][i], 0, 0])[f[near["primitive_ids"][i]]]
        u, w = near["primitive_uvs"][i].astype(np.float64)
        np.testing.assert_allclose((1 - u - w) * tri[0] + u * tri[1] + w * tri[2], expected[i], atol=1e-6)
    distance = np.array([1.0, 0.4, 0.5, 1.0, math.sqrt(3)])
    np.testing.assert_allclose(scene.compute_distance(points), distance, rtol=1e-6)
    inside = np.array([False, True, False, False, False])
    signed = scene.compute_signed_distance(points)
    assert signed.dtype == np.float32
    np.testing.assert_allclose(signed, np.where(inside, -distance, distance), rtol=1e-6)
    for nsamples in (1, 3, 5):
        occupancy = scene.compute_occupancy(points, nsamples=nsamples)
        assert occupancy.dtype == np.float32
        np.testing.assert_array_equal(occupancy, inside.astype(np.float32))
        np.testing.assert_allclose(scene.compute_signed_distance(points, nsamples=nsamples), signed)
    for bad in (0, 2, -1, 1.0):
        with pytest.raises(ValueError, match="nsamples"):
            scene.compute_occupancy(points, nsamples=bad)


def test_occupancy_is_exact_on_vertices_and_edges_with_one_sample(bumpy):
    """Open3D asks for more samples where a ray meets an edge or a vertex;
    strata's one ray is exact there: points just inside and outside,
    against the parity of a float64 brute force away from edges."""
    v, f = bumpy
    scene = RaycastingScene(nthreads=1)
    scene.add_triangles(v, f)
    rng = np.random.default_rng(8)
    points = rng.uniform(v.min(0), v.max(0), (3000, 3))
    occupancy = scene.compute_occupancy(points)
    brute, clear = helpers.parity_inside(v[f], points, rng)
    assert clear.mean() > 0.9
    np.testing.assert_array_equal(occupancy.astype(bool)[clear], brute[clear])
    np.testing.assert_array_equal(scene.compute_occupancy(points, nsamples=3), occupancy)


def test_nthreads_and_bad_input_name_the_argument():
    scene, *_ = two_boxes()
    rays = np.random.default_rng(1).normal(size=(1000, 6))
    one = scene.cast_rays(rays, nthreads=1)
    every = scene.cast_rays(rays, nthreads=0)
    for k in one:
        np.testing.assert_array_equal(one[k], every[k])
    cases = [
        (lambda: scene.cast_rays(np.zeros((4, 3))), "rays"),
        (lambda: scene.cast_rays(np.array(["a"] * 6)), "rays"),
        (lambda: scene.cast_rays(rays, nthreads=-1), "nthreads"),
        (lambda: RaycastingScene(nthreads=1.5), "nthreads"),
        (lambda: scene.compute_distance(np.zeros((3, 2))), "query_points"),
        (lambda: scene.add_triangles(np.zeros((3, 3)), np.array([[0, 1, 3]])), "triangle_indices"),
        (lambda: scene.add_triangles(np.full((3, 3), np.nan), np.array([[0, 1, 2]])), "vertex_positions"),
        (lambda: scene.add_triangles(np.zeros((3, 2)), np.array([[0, 1, 2]])), "vertex_positions"),
        (lambda: RaycastingScene.create_rays_pinhole(np.eye(3), np.eye(3), 4, 4), "extrinsic_matrix"),
        (lambda: RaycastingScene.create_rays_pinhole(np.eye(3), np.eye(4), 0, 4), "width_px"),
        (lambda: RaycastingScene.create_rays_pinhole(fov_deg=200, center=[0, 0, 0], eye=[0, 0, 1], up=[0, 1, 0], width_px=2, height_px=2), "fov_deg"),
        (lambda: RaycastingScene.create_rays_pinhole(fov_deg=60, center=[0, 0, 0], eye=[0, 0, 1], up=[0, 0, 1], width_px=2, height_px=2), "up"),
    ]
    for call, name in cases:
        with pytest.raises(ValueError, match=name):
            call()
    with pytest.raises(TypeError, match="add_triangles"):
        scene.add_triangles(object())


def test_a_vertex_no_triangle_uses_may_be_nan():
    """A depth image's mesh keeps its missing pixels as NaN vertices that
    no triangle uses: taken, and answered as without them; a NaN vertex
    a triangle uses is refused, naming it and the triangle."""
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    rays = np.random.default_rng(3).normal(size=(500, 6)) * [0.6, 0.6, 0.6, 1, 1, 1] + [0.5, 0.5, 0.5, 0, 0, 0]
    plain = RaycastingScene()
    plain.add_triangles(v, f)
    scene = RaycastingScene()
    scene.add_triangles(np.vstack([[np.nan] * 3, v, [np.inf, 0, 0]]), f + 1)
    want, got = plain.cast_rays(rays), scene.cast_rays(rays)
    for k in want:
        np.testing.assert_array_equal(got[k], want[k])
    assert np.isfinite(want["t_hit"]).sum() > 100
    np.testing.assert_array_equal(scene.count_intersections(rays), plain.count_intersections(rays))
    mesh = strata_rt.Mesh(np.vstack([v, [np.nan, 0, 0]]), f)
    np.testing.assert_array_equal(mesh.intersect(rays[:, :3], rays[:, 3:]).t, want["t_hit"])
    used = f.copy()
    used[5, 1] = len(v)
    with pytest.raises(ValueError, match=rf"vertex_positions\[{len(v)}\] is not finite.*triangle_indices\[5\]"):
        RaycastingScene().add_triangles(np.vstack([v, [np.nan, 0, 0]]), used)
    with pytest.raises(ValueError, match=rf"vertices\[{len(v)}\] is not finite.*faces\[5\]"):
        strata_rt.Mesh(np.vstack([v, [np.nan, 0, 0]]), used)


def test_open3d_takes_a_nan_vertex_no_triangle_uses(o3d):
    """The case above, as Open3D answers it: the same first hits."""
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    with_nan = np.vstack([v, [np.nan, 0, 0]]).astype(np.float32)
    rays = (np.random.default_rng(3).normal(size=(500, 6)) * [0.6, 0.6, 0.6, 1, 1, 1] + [0.5, 0.5, 0.5, 0, 0, 0]).astype(np.float32)
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(with_nan), o3d.core.Tensor(f.astype(np.uint32)))
    ours = RaycastingScene()
    ours.add_triangles(with_nan, f)
    want = theirs.cast_rays(o3d.core.Tensor(rays))
    got = ours.cast_rays(rays)
    np.testing.assert_array_equal(np.isfinite(got["t_hit"]), np.isfinite(want["t_hit"].numpy()))
    np.testing.assert_allclose(got["t_hit"], want["t_hit"].numpy(), rtol=1e-6, atol=1e-6)


def test_an_empty_scene_and_a_scene_grown_after_a_query():
    scene = RaycastingScene()
    rays = np.array([[0.5, 0.5, 10, 0, 0, -1]])
    assert np.isinf(scene.cast_rays(rays)["t_hit"][0])
    assert scene.count_intersections(rays)[0] == 0
    # No surface: no closest point (NaN, invalid ids; Open3D answers the
    # origin at distance 0), an infinite distance, nothing inside.
    near = scene.compute_closest_points(np.zeros((2, 3), np.float32))
    assert np.isnan(near["points"]).all() and (near["geometry_ids"] == INVALID_ID).all()
    assert (near["primitive_ids"] == INVALID_ID).all() and (near["primitive_normals"] == 0).all()
    assert np.isinf(scene.compute_distance(np.zeros((1, 3)))).all()
    assert scene.compute_occupancy(np.zeros((1, 3)))[0] == 0
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    assert scene.add_triangles(v, f) == 0
    assert scene.count_intersections(rays)[0] == 2
    # Meshes of every kind Open3D's users hold: a strata_rt.Mesh, a
    # trimesh-like object, an Open3D legacy-like one.
    assert scene.add_triangles(strata_rt.Mesh(v + [0, 0, 2], f)) == 1
    assert scene.add_triangles(types.SimpleNamespace(vertices=v + [0, 0, 4], faces=f)) == 2
    assert scene.add_triangles(types.SimpleNamespace(vertices=v + [0, 0, 6], triangles=f)) == 3
    assert scene.count_intersections(rays)[0] == 8
    assert scene.cast_rays(rays)["geometry_ids"][0] == 3


def test_a_far_strata_mesh_is_added_as_it_holds_its_corners():
    """A strata_rt.Mesh far from the origin goes in with its float64
    corners (UTM coordinates, where float32 is 0.5 m coarse): the scene
    answers as the mesh does."""
    utm = np.array([500123.37, 5000456.71, 100.0])
    v, f = helpers.icosphere(2)
    mesh = strata_rt.Mesh(v * 5 + utm, f)
    scene = RaycastingScene()
    scene.add_triangles(mesh)
    rng = np.random.default_rng(8)
    origins = utm + helpers.random_directions(rng, 500) * 20
    directions = utm + rng.uniform(-3, 3, (500, 3)) - origins
    want = mesh.intersect(origins, directions)
    got = scene.cast_rays(np.hstack([origins, directions]))
    np.testing.assert_array_equal(got["primitive_ids"], np.where(want.prim >= 0, want.prim, INVALID_ID))
    np.testing.assert_array_equal(got["t_hit"], want.t)


def test_create_rays_pinhole_both_forms():
    k = np.array([[100.0, 0, 20], [0, 50, 10], [0, 0, 1]])
    angle = 0.3
    r = np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0], [0, 0, 1]])
    e = np.eye(4)
    e[:3, :3], e[:3, 3] = r, [1, 2, 3]
    rays = RaycastingScene.create_rays_pinhole(k, e, 4, 3)
    assert rays.shape == (3, 4, 6) and rays.dtype == np.float32
    # Every origin is the camera's centre: e maps it to the camera's origin.
    np.testing.assert_allclose(r @ rays[0, 0, :3] + [1, 2, 3], 0, atol=1e-6)
    # Pixel (row 2, column 3)'s ray, in camera space, is K⁻¹ (3.5, 2.5, 1).
    np.testing.assert_allclose(r @ rays[2, 3, 3:], [(3.5 - 20) / 100, (2.5 - 10) / 50, 1], atol=1e-6)
    # The fov form is the matrix form of its camera: the middle of the
    # image looks at center, the outer pixel edges span fov_deg across.
    w, h, fov = 64, 48, 70.0
    rays = RaycastingScene.create_rays_pinhole(fov_deg=fov, center=[1, 2, 3], eye=[4, -2, 3], up=[0, 0, 1], width_px=w, height_px=h)
    d = helpers.unit(rays[..., 3:].astype(np.float64))
    forward = helpers.unit(np.array([1.0, 2, 3]) - [4, -2, 3])
    middle = helpers.unit(d[h // 2 - 1:h // 2 + 1, w // 2 - 1:w // 2 + 1].sum(axis=(0, 1)))
    np.testing.assert_allclose(middle, forward, atol=1e-6)
    # Pixel (row i, column j) looks along (j + ½ − w/2, i + ½ − h/2, f) in
    # the camera's axes: x along up × forward, y along forward × x.
    focal = w / 2 / math.tan(math.radians(fov) / 2)
    side = helpers.unit(np.cross([0, 0, 1], forward))
    along_y = np.cross(forward, side)
    ahead = d @ forward
    cols, rows = np.meshgrid(np.arange(w) + 0.5 - w / 2, np.arange(h) + 0.5 - h / 2)
    np.testing.assert_allclose((d @ side) / ahead, cols / focal, atol=1e-6)
    np.testing.assert_allclose((d @ along_y) / ahead, rows / focal, atol=1e-6)
    row = d[h // 2]
    # Row 0 lies along -up (Open3D's order), columns run along up × forward.
    assert (d[0, :, 2] < 0).all() and (d[-1, :, 2] > 0).all()
    assert (row[-1] - row[0]) @ np.cross([0, 0, 1], forward) > 0
    np.testing.assert_array_equal(rays[..., :3], np.broadcast_to(np.float32([4, -2, 3]), (h, w, 3)))


class FakeTensor:
    """What strata_rt needs of an Open3D tensor: numpy()."""

    def __init__(self, a):
        self.a = np.asarray(a)

    def numpy(self):
        return self.a

    @staticmethod
    def from_numpy(a):
        return FakeTensor(a)


FakeTensor.__module__ = "open3d.core"


def test_open3d_tensors_in_give_open3d_tensors_out(monkeypatch):
    fake = types.ModuleType("open3d")
    fake.core = types.SimpleNamespace(Tensor=FakeTensor)
    monkeypatch.setitem(sys.modules, "open3d", fake)
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    scene = RaycastingScene()
    scene.add_triangles(FakeTensor(v.astype(np.float32)), FakeTensor(f.astype(np.uint32)))
    ans = scene.cast_rays(FakeTensor(np.float32([[0.5, 0.5, 5, 0, 0, -1]])))
    assert isinstance(ans["t_hit"], FakeTensor) and ans["t_hit"].numpy()[0] == 4.0
    rays = RaycastingScene.create_rays_pinhole(FakeTensor(np.eye(3)), FakeTensor(np.eye(4)), 2, 2)
    assert isinstance(rays, FakeTensor) and rays.numpy().shape == (2, 2, 6)
    # With Open3D loaded, the camera's rays are a tensor whatever its
    # arguments, as Open3D's are (its tutorial passes lists); without, numpy.
    for args in ((np.eye(3), np.eye(4), 2, 2), (90, [0, 0, 2], [2, 3, 0], [0, 1, 0], 4, 3)):
        rays = RaycastingScene.create_rays_pinhole(*args)
        assert isinstance(rays, FakeTensor) and rays.numpy().dtype == np.float32
        monkeypatch.delitem(sys.modules, "open3d")
        plain = RaycastingScene.create_rays_pinhole(*args)
        assert type(plain) is np.ndarray
        np.testing.assert_array_equal(plain, rays.numpy())
        monkeypatch.setitem(sys.modules, "open3d", fake)


def test_open3d_s_tutorial_runs_as_written(o3d):
    """Open3D's ray-casting tutorial, its lines as they are but for the
    scene's class: a scene of tensor meshes answers in tensors, which
    index the camera's rays; the points are Open3D's."""

    def tutorial(scene_class):
        cube = o3d.t.geometry.TriangleMesh.from_legacy(o3d.geometry.TriangleMesh.create_box())
        scene = scene_class()
        scene.add_triangles(cube)
        rays = scene_class.create_rays_pinhole(
            fov_deg=90, center=[0, 0, 2], eye=[2, 3, 0], up=[0, 1, 0], width_px=64, height_px=48
        )
        ans = scene.cast_rays(rays)
        hit = ans["t_hit"].isfinite()
        points = rays[hit][:, :3] + rays[hit][:, 3:] * ans["t_hit"][hit].reshape((-1, 1))
        return hit.numpy(), points.numpy()

    hit, points = tutorial(RaycastingScene)
    their_hit, their_points = tutorial(o3d.t.geometry.RaycastingScene)
    np.testing.assert_array_equal(hit, their_hit)
    assert hit.sum() > 100
    np.testing.assert_allclose(points, their_points, rtol=0, atol=1e-5)


NON_FINITE = np.float32([
    [np.nan, 0.5, 0.5], [0.5, np.inf, 0.5], [-np.inf, np.inf, 0.0], [np.nan, np.inf, 0.0],
    [0.5, 0.3, 0.2], [2.0, 0.5, 0.25],
])


def test_point_queries_answer_non_finite_points_as_open3d_does(o3d):
    """A query point with a NaN or infinite coordinate: Open3D 0.20's
    distance is NaN for a NaN coordinate, else inf, its occupancy 0 and
    its ids INVALID_ID (the rest of its closest point is whatever its
    memory held); the finite points answer as they would alone."""
    v, f = helpers.box([0, 0, 0], [1, 1, 1])
    ours, theirs = RaycastingScene(), o3d.t.geometry.RaycastingScene()
    ours.add_triangles(v, f)
    theirs.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
    points = o3d.core.Tensor(NON_FINITE)
    distance = ours.compute_distance(points).numpy()
    np.testing.assert_allclose(distance, theirs.compute_distance(points).numpy(), rtol=1e-6)
    for nsamples in (1, 3):
        for query in ("compute_signed_distance", "compute_occupancy"):
            got = getattr(ours, query)(points, nsamples=nsamples).numpy()
            expected = getattr(theirs, query)(points, nsamples=nsamples).numpy()
            np.testing.assert_allclose(got, expected, rtol=1e-6, err_msg=f"{query}, nsamples={nsamples}")
    near, their_near = ours.compute_closest_points(points), theirs.compute_closest_points(points)
    for k in ("geometry_ids", "primitive_ids"):
        np.testing.assert_array_equal(near[k].numpy(), their_near[k].numpy())
    np.testing.assert_allclose(near["points"].numpy()[4:], their_near["points"].numpy()[4:], atol=1e-6)


def test_point_queries_take_non_finite_points():
    """Without Open3D: no error for the batch, the finite points' answers
    as alone, and for the others the answers the docstrings give."""
    scene, *_ = two_boxes()
    bad, good = NON_FINITE[:4], NON_FINITE[4:]
    np.testing.assert_array_equal(scene.compute_distance(NON_FINITE)[:4], [np.nan, np.inf, np.inf, np.nan])
    np.testing.assert_array_equal(scene.compute_distance(NON_FINITE)[4:], scene.compute_distance(good))
    for nsamples in (1, 3):
        occupancy = scene.compute_occupancy(NON_FINITE, nsamples=nsamples)
        alone = scene.compute_occupancy(good, nsamples=nsamples)
        np.testing.assert_array_equal(occupancy, np.concatenate([np.zeros(4), alone]))
        signed = scene.compute_signed_distance(NON_FINITE, nsamples=nsamples)
        alone = scene.compute_signed_distance(good, nsamples=nsamples)
        np.testing.assert_array_equal(signed, np.concatenate([scene.compute_distance(bad), alone]))
    near = scene.compute_closest_points(NON_FINITE)
    alone = scene.compute_closest_points(good)
    for k in near:
        np.testing.assert_array_equal(near[k][4:], alone[k])
    assert (near["geometry_ids"][:4] == INVALID_ID).all() and (near["primitive_ids"][:4] == INVALID_ID).all()
    assert np.isnan(near["points"][:4]).all() and (near["primitive_normals"][:4] == 0).all()


ON_A_FACE = np.float32([
    [0.3, 0.4, 0.0, 0, 0, 1],   # on the cube's bottom face, going in
    [0.3, 0.4, 0.0, 0, 0, -1],  # on it, going out
])


def test_a_ray_from_a_surface_does_not_hit_it_there():
    """strata's rays cover (0, t_max] (docs/python.md): from a point on a
    face, going in, the far face; going out, nothing."""
    scene = RaycastingScene()
    scene.add_triangles(*helpers.box([0, 0, 0], [1, 1, 1]))
    np.testing.assert_array_equal(scene.cast_rays(ON_A_FACE)["t_hit"], [1.0, np.inf])
    np.testing.assert_array_equal(scene.count_intersections(ON_A_FACE), [1, 0])
    np.testing.assert_array_equal(scene.test_occlusions(ON_A_FACE), [True, False])


def test_open3d_hits_a_surface_a_ray_starts_on(o3d):
    """What docs/python.md says Open3D 0.20 answers for those rays: t_hit 0
    both ways, 2 and 1 crossings, occluded both ways."""
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(o3d.geometry.TriangleMesh.create_box()))
    rays = o3d.core.Tensor(ON_A_FACE)
    np.testing.assert_array_equal(scene.cast_rays(rays)["t_hit"].numpy(), [0.0, 0.0])
    np.testing.assert_array_equal(scene.count_intersections(rays).numpy(), [2, 1])
    np.testing.assert_array_equal(scene.test_occlusions(rays).numpy(), [True, True])

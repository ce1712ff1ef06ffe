"""Meshes far from the origin answer as they do at the origin.

A mesh whose box lies farther from the origin than its size is traced
relative to a centre near its middle, and hit and closest points are
float64, computed on the triangle as given (``strata_rt.Mesh``'s docs):
an icosphere of radius 5 at UTM-like coordinates, and the bunny moved by
1e6 (a multiple of the power of two its centre is rounded to, so its
answers equal the unmoved bunny's bit for bit).
"""

import numpy as np
import pytest

import helpers
import strata_rt
from strata_rt.trimesh import RayMeshIntersector

UTM = np.array([500123.37, 5000456.71, 100.0])


def plane_distance(points, tris):
    """Each point's distance to the plane of its triangle, in float64."""
    a = tris[:, 0]
    n = helpers.unit(np.cross(tris[:, 1] - a, tris[:, 2] - a))
    return np.abs(np.einsum("ij,ij->i", points - a, n))


def sphere_at(centre, radius=5.0):
    v, f = helpers.icosphere(3)
    return v * radius + centre, f


def rays_through(rng, centre, radius, n, within):
    """Rays from 4 radii away aimed at points within `within` of the centre."""
    origins = centre + helpers.random_directions(rng, n) * 4 * radius
    targets = centre + helpers.random_directions(rng, n) * rng.uniform(0, within, (n, 1))
    return origins, targets - origins


def test_a_sphere_at_utm_coordinates_answers_as_at_the_origin():
    v, f = sphere_at(UTM)
    mesh = strata_rt.Mesh(v, f)
    rng = np.random.default_rng(4)
    origins, directions = rays_through(rng, UTM, 5.0, 4000, 4.5)
    hits = mesh.intersect(origins, directions)
    assert (hits.prim >= 0).all()
    # Hit points on their triangle's plane, in float64 (float32 at these
    # coordinates is 0.5 m coarse).
    off = plane_distance(hits.point, v[f[hits.prim]])
    assert off.max() < 1e-8, off.max()
    # The hit point is on the ray, where the traced t says.
    along = np.linalg.norm(hits.point - origins - hits.t[:, None] * directions, axis=1)
    assert along.max() < 1e-5 * np.linalg.norm(directions, axis=1).max()
    # Through a closed sphere: exactly two crossings each, also on rays
    # from outside through each vertex and the centre.
    assert (mesh.count_hits(origins, directions) == 2).all()
    assert (mesh.count_hits(UTM + (v - UTM) * 3, UTM - v) == 2).all()
    # Inside or outside: every point clear of the surface, as at the origin.
    r = np.concatenate([rng.uniform(0, 4.85, 2000), rng.uniform(5.05, 9, 2000)])
    points = UTM + helpers.random_directions(rng, 4000) * r[:, None]
    np.testing.assert_array_equal(mesh.contains(points), r < 5)
    # Closest points: on the surface, in float64, at the distance said.
    near = mesh.closest_point(points)
    np.testing.assert_allclose(np.linalg.norm(near.point - points, axis=1), near.distance, rtol=0, atol=1e-8)
    assert plane_distance(near.point, v[f[near.prim]]).max() < 1e-8
    # The same through the trimesh adapter, whose locations trimesh users read.
    trimesh = pytest.importorskip("trimesh", reason="trimesh is in tools/requirements.txt")
    tm = trimesh.Trimesh(v, f, process=False)
    tm.ray = RayMeshIntersector(tm)
    locations, index_ray, index_tri = tm.ray.intersects_location(origins, directions)
    assert np.bincount(index_ray, minlength=len(origins)).tolist() == [2] * len(origins)
    assert plane_distance(locations, v[f[index_tri]]).max() < 1e-8
    np.testing.assert_array_equal(tm.ray.contains_points(points), r < 5)


def write_obj(path, v, f):
    """An OBJ of float64 vertices in shortest round-trip decimals."""
    with open(path, "w") as out:
        out.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
        out.writelines(f"f {a} {b} {c}\n" for a, b, c in (f + 1).tolist())


def write_stl(path, v, f):
    """An ASCII STL of float64 corners in shortest round-trip decimals."""
    with open(path, "w") as out:
        out.write("solid sphere\n")
        for corners in v[f].tolist():
            out.write("facet normal 0 0 0\nouter loop\n")
            out.writelines(f"vertex {x!r} {y!r} {z!r}\n" for x, y, z in corners)
            out.write("endloop\nendfacet\n")
        out.write("endsolid sphere\n")


def write_ply(path, v, f, scalar):
    """A binary PLY of `scalar` ("double" or "float") vertex properties."""
    dtype = {"double": "<f8", "float": "<f4"}[scalar]
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
        + "".join(f"property {scalar} {axis}\n" for axis in "xyz")
        + f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(f), dtype=[("n", "u1"), ("k", "<i4", 3)])
    faces["n"], faces["k"] = 3, f
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(v.astype(dtype).tobytes())
        out.write(faces.tobytes())


def test_a_far_file_loads_as_it_writes_its_coordinates(tmp_path):
    """Mesh.load keeps an OBJ's or ASCII STL's decimals and a PLY's doubles in
    float64, as trimesh reads them: the UTM sphere from a file answers as from its
    arrays, bit for bit, on its own faces' planes. A PLY of floats is
    float32 by its header, and loads as such."""
    v, f = sphere_at(UTM)
    rng = np.random.default_rng(11)
    origins, directions = rays_through(rng, UTM, 5.0, 2000, 4.5)
    want = strata_rt.Mesh(v, f).intersect(origins, directions)
    write_obj(tmp_path / "sphere.obj", v, f)
    write_ply(tmp_path / "sphere.ply", v, f, "double")
    write_stl(tmp_path / "sphere.stl", v, f)
    for name in ["sphere.obj", "sphere.ply", "sphere.stl"]:
        loaded = strata_rt.Mesh.load(tmp_path / name)
        got = loaded.intersect(origins, directions)
        for key in want.keys():
            np.testing.assert_array_equal(got[key], want[key], err_msg=f"{name} {key}")
        assert plane_distance(got.point, v[f[got.prim]]).max() < 1e-8
        np.testing.assert_array_equal(loaded.vertices[loaded.faces], v[f])
    write_ply(tmp_path / "floats.ply", v, f, "float")
    rounded = v.astype(np.float32).astype(np.float64)
    got = strata_rt.Mesh.load(tmp_path / "floats.ply").intersect(origins, directions)
    want = strata_rt.Mesh(rounded, f).intersect(origins, directions)
    np.testing.assert_array_equal(got.point, want.point)
    # float32 moves the faces: up to 0.25 m at five million.
    assert plane_distance(got.point, v[f[got.prim]]).max() > 1e-3


def test_the_bunny_moved_by_a_million_answers_as_unmoved(bunny):
    v, f = bunny
    v = helpers.as_stored(v)
    moved_by = 1e6
    here, there = strata_rt.Mesh(v, f), strata_rt.Mesh(v + moved_by, f)
    rng = np.random.default_rng(6)
    origins, directions = helpers.random_rays(rng, v, 20000)
    origins = origins.astype(np.float32).astype(np.float64)
    np.testing.assert_array_equal(there.count_hits(origins + moved_by, directions), here.count_hits(origins, directions))
    a, b = here.intersect(origins, directions), there.intersect(origins + moved_by, directions)
    np.testing.assert_array_equal(a.prim, b.prim)
    np.testing.assert_array_equal(a.t, b.t)
    hit = a.prim >= 0
    np.testing.assert_allclose(b.point[hit] - moved_by, a.point[hit], atol=1e-9)
    points = (v.min(0) + rng.random((20000, 3)) * (v.max(0) - v.min(0))).astype(np.float32).astype(np.float64)
    np.testing.assert_array_equal(there.contains(points + moved_by), here.contains(points))
    na, nb = here.closest_point(points), there.closest_point(points + moved_by)
    np.testing.assert_array_equal(na.prim, nb.prim)
    np.testing.assert_allclose(nb.distance, na.distance, rtol=0, atol=1e-10)
    np.testing.assert_allclose(nb.point - moved_by, na.point, rtol=0, atol=1e-9)


def test_a_far_mesh_pickles_as_given():
    import pickle

    v, f = sphere_at(UTM)
    mesh = strata_rt.Mesh(v, f)
    copy = pickle.loads(pickle.dumps(mesh))
    rng = np.random.default_rng(9)
    origins, directions = rays_through(rng, UTM, 5.0, 500, 6.0)
    a, b = mesh.intersect(origins, directions), copy.intersect(origins, directions)
    for key in a.keys():
        np.testing.assert_array_equal(a[key], b[key])


@pytest.mark.parametrize("at", [[500000.5, 5000000.25, 100.0], [2e12, -3e11, 7.0]])
def test_a_far_grid_gives_back_its_vertices_and_pickles(at, tmp_path):
    """A far mesh that float32 holds exactly relative to its centre (a
    grid's half and quarter metres at UTM coordinates, whole numbers at
    2e12) keeps no copy as given, yet gives back its float64 vertices,
    pickles and loads from a file without moving a corner (float32 of the
    world coordinates would merge them)."""
    import pickle

    v, f = helpers.box([-2.0, -1.5, -0.25], [2.0, 1.5, 0.25])
    v = v + np.array(at)
    mesh = strata_rt.Mesh(v, f)
    rng = np.random.default_rng(3)
    origins = np.array(at) + helpers.random_directions(rng, 500) * 10
    directions = np.array(at) + rng.uniform(-1, 1, (500, 3)) * [2, 1.5, 0.25] - origins
    want = mesh.intersect(origins, directions)
    assert (want.prim >= 0).all()
    write_obj(tmp_path / "grid.obj", v, f)
    for copy in [mesh, pickle.loads(pickle.dumps(mesh)), strata_rt.Mesh.load(tmp_path / "grid.obj")]:
        np.testing.assert_array_equal(copy.vertices[copy.faces], v[f])
        got = copy.intersect(origins, directions)
        for key in want.keys():
            np.testing.assert_array_equal(got[key], want[key], err_msg=key)


def test_a_mesh_near_the_origin_keeps_every_bit(bumpy):
    """Near the origin nothing moves: the stored triangles are the float32
    vertices given, bit for bit."""
    v, f = bumpy
    mesh = strata_rt.Mesh(v, f)
    np.testing.assert_array_equal(mesh.triangles, v.astype(np.float32)[f])


@pytest.mark.parametrize("exponent", [-36, -30, 30, 39])
def test_every_answer_scales_with_the_mesh_where_float32_holds_it(exponent):
    """The sphere scaled by a power of two (exact in float32) from about
    1.5e-11 to 5e11 in radius: t, counts, inside and closest points answer as
    at scale 1, scaled (closest_point's region tests overflowed past 1e9
    and underflowed below 1e-10, off by up to 270%)."""
    k = 2.0**exponent
    v, f = sphere_at(np.zeros(3), radius=1.0)
    rng = np.random.default_rng(12)
    origins, directions = rays_through(rng, np.zeros(3), 1.0, 2000, 1.2)
    points = rng.uniform(-1.5, 1.5, (2000, 3))
    unit, scaled = strata_rt.Mesh(v, f), strata_rt.Mesh(v * k, f)
    a, b = unit.intersect(origins, directions), scaled.intersect(origins * k, directions)
    np.testing.assert_array_equal(b.t, (a.t * np.float32(k)).astype(np.float32))
    np.testing.assert_array_equal(b.prim, a.prim)
    np.testing.assert_array_equal(scaled.count_hits(origins * k, directions), unit.count_hits(origins, directions))
    np.testing.assert_array_equal(scaled.contains(points * k), unit.contains(points))
    near_a, near_b = unit.closest_point(points), scaled.closest_point(points * k)
    np.testing.assert_array_equal(near_b.prim, near_a.prim)
    np.testing.assert_allclose(near_b.distance, near_a.distance * k, rtol=1e-12)


@pytest.mark.parametrize("k", [1e13, 5e-12])
def test_a_mesh_too_large_or_small_for_float32_says_so(k):
    v, f = sphere_at(np.zeros(3), radius=1.0)
    with pytest.raises(ValueError, match=r"from the mesh's centre, where strata's float32 ray tests are exact from 1e-11 to 1e12: scale them"):
        strata_rt.Mesh(v * k, f)

"""strata_rt.trimesh.RayMeshIntersector against trimesh's own engine
(trimesh.ray.ray_triangle) on the same meshes and rays, and as a drop-in
``mesh.ray``."""

import types

import numpy as np
import pytest

import helpers
from strata_rt.trimesh import RayMeshIntersector

trimesh = pytest.importorskip("trimesh", reason="trimesh is in tools/requirements.txt")
pytest.importorskip("rtree", reason="trimesh's own engine needs rtree (tools/requirements.txt)")
from trimesh.ray.ray_triangle import RayMeshIntersector as TrimeshEngine  # noqa: E402


@pytest.fixture(params=["bumpy", "bunny"], scope="module")
def case(request):
    vertices, faces = request.getfixturevalue(request.param)
    vertices = helpers.as_stored(vertices)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    rng = np.random.default_rng(21)
    n = 300 if request.param == "bumpy" else 120
    origins, directions = helpers.random_rays(rng, vertices, n)
    brute = helpers.BruteHits(vertices[faces], origins, directions)
    return mesh, origins, directions, brute


def pairs(index_tri, index_ray, rays):
    keep = np.isin(index_ray, rays)
    return sorted(zip(index_ray[keep].tolist(), index_tri[keep].tolist()))


def test_every_hit_matches_trimesh_s_engine(case):
    mesh, origins, directions, brute = case
    ours, theirs = RayMeshIntersector(mesh), TrimeshEngine(mesh)
    clear = np.flatnonzero(brute.clear)
    tri, ray, loc = ours.intersects_id(origins, directions, return_locations=True)
    t_tri, t_ray, t_loc = theirs.intersects_id(origins, directions, return_locations=True)
    assert tri.dtype == t_tri.dtype == np.int64 and ray.dtype == t_ray.dtype == np.int64
    assert loc.dtype == t_loc.dtype == np.float64 and loc.shape == (len(tri), 3)
    assert pairs(tri, ray, clear) == pairs(t_tri, t_ray, clear)
    assert len(pairs(tri, ray, clear)) > 100
    # Locations: the same points, pair for pair.
    for r, f in pairs(tri, ray, clear)[:200]:
        a = loc[(ray == r) & (tri == f)][0]
        b = t_loc[(t_ray == r) & (t_tri == f)][0]
        np.testing.assert_allclose(a, b, atol=1e-5 * mesh.scale)
    # Grouped by ray, ascending; each ray's hits nearest first.
    assert (np.diff(ray) >= 0).all()
    along = ((loc - origins[ray]) * directions[ray]).sum(axis=1)
    same = np.diff(ray) == 0
    assert (np.diff(along)[same] >= 0).all()
    # intersects_location is intersects_id's answer, reordered.
    locations, index_ray, index_tri = ours.intersects_location(origins, directions)
    np.testing.assert_array_equal(locations, loc)
    np.testing.assert_array_equal(index_ray, ray)
    np.testing.assert_array_equal(index_tri, tri)


def test_first_and_any_hits_match_trimesh_s_engine(case):
    mesh, origins, directions, brute = case
    ours, theirs = RayMeshIntersector(mesh), TrimeshEngine(mesh)
    clear = brute.clear
    first, t_first = ours.intersects_first(origins, directions), theirs.intersects_first(origins, directions)
    assert first.dtype == np.int64 and first.shape == (len(origins),)
    np.testing.assert_array_equal(first[clear], t_first[clear])
    assert (first[clear] >= 0).sum() > 50
    hit_any = ours.intersects_any(origins, directions)
    assert hit_any.dtype == np.bool_
    np.testing.assert_array_equal(hit_any[clear], theirs.intersects_any(origins, directions)[clear])
    # multiple_hits=False: the first hits alone.
    tri, ray = ours.intersects_id(origins, directions, multiple_hits=False)
    np.testing.assert_array_equal(ray, np.flatnonzero(first >= 0))
    np.testing.assert_array_equal(tri, first[first >= 0])
    t_tri, t_ray = theirs.intersects_id(origins, directions, multiple_hits=False)
    c = np.flatnonzero(clear)
    assert pairs(tri, ray, c) == pairs(t_tri, t_ray, c)


def test_contains_points_matches_trimesh_s_engine_away_from_the_surface(bumpy):
    vertices, faces = bumpy
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    rng = np.random.default_rng(9)
    points = rng.uniform(-1.4, 1.4, size=(400, 3))
    ours = RayMeshIntersector(mesh)
    away = ours.strata_mesh.closest_point(points).distance > 1e-3
    np.testing.assert_array_equal(
        ours.contains_points(points)[away], TrimeshEngine(mesh).contains_points(points)[away]
    )


def test_a_drop_in_for_mesh_ray(bumpy):
    vertices, faces = bumpy
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    reference = trimesh.Trimesh(vertices, faces, process=False)
    reference.ray = TrimeshEngine(reference)
    mesh.ray = RayMeshIntersector(mesh)
    rng = np.random.default_rng(10)
    points = rng.uniform(-1.4, 1.4, size=(300, 3))
    away = mesh.ray.strata_mesh.closest_point(points).distance > 1e-3
    np.testing.assert_array_equal(mesh.contains(points)[away], reference.contains(points)[away])
    # trimesh's own code asks mesh.ray: the longest free rays from inside.
    inside = np.zeros((20, 3))
    directions = helpers.random_directions(rng, 20)
    np.testing.assert_allclose(
        trimesh.proximity.longest_ray(mesh, inside, directions),
        trimesh.proximity.longest_ray(reference, inside, directions),
        rtol=1e-5,
    )


def test_conventions_kept_from_trimesh(bumpy):
    vertices, faces = bumpy
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    ray = RayMeshIntersector(mesh)
    # A zero direction hits nothing (trimesh unitizes it to zero); the
    # others answer as they would alone.
    o = np.array([[0.0131, 0.0217, 3.0]] * 3)
    d = np.array([[0, 0, -1.0], [0, 0, 0.0], [0, 0, -2.0]])
    np.testing.assert_array_equal(ray.intersects_first(o, d)[1], -1)
    assert ray.intersects_first(o, d)[0] == ray.intersects_first(o, d)[2] >= 0
    np.testing.assert_array_equal(ray.intersects_any(o, d), [True, False, True])
    tri, idx = ray.intersects_id(o, d)
    assert 1 not in idx and (np.bincount(idx, minlength=3) == [2, 0, 2]).all()
    # A NaN or infinite coordinate makes a miss, not an error for the whole
    # batch (trimesh's embreex engine returns -1 for it); the other rays
    # answer as they would alone.
    bad = np.array([[np.nan, 0.0, 3.0], [0.0131, 0.0217, np.inf], [0.0131, 0.0217, 3.0]])
    down = np.array([[0, 0, -1.0], [0, 0, -1.0], [0, 0, -1.0]])
    np.testing.assert_array_equal(ray.intersects_first(bad, down)[:2], -1)
    assert ray.intersects_first(bad, down)[2] == ray.intersects_first(o, d)[0]
    np.testing.assert_array_equal(ray.intersects_any(bad, down), [False, False, True])
    nan_direction = np.array([[0, np.nan, -1.0], [0, 0, -1.0]])
    np.testing.assert_array_equal(ray.intersects_any(o[:2], nan_direction), [False, True])
    _, idx = ray.intersects_id(bad, down)
    assert set(idx) == {2}
    points = np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0], [0.0, 0.0, 9.0]])
    np.testing.assert_array_equal(ray.contains_points(points), [True, False, False])
    # max_hits caps each ray's hits, nearest first.
    tri1, idx1 = ray.intersects_id(o, d, max_hits=1)
    np.testing.assert_array_equal(idx1, [0, 2])
    np.testing.assert_array_equal(tri1, ray.intersects_first(o, d)[[0, 2]])
    # Mismatched shapes raise, as trimesh does; empty input gives empty answers.
    with pytest.raises(ValueError):
        ray.intersects_id(o, d[:2])
    with pytest.raises(ValueError, match="ray_origins"):
        ray.intersects_id(o[0], d[0])
    tri, idx, loc = ray.intersects_id(np.zeros((0, 3)), np.zeros((0, 3)), return_locations=True)
    assert tri.shape == (0,) and loc.shape == (0, 3)
    # The BVH follows the mesh: moved vertices, new answers.
    mesh.vertices = mesh.vertices * 0.1
    locations, _, _ = ray.intersects_location(o[:1], d[:1], multiple_hits=False)
    assert abs(locations[0, 2]) < 0.2, "the intersector kept the old mesh"


def test_first_hit_and_locations_agree_on_grazing_rays():
    """Rays that only touch a box at a corner or along an edge: whatever
    intersects_first says, every hit list's first entry is it, and the
    locations lie on their faces (trimesh's own tests ask np.isclose)."""
    mesh = trimesh.creation.box()
    mesh.ray = RayMeshIntersector(mesh)
    corners = mesh.vertices
    rng = np.random.default_rng(3)
    origins, directions = [], []
    for c in corners:
        # Directions that leave the box behind on both sides of the corner.
        for _ in range(8):
            d = np.sign(c) * rng.uniform(0.2, 1, 3) * np.array([1, -1, 1])[rng.permutation(3)]
            origins.append(c - 2 * d)
            directions.append(d)
    # Along an edge (x = y = 0.5), and through the middle of a face from z = -100.
    origins += [[0.5, 0.5, -3.0], [0.1, 0.2, -100.0]]
    directions += [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]
    origins, directions = np.array(origins), np.array(directions)
    first = mesh.ray.intersects_first(origins, directions)
    for multiple in (True, False):
        locations, index_ray, index_tri = mesh.ray.intersects_location(origins, directions, multiple_hits=multiple)
        hit_rays = np.unique(index_ray)
        np.testing.assert_array_equal(hit_rays, np.flatnonzero(first >= 0))
        leading = np.searchsorted(index_ray, hit_rays)
        np.testing.assert_array_equal(index_tri[leading], first[hit_rays])
        # On the face's plane, exactly as trimesh's own test_box asks.
        normals = mesh.face_normals[index_tri]
        offset = np.einsum("ij,ij->i", locations - mesh.vertices[mesh.faces[index_tri, 0]], normals)
        assert np.abs(offset).max() < 1e-12
    assert first[-1] >= 0
    loc, ray, _ = mesh.ray.intersects_location(origins[-1:], directions[-1:])
    assert np.isclose(loc[0, 2], -0.5, rtol=0, atol=1e-12)


def test_a_ray_through_a_shared_edge_or_vertex_lists_its_crossing_once():
    """Rays from outside a closed icosphere through each of its vertices
    and edge midpoints cross it twice: listed twice, as count_hits counts,
    and led by intersects_first's face. There Mesh.intersect and
    Mesh.all_hits name different faces of the edge or vertex, whose t
    differ by a float32 step either way (on up to an eighth of these rays)."""
    far = [7e4, -3e4, 1e3]  # a mesh far from the origin is traced relative to its centre
    for sphere, shift in ((trimesh.creation.icosphere(3), 0), (trimesh.creation.icosphere(3), far),
                          (trimesh.creation.icosphere(2, radius=1e3), far)):
        sphere.vertices += shift
        centre = sphere.vertices.mean(axis=0)
        targets = np.vstack([sphere.vertices, sphere.vertices[sphere.edges_unique].mean(axis=1)])
        out = targets - centre
        for origins in (centre + 3 * out + 0.246 * sphere.scale, centre + 1e3 * out):
            directions = targets - origins
            ray = RayMeshIntersector(sphere)
            counts = ray.strata_mesh.count_hits(origins, directions)
            assert (counts == 2).all()
            first = ray.intersects_first(origins, directions)
            tri, index = ray.intersects_id(origins, directions, multiple_hits=True)
            np.testing.assert_array_equal(np.bincount(index, minlength=len(origins)), counts)
            np.testing.assert_array_equal(tri[0::2], first)
            locations, index_ray, index_tri = ray.intersects_location(origins, directions)
            np.testing.assert_array_equal(np.bincount(index_ray, minlength=len(origins)), counts)
            np.testing.assert_array_equal(index_tri, tri)
            # The first location is the target itself, the second beyond it.
            np.testing.assert_allclose(locations[0::2], targets, rtol=0, atol=1e-9 * np.abs(origins).max())
            along = np.einsum("ij,ij->i", locations[1::2] - locations[0::2], directions)
            assert (along > 0).all()


def test_a_ray_that_touches_an_edge_or_vertex_lists_no_face_twice():
    """Rays along the tangent plane at an icosphere's vertices and edge
    midpoints only touch it there: all_hits lists two faces of the edge or
    vertex, or none, and intersect names one of them, maybe the second:
    each face is listed once, the first hit first."""
    sphere = trimesh.creation.icosphere(2)
    rng = np.random.default_rng(5)
    targets = np.vstack([sphere.vertices, sphere.vertices[sphere.edges_unique].mean(axis=1)])
    normals = targets / np.linalg.norm(targets, axis=1, keepdims=True)
    ray = RayMeshIntersector(sphere)
    for _ in range(4):
        tangents = np.cross(normals, rng.normal(size=normals.shape))
        origins = targets - 2 * tangents
        tri, index = ray.intersects_id(origins, tangents)
        pairs = index * len(sphere.faces) + tri
        assert len(np.unique(pairs)) == len(pairs)
        first = ray.intersects_first(origins, tangents)
        hit = np.unique(index)
        np.testing.assert_array_equal(hit, np.flatnonzero(first >= 0))
        np.testing.assert_array_equal(tri[np.searchsorted(index, hit)], first[hit])


def test_contains_points_follows_trimesh_s_rule_on_an_open_mesh(bumpy, monkeypatch):
    """On an open mesh one ray's parity depends on the ray; trimesh asks
    both ways along it (and once more, along a random direction, where the
    two disagree and neither count is 0). The adapter asks the same
    questions, its second direction fixed: with trimesh's random one made
    that direction, the two agree on every point away from the surface."""
    from trimesh.ray import ray_util

    import strata_rt.trimesh as adapter

    plane = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    points = [[0.2, 0.2, -0.1], [0.2, 0.2, 0.1]]
    np.testing.assert_array_equal(RayMeshIntersector(plane).contains_points(points), [False, False])
    np.testing.assert_array_equal(TrimeshEngine(plane).contains_points(points), [False, False])
    # A box less one of its 12 triangles: open, an odd number of faces.
    box = trimesh.creation.box()
    open_box = trimesh.Trimesh(box.vertices, box.faces[:11])
    points = np.random.default_rng(6).uniform(-0.6, 0.6, size=(300, 3))
    away = np.abs(np.abs(points).max(axis=1) - 0.5) > 0.01
    inside = RayMeshIntersector(open_box).contains_points(points)
    np.testing.assert_array_equal(inside[away], TrimeshEngine(open_box).contains_points(points)[away])
    assert inside.sum() > 50
    # The bumpy sphere with two holes, and a square inside it: a point
    # below the square sees the square and the sphere one way, the sphere
    # alone the other.
    vertices, faces = bumpy
    middle = vertices[faces].mean(axis=1)
    keep = ~((middle[:, 2] > 0.7) | ((np.abs(middle[:, 0]) < 0.25) & (middle[:, 1] > 0)))
    square = np.array([[-0.5, -0.5, 0.05], [0.5, -0.5, 0.05], [-0.5, 0.5, 0.05], [0.5, 0.5, 0.05]])
    mesh = trimesh.Trimesh(
        np.vstack([vertices, square]),
        np.vstack([faces[keep], np.array([[0, 1, 2], [1, 3, 2]]) + len(vertices)]),
        process=False,
    )
    ours = RayMeshIntersector(mesh)
    points = np.random.default_rng(4).uniform(-1.3, 1.3, size=(2000, 3))
    away = ours.strata_mesh.closest_point(points).distance > 1e-3
    fixed = types.SimpleNamespace(random=lambda n: adapter._CONTAINS_RETRY + 0.5)
    monkeypatch.setattr(ray_util.util, "random_generator", lambda *args: fixed)
    theirs = ray_util.contains_points(TrimeshEngine(mesh), points)
    inside = ours.contains_points(points)
    np.testing.assert_array_equal(inside[away], theirs[away])
    # Points of every kind: inside, where one ray's parity says otherwise,
    # and where the first two counts disagree and neither is 0.
    assert inside.sum() > 50 and (ours.strata_mesh.contains(points) != inside).sum() > 50
    d = np.broadcast_to(adapter._CONTAINS_DIRECTION, points.shape)
    ahead, behind = ours.strata_mesh.count_hits(points, d), ours.strata_mesh.count_hits(points, -d)
    assert (((ahead - behind) % 2 == 1) & (ahead > 0) & (behind > 0)).sum() > 20
    # mesh.contains asks mesh.ray: the drop-in answers the same.
    mesh.ray = ours
    np.testing.assert_array_equal(mesh.contains(points), inside)


def test_a_nan_vertex_no_face_uses_answers_as_without_it():
    """A mesh that keeps missing samples as NaN vertices no face uses:
    the intersector takes it and answers as for the mesh without them."""
    box = trimesh.creation.box()
    with_nan = trimesh.Trimesh(np.vstack([box.vertices, [[np.nan] * 3]]), box.faces, process=False)
    rng = np.random.default_rng(5)
    origins = rng.normal(size=(300, 3)) * 0.3
    directions = rng.normal(size=(300, 3))
    plain, ours = RayMeshIntersector(box), RayMeshIntersector(with_nan)
    first = plain.intersects_first(origins, directions)
    np.testing.assert_array_equal(ours.intersects_first(origins, directions), first)
    assert (first >= 0).sum() > 200
    points = rng.normal(size=(300, 3)) * 0.6
    np.testing.assert_array_equal(ours.contains_points(points), plain.contains_points(points))

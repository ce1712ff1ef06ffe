"""contains and closest_point: on a cube, against brute-force parity on
watertight meshes, and against the brute-force nearest point."""

import numpy as np
import pytest

import helpers
import strata_rt


def test_contains_on_a_cube():
    vertices, faces = helpers.cube()
    mesh = strata_rt.Mesh(vertices, faces)
    # The corners pulled in (on the diagonals, through shared edges and
    # vertices of the diagonal triangles) are inside; pushed out, outside.
    assert mesh.contains(vertices / 1.5).all()
    assert not mesh.contains(vertices * 1.5).any()
    assert not mesh.contains(vertices * 100).any()
    assert mesh.contains(vertices.mean(axis=0, keepdims=True)).all()
    # Edge and face midpoints, pulled in and pushed out.
    e = np.array([[a, b] for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1])
    mids = (vertices[e[:, 0]] + vertices[e[:, 1]]) / 2
    faces_mid = np.array([[s * (k == i) for k in range(3)] for i in range(3) for s in (-1, 1)], dtype=float)
    for p in (mids, faces_mid):
        assert mesh.contains(p * 0.9).all()
        assert not mesh.contains(p * 1.1).any()
    rng = np.random.default_rng(4)
    points = rng.uniform(-2, 2, size=(20_000, 3))
    inside = (np.abs(points) < 1).all(axis=1)
    sure = np.abs(np.abs(points).max(axis=1) - 1) > 1e-6
    np.testing.assert_array_equal(mesh.contains(points)[sure], inside[sure])
    assert mesh.contains(points).dtype == np.bool_


@pytest.mark.parametrize("name", ["bumpy", "closed_bunny"])
def test_contains_matches_brute_force_parity(request, name):
    vertices, faces = request.getfixturevalue(name)
    vertices = helpers.as_stored(vertices)
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(6)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    points = lo + (hi - lo) * (rng.random((600, 3)) * 1.2 - 0.1)
    inside, clear = helpers.parity_inside(vertices[faces], points, rng)
    assert clear.mean() > 0.8 and 0.1 < inside[clear].mean() < 0.9
    np.testing.assert_array_equal(mesh.contains(points)[clear], inside[clear])


def edge_distance(points, tris):
    """How far each point is from the nearest edge of its triangle."""
    best = np.full(len(points), np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        p, q = tris[:, a], tris[:, b]
        w = np.clip(((points - p) * (q - p)).sum(1) / ((q - p) ** 2).sum(1), 0, 1)
        best = np.minimum(best, np.linalg.norm(points - (p + (q - p) * w[:, None]), axis=1))
    return best


@pytest.mark.parametrize("name", ["bumpy", "bunny"])
def test_closest_points_match_brute_force(request, name):
    vertices, faces = request.getfixturevalue(name)
    vertices = helpers.as_stored(vertices)
    tris = vertices[faces]
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(11)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    # Points anywhere around the mesh, and points just off random
    # triangles (whose nearest point is mostly inside one triangle).
    around = lo + (hi - lo) * (rng.random((200, 3)) * 1.6 - 0.3)
    pick = rng.choice(len(tris), 100)
    w = rng.dirichlet([1, 1, 1], 100)
    on = np.einsum("ij,ijk->ik", w, tris[pick])
    cross = np.cross(tris[pick, 1] - tris[pick, 0], tris[pick, 2] - tris[pick, 0])
    area = np.linalg.norm(cross, axis=1, keepdims=True)
    off = cross / area * np.sqrt(area) * rng.uniform(-0.3, 0.3, (100, 1))
    points = np.vstack([around, on + off])
    dist, prim, point, second = helpers.closest_on_triangles(points, tris)
    near = mesh.closest_point(points)
    assert near.distance.dtype == np.float64 and near.point.dtype == np.float64 and near.prim.dtype == np.int64 and near.point.shape == (300, 3)
    tol = 1e-5 * size
    np.testing.assert_allclose(near.distance, dist, rtol=1e-5, atol=tol)
    # The triangle strata names is that far away, and so is its point.
    got = np.array([helpers.closest_on_triangles(points[i:i + 1], tris[near.prim[i]][None])[0][0] for i in range(len(points))])
    np.testing.assert_allclose(got, dist, rtol=1e-5, atol=tol)
    np.testing.assert_allclose(np.linalg.norm(near.point - points, axis=1), dist, rtol=1e-5, atol=tol)
    # Where the nearest point is clear of the runner-up's, the same point
    # (its triangle may be any of those that share it: checked above).
    clear = second - dist > 1e-5 * size
    assert clear.mean() > 0.5
    np.testing.assert_allclose(near.point[clear], point[clear], atol=tol)
    # Where that point lies inside one triangle, away from its edges, that
    # triangle.
    inner = clear & (edge_distance(point, tris[prim]) > 1e-5 * size)
    assert inner.sum() > 20
    np.testing.assert_array_equal(near.prim[inner], prim[inner])
    # Signed: negative inside, by contains (the bumpy sphere is closed).
    signed = mesh.closest_point(points, signed=True)
    inside = mesh.contains(points)
    np.testing.assert_array_equal(signed.distance, np.where(inside, -near.distance, near.distance))
    np.testing.assert_array_equal(signed.point, near.point)
    # max_distance: nothing farther is found.
    limit = float(np.median(dist))
    capped = mesh.closest_point(points, max_distance=limit)
    sure = np.abs(dist - limit) > tol
    far = dist > limit
    assert (capped.prim[far & sure] == -1).all() and np.isinf(capped.distance[far & sure]).all()
    assert np.isnan(capped.point[far & sure]).all()
    np.testing.assert_array_equal(capped.prim[~far & sure], near.prim[~far & sure])
    assert set(near.keys()) == {"point", "distance", "prim", "u", "v"}
    # u and v weigh the face's corners to the point, in float64.
    hit = near.prim >= 0
    w = np.stack([1 - near.u - near.v, near.u, near.v], axis=1)[hit]
    by_weights = np.einsum("ij,ijk->ik", w, tris[near.prim[hit]])
    np.testing.assert_allclose(by_weights, near.point[hit], rtol=0, atol=1e-12 * size)


def test_points_on_vertices_and_empty_input(bumpy):
    vertices, faces = bumpy
    mesh = strata_rt.Mesh(vertices, faces)
    on = mesh.closest_point(vertices)
    assert (on.distance <= 1e-6).all()
    assert mesh.contains(np.zeros((0, 3))).shape == (0,)
    assert mesh.closest_point(np.zeros((0, 3))).distance.shape == (0,)
    empty = strata_rt.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    none = empty.closest_point([[0, 0, 0]])
    assert none.prim[0] == -1 and np.isinf(none.distance[0])
    assert not empty.contains([[0, 0, 0]])[0]

"""A placed mesh (``Mesh.place``) against a mesh of its copies: the mesh is
stored once and rays enter it in its own space, yet every query answers as
the copies do (face ``k * T + j`` is face ``j`` of copy ``k``), under random
maps with non-uniform scale, shear and mirroring, with copies that overlap:
first hits and occlusion within float rounding, and every crossing, count,
containment and nearest point exactly.
"""

import numpy as np
import pytest

import helpers
import strata_rt


def random_maps(rng, n):
    """n random invertible (3, 4) row-major maps, half of them mirrors."""
    maps = []
    for k in range(n):
        q1, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        q2, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        scale = rng.uniform(0.4, 2.0, size=3) * np.array([1.0, 1.0, -1.0 if k % 2 else 1.0])
        linear = q1 @ np.diag(scale) @ q2
        maps.append(np.hstack([linear, rng.uniform(-6, 6, size=(3, 1))]))
    return np.array(maps)


@pytest.fixture(scope="module")
def placed():
    vertices, faces = helpers.bumpy_sphere(16, 32)
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(45)
    maps = random_maps(rng, 12)
    placed = mesh.place(maps)
    copies = strata_rt.Mesh(placed.triangles.reshape(-1, 3), np.arange(3 * len(placed)).reshape(-1, 3))
    return mesh, maps, placed, copies


def test_a_placed_mesh_counts_and_lists_every_copy(placed):
    mesh, maps, placed, copies = placed
    assert len(placed) == len(maps) * len(mesh) == placed.triangle_count
    tris = placed.triangles
    # Copy k, face j: the mesh's face j under map k (float32 rounding).
    own = mesh.triangles.astype(np.float64)
    for k in (0, 5, 11):
        moved = own @ maps[k][:, :3].T + maps[k][:, 3]
        np.testing.assert_allclose(tris[k * len(mesh):(k + 1) * len(mesh)], moved, rtol=0, atol=2e-5)
    np.testing.assert_allclose(placed.bounds, copies.bounds, atol=1e-4)


def test_first_hits_and_occlusion_are_the_copies(placed, rng):
    _, _, placed, copies = placed
    origins = rng.uniform(-12, 12, size=(20000, 3))
    targets = rng.uniform(-7, 7, size=(20000, 3))
    directions = targets - origins
    a = placed.intersect(origins, directions)
    b = copies.intersect(origins, directions)
    hit = np.isfinite(b.t)
    assert hit.mean() > 0.2
    np.testing.assert_array_equal(np.isfinite(a.t), hit)
    same = a.prim == b.prim
    # Only a ray through a shared edge may name the neighbour.
    assert same.mean() > 0.999, same.mean()
    np.testing.assert_allclose(a.t[hit], b.t[hit], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(a.point[same & hit], b.point[same & hit], atol=1e-4)
    # The face normal by the right-hand rule over the copy's vertices
    # (a mirrored copy's turns the other way, as trimesh's would).
    np.testing.assert_allclose(a.normal[same & hit], b.normal[same & hit], atol=1e-3)
    t_max = rng.uniform(0.2, 1.5, size=len(origins))
    np.testing.assert_array_equal(
        placed.occluded(origins, directions, t_max=t_max), copies.occluded(origins, directions, t_max=t_max)
    )


def test_bad_maps_name_the_argument_and_placing_twice_says_so(placed):
    mesh, maps, placed, _ = placed
    singular = maps.copy()
    singular[3, :, :3] = 0.0
    with pytest.raises(ValueError, match=r"transforms\[3\]"):
        mesh.place(singular)
    bad = maps.copy()
    bad[2, 1, 1] = np.nan
    with pytest.raises(ValueError, match=r"transforms\[2\]\[1\]\[1\]"):
        mesh.place(bad)
    with pytest.raises(ValueError, match=r"shape \(n, 3, 4\) or \(n, 4, 4\)"):
        mesh.place(np.zeros((2, 3, 3)))
    four = np.concatenate([maps, np.tile([[[0.0, 0.0, 0.0, 1.0]]], (len(maps), 1, 1))], axis=1)
    assert len(mesh.place(four)) == len(placed)
    four[0, 3, 0] = 1.0
    with pytest.raises(ValueError, match="last row"):
        mesh.place(four)
    with pytest.raises(NotImplementedError, match="placed mesh"):
        placed.place(maps)


def copies_of(placed):
    """A Mesh of every copy of ``placed``, from its world-space triangles."""
    tris = placed.triangles
    return strata_rt.Mesh(tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3))


def rays_at(copies, rng, n):
    """Random rays through the copies' box, and rays aimed exactly at the
    copies' vertices and edge midpoints (where ties are broken)."""
    lo, hi = copies.bounds.astype(np.float64)
    tris = copies.triangles.astype(np.float64)
    pick = tris[rng.integers(0, len(tris), size=n)]
    targets = rng.uniform(lo, hi, size=(n, 3))
    targets[1::3] = pick[1::3, 0]
    targets[2::3] = (pick[2::3, 0] + pick[2::3, 1]) / 2
    origins = targets + helpers.unit(rng.normal(size=(n, 3))) * np.linalg.norm(hi - lo)
    return origins, targets - origins


def test_every_crossing_and_count_is_the_copies(placed, rng):
    _, _, placed, copies = placed
    origins, directions = rays_at(copies, rng, 20000)
    t_max = np.where(rng.uniform(size=len(origins)) < 0.2, rng.uniform(0.5, 1.5, size=len(origins)), np.inf)
    for limit in (None, t_max):
        got = placed.all_hits(origins, directions, t_max=limit)
        want = copies.all_hits(origins, directions, t_max=limit)
        assert want[1].size > len(origins)
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(
            placed.count_hits(origins, directions, t_max=limit), np.diff(want[0])
        )


def test_contains_is_the_copies_and_holds_each_lone_copys_centre(placed, rng):
    mesh, maps, placed, copies = placed
    lo, hi = copies.bounds
    points = np.vstack([maps[:, :, 3], rng.uniform(lo, hi, size=(20000, 3))])
    inside = placed.contains(points)
    np.testing.assert_array_equal(inside, copies.contains(points))
    assert 0.01 < inside.mean() < 0.99
    # A copy far from the others holds its centre, and nothing else does.
    far = maps[:2].copy()
    far[1, :, 3] += 100.0
    lone = mesh.place(far)
    centre = far[1, :, 3]
    np.testing.assert_array_equal(lone.contains([centre, centre + 50.0]), [True, False])


@pytest.mark.parametrize("squash", [False, True])
def test_closest_points_are_the_copies_in_world_distances(placed, rng, squash):
    mesh, maps, placed, copies = placed
    if squash:
        # Stretched 40:1 and sheared, so object distances are far from world ones.
        maps = np.array([[[40.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.5, 0.0]],
                         [[0.02, 0.0, 0.0, 1.0], [3.0, 1.0, 0.0, 2.0], [0.0, 0.0, -4.0, 3.0]]])
        placed = mesh.place(maps)
        copies = copies_of(placed)
    lo, hi = copies.bounds
    size = hi - lo
    points = np.vstack([
        rng.uniform(lo - 0.1 * size, hi + 0.1 * size, size=(6000, 3)),
        rng.uniform(lo - 2 * size, hi + 2 * size, size=(1000, 3)),
        maps[:, :, 3],
    ])
    for kwargs in ({}, {"signed": True}, {"max_distance": 0.05}):
        got = placed.closest_point(points, **kwargs)
        want = copies.closest_point(points, **kwargs)
        for key in ("point", "distance", "prim"):
            np.testing.assert_array_equal(got[key], want[key], err_msg=f"{key} {kwargs}")
    # Against brute force in float64 over every copy's triangle.
    near = placed.closest_point(points[:300])
    brute, _, _, _ = helpers.closest_on_triangles(points[:300], copies.triangles)
    # (float32's nearest point on a triangle 40 long and 1 wide is good to
    # a few ε of its size, which the copies share: they are equal above.)
    np.testing.assert_allclose(near.distance, brute, rtol=1e-5, atol=2e-6 * size.max())
    # A copy's centre is inside it: a negative signed distance.
    assert (placed.closest_point(maps[:, :, 3], signed=True).distance < 0).all()


def test_a_placed_mesh_says_it_is_placed(placed):
    mesh, maps, placed, copies = placed
    assert repr(placed).startswith(f"Mesh(12 placements of {len(mesh)} triangles, bounds [")
    assert len(placed) == 12 * len(mesh)
    assert repr(copies).startswith(f"Mesh({12 * len(mesh)} triangles, bounds")
    one = strata_rt.Mesh(np.eye(3), [[0, 1, 2]]).place(maps[:1])
    assert repr(one).startswith("Mesh(1 placement of 1 triangle, bounds")

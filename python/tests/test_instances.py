"""A placed mesh (``Mesh.place``) against a mesh of its copies: the mesh is
stored once and rays enter it in its own space, yet every first hit and
every occlusion answer is the copies' (face ``k * T + j`` is face ``j`` of
copy ``k``), under random maps with non-uniform scale, shear and mirroring.
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


def test_bad_maps_name_the_argument_and_unwalked_queries_say_so(placed):
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
    with pytest.raises(NotImplementedError, match="all_hits"):
        placed.all_hits(np.zeros((1, 3)), np.ones((1, 3)))
    with pytest.raises(NotImplementedError, match="contains"):
        placed.contains(np.zeros((1, 3)))

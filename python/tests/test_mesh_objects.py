"""A Mesh as an object: made from another mesh object, and pickled.

A pickled mesh comes back as its triangles, one vertex row per corner;
every answer depends on the triangles' corners alone, so the copy answers
every query bit for bit as the original does, a placed mesh included.
"""

import pickle

import numpy as np
import pytest

import helpers
import strata_rt


def answers(mesh, origins, directions, points):
    hits = mesh.intersect(origins, directions)
    splits, t, prim = mesh.all_hits(origins, directions)
    near = mesh.closest_point(points, signed=True)
    return {
        "t": hits.t, "prim": hits.prim, "u": hits.u, "v": hits.v, "normal": hits.normal,
        "occluded": mesh.occluded(origins, directions, t_max=1.5),
        "splits": splits, "all_t": t, "all_prim": prim,
        "count": mesh.count_hits(origins, directions),
        "contains": mesh.contains(points),
        "near_point": near.point, "near_distance": near.distance, "near_prim": near.prim,
    }


def assert_same_answers(a, b):
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


@pytest.fixture
def rays_and_points(bumpy, rng):
    vertices, _ = bumpy
    origins, directions = helpers.random_rays(rng, vertices, 4000)
    points = rng.uniform(-1.5, 1.5, size=(2000, 3))
    return origins, directions, points


def test_a_pickled_mesh_answers_bit_for_bit_as_the_original(bumpy, rays_and_points):
    mesh = strata_rt.Mesh(*bumpy)
    copy = pickle.loads(pickle.dumps(mesh))
    assert isinstance(copy, strata_rt.Mesh) and len(copy) == len(mesh)
    np.testing.assert_array_equal(copy.triangles, mesh.triangles)
    before = answers(mesh, *rays_and_points)
    assert before["prim"].max() >= 0 and before["contains"].any(), "the rays must hit"
    assert_same_answers(answers(copy, *rays_and_points), before)


def test_a_pickled_placed_mesh_answers_as_its_copies(bumpy, rays_and_points):
    transforms = np.array([np.eye(4), np.diag([0.5, 2.0, 1.0, 1.0])])
    transforms[1, :3, 3] = [0.3, 0.0, 0.0]
    placed = strata_rt.Mesh(*bumpy).place(transforms)
    copy = pickle.loads(pickle.dumps(placed))
    assert len(copy) == len(placed)
    assert_same_answers(answers(copy, *rays_and_points), answers(placed, *rays_and_points))


def test_one_object_with_vertices_and_faces_is_a_mesh(bumpy, rays_and_points):
    vertices, faces = bumpy

    class Like:  # what trimesh.Trimesh offers, and nothing else
        def __init__(self):
            self.vertices, self.faces = vertices, faces

    mesh = strata_rt.Mesh(Like())
    assert_same_answers(answers(mesh, *rays_and_points), answers(strata_rt.Mesh(vertices, faces), *rays_and_points))
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.Trimesh(vertices, faces, process=False)
    np.testing.assert_array_equal(strata_rt.Mesh(tm).triangles, mesh.triangles)
    with pytest.raises(TypeError, match="vertices and faces"):
        strata_rt.Mesh(vertices)


def test_a_loaded_mesh_gives_its_vertices_and_faces(bunny):
    """Mesh.load's vertices and faces make the same mesh again: each face's
    corners are the file's, and a Mesh of them answers as the loaded one."""
    path = helpers.bunny_path()
    loaded = strata_rt.Mesh.load(path)
    v, f = loaded.vertices, loaded.faces
    assert v.dtype == np.float64 and f.dtype == np.int64 and f.shape == (len(loaded), 3)
    np.testing.assert_array_equal(v[f].astype(np.float32), loaded.triangles)
    file_v, file_f = bunny
    used = np.unique(file_f)
    assert len(v) == len(np.unique(file_v[used].astype(np.float32), axis=0))
    again = strata_rt.Mesh(v, f)
    rng = np.random.default_rng(2)
    o, d = helpers.random_rays(rng, v, 2000)
    np.testing.assert_array_equal(again.count_hits(o, d), loaded.count_hits(o, d))

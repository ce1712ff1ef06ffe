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


def same_result(copy, original):
    """`copy` is `original` again: same class, keys, arrays (dtype and
    shape too), None where it has None, len and repr."""
    assert type(copy) is type(original)
    assert copy.keys() == original.keys()
    for key in ("t", "prim", "u", "v", "normal", "point", "splits", "ray", "distance"):
        a, b = getattr(original, key, None), getattr(copy, key, None)
        if a is None:
            assert b is None, key
        else:
            assert b.dtype == a.dtype and b.shape == a.shape, key
            np.testing.assert_array_equal(b, a, err_msg=key)
    assert repr(copy) == repr(original)
    try:
        n = len(original)
    except TypeError:
        with pytest.raises(TypeError):
            len(copy)
    else:
        assert len(copy) == n


def test_results_pickle_as_equal_results(bumpy, rays_and_points):
    """Hits, Crossings and ClosestPoints pickle, as a Mesh does, and
    unpickle to the same arrays, Nones and shape (a multiprocessing worker
    returns them pickled)."""
    mesh = strata_rt.Mesh(*bumpy)
    origins, directions, points = rays_and_points
    results = [
        mesh.intersect(origins, directions),
        mesh.intersect(origins[:60].reshape(3, 4, 5, 3), directions[:60].reshape(3, 4, 5, 3), fields=("t", "prim")),
        mesh.intersect(origins[0], directions[0]),  # one ray: 0-d arrays, no len()
        mesh.intersect(origins[:0], directions[:0]),
        mesh.all_hits(origins, directions),
        mesh.all_hits(origins, directions, uv=True),
        mesh.closest_point(points),
        mesh.closest_point(points[:24].reshape(2, 4, 3, 3), signed=True),
        mesh.closest_point(points[0]),
    ]
    assert results[0].prim.max() >= 0 and len(results[4].t) > 0, "the rays must hit"
    for result in results:
        for protocol in (2, pickle.HIGHEST_PROTOCOL):
            same_result(pickle.loads(pickle.dumps(result, protocol=protocol)), result)
    splits, t, prim = pickle.loads(pickle.dumps(results[4]))  # still unpacks
    np.testing.assert_array_equal(splits, results[4].splits)


def first_hits_in_a_worker(args):
    mesh, origins, directions = args
    return mesh.intersect(origins, directions), mesh.all_hits(origins, directions), mesh.closest_point(origins)


def test_a_worker_process_returns_results(bumpy, rays_and_points):
    import multiprocessing

    mesh = strata_rt.Mesh(*bumpy)
    origins, directions, _ = rays_and_points
    o, d = origins[:200], directions[:200]
    # spawn: a fresh interpreter (fork would copy the parent's thread pools
    # without their threads).
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        hits, crossings, near = pool.map(first_hits_in_a_worker, [(mesh, o, d)])[0]
    same_result(hits, mesh.intersect(o, d))
    same_result(crossings, mesh.all_hits(o, d))
    same_result(near, mesh.closest_point(o))


def test_an_open3d_mesh_legacy_or_tensor_is_a_mesh(rays_and_points):
    """Mesh(o3d.geometry.TriangleMesh) (vertices, triangles) and
    Mesh(o3d.t.geometry.TriangleMesh) (vertex.positions, triangle.indices)
    answer as Mesh(vertices, faces) of their arrays."""
    o3d = pytest.importorskip("open3d")
    legacy = o3d.geometry.TriangleMesh.create_box(1.0, 2.0, 0.5).translate([-0.5, -1.0, -0.25])
    tensor = o3d.t.geometry.TriangleMesh.from_legacy(legacy)
    vertices, faces = np.asarray(legacy.vertices), np.asarray(legacy.triangles)
    want = strata_rt.Mesh(vertices, faces)
    origins, directions, points = rays_and_points
    before = answers(want, origins, directions, points)
    assert before["prim"].max() >= 0 and before["contains"].any(), "the rays must hit"
    for mesh in (strata_rt.Mesh(legacy), strata_rt.Mesh(tensor)):
        np.testing.assert_array_equal(mesh.triangles, want.triangles)
        assert_same_answers(answers(mesh, origins, directions, points), before)
    assert len(strata_rt.Mesh(o3d.t.geometry.TriangleMesh())) == 0


def test_a_trimesh_scene_says_how_to_get_one_mesh():
    trimesh = pytest.importorskip("trimesh")
    scene = trimesh.Scene([trimesh.creation.box(), trimesh.creation.icosphere()])
    with pytest.raises(TypeError) as info:
        strata_rt.Mesh(scene)
    message = str(info.value)
    assert "Scene" in message and 'force="mesh"' in message and "Mesh.load(path)" in message
    # What it says to call exists in this trimesh, and joins the scene.
    if "trimesh.load_mesh(path)" in message:
        assert callable(trimesh.load_mesh)
    joined = scene.to_mesh() if "scene.to_mesh()" in message else scene.dump(concatenate=True)
    assert len(strata_rt.Mesh(joined)) == sum(len(g.faces) for g in scene.geometry.values())


def test_a_mesh_pickles_as_its_stub_says(bumpy, tmp_path):
    """From float64 arrays float32 does not hold: Mesh(float64 vertices as
    given, int64 faces); else, and loaded: float32 corners; placed:
    Mesh._placed(float32, int64, float64 maps)."""
    vertices, faces = bumpy
    given = strata_rt.Mesh(vertices, faces).__reduce__()
    assert given[0] is strata_rt.Mesh
    assert [a.dtype for a in given[1]] == [np.float64, np.int64]
    np.testing.assert_array_equal(given[1][0], vertices)
    exact = strata_rt.Mesh(vertices.astype(np.float32), faces).__reduce__()
    assert exact[0] is strata_rt.Mesh and [a.dtype for a in exact[1]] == [np.float32, np.int64]
    placed = strata_rt.Mesh(vertices, faces).place(np.tile(np.eye(3, 4), (2, 1, 1)))
    call, args = placed.__reduce__()
    assert call == strata_rt.Mesh._placed
    assert [a.dtype for a in args] == [np.float32, np.int64, np.float64] and args[2].shape == (2, 3, 4)
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    call, args = strata_rt.Mesh.load(obj).__reduce__()
    assert call is strata_rt.Mesh and [a.dtype for a in args] == [np.float32, np.int64]

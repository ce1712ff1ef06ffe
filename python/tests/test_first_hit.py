"""intersect and occluded against float64 brute force and Embree (robust
mode, through embreex), on the bunny and a generated mesh; the same
answers for any thread count and any input dtype or layout."""

import os

import numpy as np
import pytest

import helpers
import strata_rt

MESHES = ["bumpy", "bunny"]


@pytest.fixture(params=MESHES, scope="module")
def case(request):
    """(vertices as stored, faces, mesh, origins, directions, brute force)."""
    rng = np.random.default_rng(2024)
    vertices, faces = request.getfixturevalue(request.param)
    vertices = helpers.as_stored(vertices)
    mesh = strata_rt.Mesh(vertices, faces)
    origins, directions = helpers.random_rays(rng, vertices, 1000)
    brute = helpers.BruteHits(vertices[faces], origins, directions)
    return vertices, faces, mesh, origins, directions, brute


def scale(vertices):
    return float(np.abs(vertices).max())


def bumpy_query(bumpy, n, seed):
    """The bumpy mesh, n random rays at it, and the generator that drew
    them (for a test's further draws)."""
    vertices, faces = bumpy
    rng = np.random.default_rng(seed)
    origins, directions = helpers.random_rays(rng, vertices, n)
    return strata_rt.Mesh(vertices, faces), origins, directions, rng


def test_first_hits_match_brute_force_away_from_edges(case):
    vertices, faces, mesh, origins, directions, brute = case
    hits = mesh.intersect(origins, directions)
    clear = brute.clear
    assert clear.mean() > 0.8, f"only {clear.sum()} rays clear of edges"
    assert (brute.first_prim[clear] >= 0).sum() > 300, "too few hits to compare"
    np.testing.assert_array_equal(hits.prim[clear], brute.first_prim[clear])
    hit = clear & (brute.first_prim >= 0)
    np.testing.assert_allclose(hits.t[hit], brute.first_t[hit], rtol=1e-5, atol=1e-6 * scale(vertices))
    np.testing.assert_allclose(hits.u[hit], brute.first_u[hit], atol=1e-3)
    np.testing.assert_allclose(hits.v[hit], brute.first_v[hit], atol=1e-3)
    # The geometric normal: the face's, by the right-hand rule.
    tri = vertices[faces[hits.prim[hit]]]
    normal = helpers.unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    np.testing.assert_allclose(hits.normal[hit], normal, atol=1e-5)
    point = origins[hit] + directions[hit] * brute.first_t[hit][:, None]
    np.testing.assert_allclose(hits.point[hit], point, atol=1e-5 * scale(vertices))
    # Misses: inf, -1, NaN.
    miss = hits.prim < 0
    assert np.isinf(hits.t[miss]).all()
    assert np.isnan(hits.u[miss]).all() and np.isnan(hits.normal[miss]).all()
    assert hits.t.dtype == np.float32 and hits.prim.dtype == np.int64
    assert hits.normal.shape == (len(origins), 3) and hits.point.shape == (len(origins), 3)
    assert set(hits.keys()) == {"t", "prim", "u", "v", "normal", "point"}
    np.testing.assert_array_equal(hits["prim"], hits.prim)


def test_occlusion_matches_brute_force_and_t_max_cuts_rays(case):
    vertices, faces, mesh, origins, directions, brute = case
    clear = brute.clear
    blocked = mesh.occluded(origins, directions)
    assert blocked.dtype == np.bool_
    np.testing.assert_array_equal(blocked[clear], brute.first_prim[clear] >= 0)
    # A per-ray t_max just short of the first hit, and just past it.
    hit = clear & (brute.first_prim >= 0)
    o, d, t = origins[hit], directions[hit], brute.first_t[hit]
    assert not mesh.occluded(o, d, t_max=t * (1 - 1e-4)).any()
    assert (mesh.intersect(o, d, t_max=t * (1 - 1e-4)).prim == -1).all()
    assert mesh.occluded(o, d, t_max=t * (1 + 1e-4)).all()
    np.testing.assert_array_equal(mesh.intersect(o, d, t_max=t * (1 + 1e-4)).prim, brute.first_prim[hit])
    # A scalar t_max: hits beyond it are gone.
    limit = float(np.median(t))
    near = mesh.intersect(o, d, t_max=limit)
    sure = np.abs(t - limit) > 1e-4 * limit
    np.testing.assert_array_equal((near.prim >= 0)[sure], (t < limit)[sure])


def test_first_hits_match_embree_robust(case):
    embree = pytest.importorskip("embreex.rtcore_scene", reason="embreex is in tools/requirements.txt")
    vertices, faces, mesh, origins, directions, brute = case
    scene = embree.EmbreeScene(robust=True)
    from embreex.mesh_construction import TriangleMesh

    TriangleMesh(scene, vertices.astype(np.float32), faces.astype(np.int32))
    o, d = origins.astype(np.float32), directions.astype(np.float32)
    answer = scene.run(o, d, output=1)
    embree_prim = answer["primID"].astype(np.int64)
    hits = mesh.intersect(o, d)
    clear = brute.clear
    np.testing.assert_array_equal(hits.prim[clear], embree_prim[clear])
    hit = clear & (embree_prim >= 0)
    np.testing.assert_allclose(hits.t[hit], answer["tfar"][hit], rtol=1e-5, atol=1e-6 * scale(vertices))
    np.testing.assert_allclose(hits.u[hit], answer["u"][hit], atol=1e-3)
    np.testing.assert_allclose(hits.v[hit], answer["v"][hit], atol=1e-3)
    occluded = scene.run(o, d, query="OCCLUDED") == 0
    np.testing.assert_array_equal(mesh.occluded(o, d)[clear], occluded[clear])


def test_answers_are_the_same_for_any_thread_count(bumpy, rng):
    mesh = strata_rt.Mesh(*bumpy)
    o, d = helpers.random_rays(rng, bumpy[0], 20_000)
    a, b = mesh.intersect(o, d), mesh.intersect(o, d, threads=1)
    for key in a.keys():
        np.testing.assert_array_equal(a[key], b[key])
    np.testing.assert_array_equal(mesh.occluded(o, d, threads=3), mesh.occluded(o, d, threads=1))


def test_any_dtype_and_layout_gives_the_same_answers(bumpy, rng):
    vertices, faces = bumpy
    mesh = strata_rt.Mesh(vertices.astype(np.float32), faces.astype(np.int32))
    o, d = helpers.random_rays(rng, vertices, 500)
    o32, d32 = o.astype(np.float32), d.astype(np.float32)
    want = mesh.intersect(o32, d32)
    wide = np.hstack([o32, d32]).astype(np.float64)  # columns of one array: strided views
    for origins, directions in [
        (o32.astype(np.float64), d32.astype(np.float64)),
        (o32.tolist(), d32.tolist()),
        (wide[:, :3], wide[:, 3:]),
        (np.asfortranarray(o32), np.asfortranarray(d32)),
        (o32[::-1][::-1], d32[::-1][::-1]),
        (o32.astype(np.longdouble), d32.astype(np.longdouble)),
        (np.hstack([o32, d32])[:, :3], np.hstack([o32, d32])[:, 3:]),  # float32 (n, 6) columns
    ]:
        got = mesh.intersect(origins, directions)
        np.testing.assert_array_equal(got.prim, want.prim)
        np.testing.assert_array_equal(got.t, want.t)
    # Views read where they lie, by their strides: rows backwards, every
    # other row, columns of an (n, 6) array; each answers for the rows it
    # shows, in every query.
    for view in (slice(None, None, -1), slice(None, None, 2), slice(7, None, 3)):
        got = mesh.intersect(o32[view], d32[view])
        np.testing.assert_array_equal(got.prim, want.prim[view])
        np.testing.assert_array_equal(got.t, want.t[view])
    for rays in (np.hstack([o32, d32]), np.hstack([o32, d32]).astype(np.float64)):
        o_view, d_view = rays[:, :3], rays[:, 3:]
        assert not o_view.flags.c_contiguous
        np.testing.assert_array_equal(mesh.occluded(o_view, d_view), mesh.occluded(o32, d32))
        np.testing.assert_array_equal(mesh.count_hits(o_view, d_view), mesh.count_hits(o32, d32))
        listed, contiguous = mesh.all_hits(o_view, d_view, uv=True), mesh.all_hits(o32, d32, uv=True)
        for key in contiguous.keys():
            np.testing.assert_array_equal(listed[key], contiguous[key])
    points = np.hstack([o32, o32])[:, 3:]
    np.testing.assert_array_equal(mesh.contains(points), mesh.contains(o32))
    np.testing.assert_array_equal(mesh.closest_point(points).distance, mesh.closest_point(o32).distance)
    # Every integer dtype of faces, any float dtype of vertices: the same mesh.
    for vdtype, fdtype in [(np.float64, np.int64), (np.float16, np.uint16), (np.float32, np.uint64), (np.float64, np.int16)]:
        v = vertices.astype(np.float32).astype(vdtype)
        other = strata_rt.Mesh(v, faces.astype(fdtype))
        if vdtype is np.float16:
            continue  # a different (coarser) mesh; it only has to build
        np.testing.assert_array_equal(other.intersect(o32, d32).prim, want.prim)
    # Vertices as a view of a wider array's columns: the same mesh.
    wide_vertices = np.hstack([vertices, vertices]).astype(np.float32)[:, 3:]
    np.testing.assert_array_equal(strata_rt.Mesh(wide_vertices, faces).intersect(o32, d32).t, want.t)
    # Lists of faces and vertices.
    listed = strata_rt.Mesh(vertices.astype(np.float32).tolist(), faces.tolist())
    np.testing.assert_array_equal(listed.intersect(o32, d32).t, want.t)


def test_zero_misses_zeroes_a_miss_s_arrays_and_nothing_else(bumpy, rng):
    """zero_misses=True (Open3D's convention): a miss's u, v, normal and
    point are 0 where they would be NaN; t stays inf, prim -1, and every
    hit's arrays are the default call's bit for bit."""
    mesh = strata_rt.Mesh(*bumpy)
    o, d = helpers.random_rays(rng, bumpy[0], 3000)
    plain, zeroed = mesh.intersect(o, d), mesh.intersect(o, d, zero_misses=True)
    miss = plain.prim < 0
    assert 0 < miss.sum() < len(o)
    np.testing.assert_array_equal(zeroed.t, plain.t)
    np.testing.assert_array_equal(zeroed.prim, plain.prim)
    for key in ("u", "v", "normal", "point"):
        assert np.isnan(plain[key][miss]).all() and (zeroed[key][miss] == 0).all(), key
        np.testing.assert_array_equal(zeroed[key][~miss], plain[key][~miss])
    some = mesh.intersect(o, d, fields=("t", "normal"), zero_misses=True)
    assert some.u is None and (some.normal[miss] == 0).all()


def test_empty_input_gives_empty_answers(bumpy):
    mesh = strata_rt.Mesh(*bumpy)
    for empty in (np.zeros((0, 3)), [], np.zeros((0, 3), dtype=np.float32)):
        hits = mesh.intersect(empty, empty)
        assert hits.t.shape == (0,) and hits.normal.shape == (0, 3) and hits.prim.dtype == np.int64
        assert mesh.occluded(empty, empty).shape == (0,)
    empty_mesh = strata_rt.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    assert empty_mesh.triangle_count == 0
    # No bounds to show (the empty box's are inf and -inf); one triangle is singular.
    assert repr(empty_mesh) == "Mesh(0 triangles)"
    assert repr(strata_rt.Mesh(np.eye(3), [[0, 1, 2]])) == "Mesh(1 triangle, bounds [0.0, 0.0, 0.0] to [1.0, 1.0, 1.0])"
    assert (empty_mesh.intersect([[0, 0, 0]], [[0, 0, 1]]).prim == -1).all()


def test_mesh_properties_and_load(bunny, tmp_path):
    vertices, faces = bunny
    mesh = strata_rt.Mesh(vertices, faces)
    assert mesh.triangle_count == len(faces) == len(mesh)
    np.testing.assert_array_equal(mesh.bounds, [vertices.astype(np.float32).min(0), vertices.astype(np.float32).max(0)])
    np.testing.assert_array_equal(mesh.triangles, vertices.astype(np.float32)[faces])
    # Mesh.load: strata's own OBJ loader, face i of the file is triangle i.
    loaded = strata_rt.Mesh.load(helpers.bunny_path())
    np.testing.assert_array_equal(loaded.triangles, mesh.triangles)
    # A PLY written here loads the same triangles.
    ply = tmp_path / "bunny.ply"
    with open(ply, "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        np.savetxt(f, vertices.astype(np.float32), fmt="%.9g")
        np.savetxt(f, np.hstack([np.full((len(faces), 1), 3), faces]), fmt="%d")
    np.testing.assert_array_equal(strata_rt.Mesh.load(str(ply)).triangles, mesh.triangles)


def test_every_query_answers_for_t_in_0_to_t_max_inclusive():
    """A hit at exactly t_max counts, for every query alike (as Embree's
    tfar); one just short of it does not."""
    quad = strata_rt.Mesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    o, d = np.array([[0.25, -0.5, 1.0]]), np.array([[0.0, 0.0, -1.0]])
    for t_max, expected in [(1.0, 1), (np.nextafter(np.float32(1), np.float32(0)), 0), (np.inf, 1)]:
        hits = quad.intersect(o, d, t_max=t_max)
        assert (hits.prim[0] >= 0) == bool(expected), t_max
        assert quad.occluded(o, d, t_max=t_max)[0] == bool(expected), t_max
        assert quad.count_hits(o, d, t_max=t_max)[0] == expected, t_max
        assert np.diff(quad.all_hits(o, d, t_max=t_max)[0])[0] == expected, t_max


def test_fields_computes_only_what_is_asked(bumpy):
    mesh, origins, directions, _ = bumpy_query(bumpy, 500, seed=3)
    every = mesh.intersect(origins, directions)
    some = mesh.intersect(origins, directions, fields=("t", "prim"))
    assert some.keys() == ["t", "prim"] and some.normal is None and some.point is None
    assert "u" not in some and len(some) == 500
    np.testing.assert_array_equal(some.t, every.t)
    np.testing.assert_array_equal(some.prim, every.prim)
    with pytest.raises(ValueError, match="fields"):
        mesh.intersect(origins, directions, fields=("depth",))
    # One name alone is not a sequence of its letters.
    with pytest.raises(TypeError, match=r"fields must be a sequence of names .* got the str 't'"):
        mesh.intersect(origins, directions, fields="t")
    with pytest.raises(TypeError, match="fields must be a sequence of names from t, prim"):
        mesh.intersect(origins, directions, fields=[1, 2])
    assert mesh.intersect(origins, directions, fields=None).keys() == every.keys()


def test_inputs_of_any_leading_shape_answer_in_that_shape(bumpy):
    mesh, o, d, rng = bumpy_query(bumpy, 60, seed=4)
    grid_o, grid_d = o.reshape(3, 4, 5, 3), d.reshape(3, 4, 5, 3)
    flat, grid = mesh.intersect(o, d), mesh.intersect(grid_o, grid_d, t_max=np.full((3, 4, 5), np.inf))
    assert grid.t.shape == (3, 4, 5) and grid.normal.shape == (3, 4, 5, 3) and grid.point.shape == (3, 4, 5, 3)
    for key in flat.keys():
        np.testing.assert_array_equal(grid[key].reshape(flat[key].shape), flat[key])
    assert mesh.occluded(grid_o, grid_d).shape == (3, 4, 5)
    np.testing.assert_array_equal(mesh.count_hits(grid_o, grid_d).reshape(-1), mesh.count_hits(o, d))
    np.testing.assert_array_equal(mesh.all_hits(grid_o, grid_d).splits, mesh.all_hits(o, d).splits)
    points = rng.uniform(-1, 1, (2, 3, 4, 3))
    assert mesh.contains(points).shape == (2, 3, 4)
    near = mesh.closest_point(points)
    assert near.point.shape == (2, 3, 4, 3) and near.distance.shape == (2, 3, 4)
    np.testing.assert_array_equal(near.distance.reshape(-1), mesh.closest_point(points.reshape(-1, 3)).distance)


def test_one_row_given_as_a_vector_answers_as_a_scalar(bumpy):
    # (..., 3) with no leading axis: one ray or point, as an array or a
    # list, its answers 0-d (vectors of 3 for normals and points), each
    # the answer of the same row given as (1, 3).
    mesh, o, d, rng = bumpy_query(bumpy, 40, seed=5)
    hits = mesh.intersect(o, d)
    i = int(np.flatnonzero(hits.prim >= 0)[0])
    for origin, direction in [(o[i], d[i]), (list(o[i]), tuple(d[i]))]:
        one = mesh.intersect(origin, direction)
        assert one.t.shape == () and one.prim.shape == () and one.normal.shape == (3,) and one.point.shape == (3,)
        for key in hits.keys():
            np.testing.assert_array_equal(one[key], hits[key][i])
        assert mesh.occluded(origin, direction).shape == ()
        assert mesh.count_hits(origin, direction) == mesh.count_hits(o[i:i + 1], d[i:i + 1])[0]
        assert mesh.all_hits(origin, direction).splits.tolist() == mesh.all_hits(o[i:i + 1], d[i:i + 1]).splits.tolist()
    p = rng.uniform(-1, 1, 3)
    assert mesh.contains(p).shape == () and mesh.contains(p) == mesh.contains(p[None])[0]
    near = mesh.closest_point(p)
    assert near.point.shape == (3,) and near.distance == mesh.closest_point(p[None]).distance[0]
    with pytest.raises(ValueError, match=r"origins must be an \(n, 3\) array of floats; got shape \(4,\)"):
        mesh.intersect(np.zeros(4), np.zeros(4))


def test_len_and_repr_count_the_queries_in_any_shape(bumpy):
    # len() is the first axis, as numpy's; the repr counts every query
    # (and names the shape where it is not a list), with or without an
    # array computed; one ray or point given alone has no len(), as a 0-d
    # numpy array has none.
    mesh, o, d, rng = bumpy_query(bumpy, 60, seed=6)
    flat = mesh.intersect(o, d)
    hits = int((flat.prim >= 0).sum())
    assert 1 < hits < 60 and len(flat) == 60
    assert repr(flat).startswith(f"Hits(60 rays, {hits} hits; keys t, prim")
    grid = mesh.intersect(o.reshape(3, 4, 5, 3), d.reshape(3, 4, 5, 3), fields=("t",))
    assert len(grid) == 3 and repr(grid) == f"Hits(60 rays in shape (3, 4, 5), {hits} hits; keys t)"
    assert len(mesh.intersect(o, d, fields=())) == 60
    assert repr(mesh.intersect(o, d, fields=())) == "Hits(60 rays; keys )"
    i = int(np.flatnonzero(flat.prim >= 0)[0])
    one = mesh.intersect(o[i], d[i])
    assert repr(one).startswith("Hits(1 ray, 1 hit; keys")
    with pytest.raises(TypeError, match="one ray given alone"):
        len(one)
    near = mesh.closest_point(rng.uniform(-1, 1, (2, 3, 3)))
    assert len(near) == 2 and repr(near).startswith("ClosestPoints(6 points in shape (2, 3); keys")
    assert repr(mesh.closest_point(o[0])).startswith("ClosestPoints(1 point; keys")
    with pytest.raises(TypeError, match="one point given alone"):
        len(mesh.closest_point(o[0]))


def test_hits_is_a_mapping_of_names_indexed_by_name_only(bumpy):
    # hits[0] and tuple(hits) once failed with "'int' object is not an
    # instance of 'str'": the error now says to index by name or index
    # the array; items(), values() and get() are a mapping's.
    mesh, o, d, rng = bumpy_query(bumpy, 30, seed=7)
    hits = mesh.intersect(o, d)
    for index in (lambda: hits[0], lambda: tuple(hits), lambda: hits[1:3]):
        with pytest.raises(TypeError, match=r'index it by name \(hits\["t"\].*hits\.t\[0\]'):
            index()
    with pytest.raises(KeyError):
        hits["depth"]
    assert [k for k, _ in hits.items()] == hits.keys() == list(dict(hits))
    for (key, array), value in zip(hits.items(), hits.values()):
        np.testing.assert_array_equal(array, getattr(hits, key))
        np.testing.assert_array_equal(value, array)
    np.testing.assert_array_equal(hits.get("t"), hits.t)
    some = mesh.intersect(o, d, fields=("prim",))
    assert some.get("t") is None and some.get("t", 5) == 5 and some.get(0) is None
    assert [k for k, _ in some.items()] == ["prim"] and 0 not in some and "prim" in some
    near = mesh.closest_point(rng.uniform(-1, 1, (5, 3)))
    with pytest.raises(TypeError, match=r'near\["distance"\].*near\.distance\[0\]'):
        near[0]
    assert [k for k, _ in near.items()] == near.keys() and near.get("depth") is None
    np.testing.assert_array_equal(near.get("distance"), near.distance)


def running_threads():
    return len(os.listdir("/proc/self/task"))


def test_threads_never_outnumber_the_tasks(bumpy):
    """threads=N starts no more threads than a call has tasks (chunks of
    256 rays or points): ten rays with threads=1024 once started 1024
    threads (1.4 s); they run on the calling thread, as with threads=1.
    The answers are the same for any count."""
    if not os.path.isdir("/proc/self/task"):
        pytest.skip("counts the process's threads in /proc/self/task (Linux)")
    mesh, o, d, rng = bumpy_query(bumpy, 2000, seed=8)
    points = rng.uniform(-1, 1, (2000, 3))

    def every_query(n, threads):
        return [
            mesh.intersect(o[:n], d[:n], threads=threads).prim,
            mesh.occluded(o[:n], d[:n], threads=threads),
            mesh.count_hits(o[:n], d[:n], threads=threads),
            np.diff(mesh.all_hits(o[:n], d[:n], threads=threads).splits),
            mesh.contains(points[:n], threads=threads),
            mesh.closest_point(points[:n], threads=threads).distance,
        ]

    want = every_query(2000, None)
    before = running_threads()
    for threads in (1, 2, 1024, 4096):
        for got, expected in zip(every_query(10, threads), want):
            np.testing.assert_array_equal(got, expected[:10])
    assert running_threads() <= before, "a call of one task started threads"
    before = running_threads()
    for got, expected in zip(every_query(2000, 37), want):  # 8 tasks
        np.testing.assert_array_equal(got, expected)
    assert running_threads() - before <= 8


def test_ray_queries_say_they_take_t_min():
    for query in ("intersect", "occluded", "all_hits", "count_hits"):
        doc = getattr(strata_rt.Mesh, query).__doc__
        assert "(t_min, t_max]" in doc and "(0, t_max]" not in doc, query


def test_one_origin_or_direction_goes_with_every_row_of_the_other(bumpy):
    # numpy's broadcasting of a single row: the answers are those of the
    # row repeated, in the other array's shape.
    mesh, o, d, rng = bumpy_query(bumpy, 30, seed=7)
    down = np.array([0.0, 0.0, -1.0])
    one_way, repeated = mesh.intersect(o, down), mesh.intersect(o, np.tile(down, (30, 1)))
    for key in repeated.keys():
        np.testing.assert_array_equal(one_way[key], repeated[key])
    np.testing.assert_array_equal(mesh.count_hits(o, [0, 0, -1]), mesh.count_hits(o, np.tile(down, (30, 1))))
    from_one = mesh.intersect(o[0], d.reshape(5, 6, 3), t_max=np.full((5, 6), 10.0))
    assert from_one.t.shape == (5, 6)
    np.testing.assert_array_equal(from_one.t.reshape(-1), mesh.intersect(np.tile(o[0], (30, 1)), d, t_max=10.0).t)
    assert mesh.occluded(o[:1], down).shape == (1,)
    with pytest.raises(ValueError, match="the same length, or one of them one row; got 4 and 3"):
        mesh.intersect(o[:4], d[:3])

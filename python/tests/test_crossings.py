"""all_hits and count_hits: against brute force on random rays; exactly
once per surface crossing on rays aimed at shared edges and vertices of
closed meshes; exactly one hit from inside big boxes."""

import numpy as np
import pytest

import helpers
import strata_rt


def check_layout(splits, t, prim, n):
    assert splits.dtype == np.int64 and splits.shape == (n + 1,) and splits[0] == 0
    assert splits[-1] == len(t) == len(prim) and (np.diff(splits) >= 0).all()
    assert t.dtype == np.float32 and prim.dtype == np.int64
    for i in range(n):
        ts = t[splits[i]:splits[i + 1]]
        assert (np.diff(ts) >= 0).all(), f"ray {i}: crossings not sorted by t"


@pytest.mark.parametrize("name", ["bumpy", "bunny"])
def test_every_crossing_matches_brute_force_on_random_rays(request, name):
    vertices, faces = request.getfixturevalue(name)
    vertices = helpers.as_stored(vertices)
    rng = np.random.default_rng(99)
    mesh = strata_rt.Mesh(vertices, faces)
    origins, directions = helpers.random_rays(rng, vertices, 800)
    brute = helpers.BruteHits(vertices[faces], origins, directions)
    splits, t, prim = mesh.all_hits(origins, directions)
    check_layout(splits, t, prim, len(origins))
    counts = mesh.count_hits(origins, directions)
    assert counts.dtype == np.int64
    np.testing.assert_array_equal(counts, np.diff(splits))
    clear = brute.clear
    assert clear.mean() > 0.8
    np.testing.assert_array_equal(counts[clear], brute.counts()[clear])
    assert brute.counts()[clear].max() >= 4, "no ray crosses the surface several times"
    for i in np.flatnonzero(clear):
        bt, bp = brute.crossings(i)
        np.testing.assert_array_equal(prim[splits[i]:splits[i + 1]], bp)
        np.testing.assert_allclose(t[splits[i]:splits[i + 1]], bt, rtol=1e-5, atol=1e-6)
    # The first crossing is the first hit.
    hits = mesh.intersect(origins, directions)
    some = counts > 0
    np.testing.assert_array_equal(prim[splits[:-1][some]], hits.prim[some])
    np.testing.assert_array_equal(t[splits[:-1][some]], hits.t[some])
    # t_max, scalar or per ray, keeps the crossings up to it.
    limit = np.full(len(origins), np.inf)
    limit[some] = t[splits[:-1][some]] * 1.00001 + 1e-6
    cut_splits, cut_t, _ = mesh.all_hits(origins, directions, t_max=limit)
    assert (cut_t <= limit[np.repeat(np.arange(len(origins)), np.diff(cut_splits))]).all()
    np.testing.assert_array_equal(mesh.count_hits(origins, directions, t_max=limit)[some & clear], 1)
    assert (mesh.count_hits(origins, directions, t_max=0.0) == 0).all()


def through(targets, directions, back):
    """Rays that pass exactly through `targets` (float32), starting `back`
    before them."""
    origins = (targets - directions * back).astype(np.float32)
    return origins, (targets.astype(np.float32) - origins).astype(np.float32)


def edges_of(faces):
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def convex_targets(vertices, faces):
    """Every vertex and every edge's midpoint and quarter points."""
    e = edges_of(faces)
    a, b = vertices[e[:, 0]], vertices[e[:, 1]]
    return np.vstack([vertices, (a + b) / 2, 0.75 * a + 0.25 * b])


@pytest.mark.parametrize("name", ["cube", "icosphere"])
def test_rays_through_shared_edges_and_vertices_cross_a_convex_mesh_twice(name):
    vertices, faces = helpers.cube() if name == "cube" else helpers.icosphere(3)
    if name == "icosphere":
        assert len(vertices) == 642 and len(edges_of(faces)) == 1920
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(5)
    targets = convex_targets(vertices, faces)
    centre = vertices.mean(axis=0)
    # Towards the centre (out through the opposite vertex or edge: both
    # crossings on shared features), and towards random points of the
    # body's inner half, so that the ray enters the body where it meets the
    # edge or vertex (and leaves it at a generic point).
    inward = helpers.unit(centre - targets)
    inner = centre + 0.5 * (helpers.random_directions(rng, len(targets)) * rng.random((len(targets), 1)))
    towards = helpers.unit(inner - targets)
    for directions in (inward, towards):
        o, dd = through(targets, directions, back=3.0)
        counts = mesh.count_hits(o, dd)
        bad = np.flatnonzero(counts != 2)
        assert len(bad) == 0, f"{len(bad)} of {len(o)} rays cross {counts[bad][:10]} times, not 2"
        splits, t, prim = mesh.all_hits(o, dd)
        np.testing.assert_array_equal(np.diff(splits), 2)
        assert (t[1::2] > t[0::2]).all(), "the two crossings coincide"
        assert (mesh.intersect(o, dd).prim >= 0).all(), "a ray slipped through"
        assert mesh.occluded(o, dd).all()
        # From the centre out through each target: exactly one crossing.
        out_o = np.repeat(centre[None], len(targets), axis=0).astype(np.float32)
        out_d = (targets - centre).astype(np.float32)
        np.testing.assert_array_equal(mesh.count_hits(out_o, out_d), 1)


def pyramid(sides):
    """A closed pyramid: apex (0, 0, 1) over a regular polygon of radius 1
    at z = 0, its base a fan from the centre vertex (0, 0, 0)."""
    a = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a), np.zeros(sides)], axis=1)
    vertices = np.vstack([[0, 0, 1], ring, [0, 0, 0]])
    centre = sides + 1
    faces = [[0, 1 + i, 1 + (i + 1) % sides] for i in range(sides)]
    faces += [[centre, 1 + (i + 1) % sides, 1 + i] for i in range(sides)]
    return vertices, np.array(faces, dtype=np.int64)


@pytest.mark.parametrize("sides", [3, 5, 8, 9, 16, 17, 24, 40, 80])
def test_a_ray_through_a_vertex_of_any_valence_crosses_once_there(sides):
    """Down the axis of a pyramid: in through the apex, out through the
    base's centre, each shared by `sides` triangles; and tilted, through
    one of them and a generic point."""
    mesh = strata_rt.Mesh(*pyramid(sides))
    tilt = np.array([0.013, 0.0071, -1.0])
    o = np.array([[0, 0, 5.0], [0, 0, -5.0], [0, 0, 1] - 5 * tilt, -5 * tilt])
    d = np.array([[0, 0, -1.0], [0, 0, 1.0], tilt, tilt])
    np.testing.assert_array_equal(mesh.count_hits(o, d), 2)
    np.testing.assert_array_equal(np.diff(mesh.all_hits(o, d)[0]), 2)


def test_rays_through_the_closed_bunny_s_vertices_cross_it_an_even_number_of_times(closed_bunny):
    vertices, faces = closed_bunny
    vertices = helpers.as_stored(vertices)
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(8)
    pick = rng.choice(len(vertices), 3000, replace=False)
    e = edges_of(faces)[rng.choice(len(edges_of(faces)), 3000, replace=False)]
    targets = np.vstack([vertices[pick], (vertices[e[:, 0]] + vertices[e[:, 1]]) / 2])
    size = np.ptp(vertices, axis=0).max()
    directions = helpers.random_directions(rng, len(targets))
    # From outside the bounding box, on to infinity: a closed surface is
    # crossed an even number of times; a missed or doubled crossing at the
    # shared edge or vertex makes it odd.
    o, d = through(targets, directions, back=3.0 * size)
    counts = mesh.count_hits(o, d)
    odd = np.flatnonzero(counts % 2)
    assert len(odd) == 0, f"{len(odd)} of {len(o)} rays cross an odd number of times: {counts[odd][:10]}"
    assert (counts > 0).mean() > 0.9
    splits, _, _ = mesh.all_hits(o, d)
    np.testing.assert_array_equal(np.diff(splits), counts)


@pytest.mark.parametrize("side", [1e4, 1e6])
def test_a_big_box_hit_from_inside_is_crossed_once(side):
    rng = np.random.default_rng(int(side))
    lo = np.array([side, -2 * side, 0.5 * side])  # away from the origin, too
    vertices, faces = helpers.box(lo, lo + side)
    mesh = strata_rt.Mesh(vertices, faces)
    n = 4000
    origins = lo + side * (0.05 + 0.9 * rng.random((n, 3)))
    directions = helpers.random_directions(rng, n)
    counts = mesh.count_hits(origins, directions)
    assert (counts == 1).all(), f"crossings from inside: {np.unique(counts, return_counts=True)}"
    splits, t, prim = mesh.all_hits(origins, directions)
    np.testing.assert_array_equal(np.diff(splits), 1)
    hits = mesh.intersect(origins, directions)
    np.testing.assert_array_equal(hits.prim, prim)
    np.testing.assert_array_equal(hits.t, t)
    # The hit lies on the box: one coordinate on a face plane.
    on_face = np.minimum(np.abs(hits.point - lo), np.abs(hits.point - (lo + side))).min(axis=1)
    assert (on_face <= side * 1e-6).all()


def test_empty_rays_give_empty_lists(bumpy):
    mesh = strata_rt.Mesh(*bumpy)
    splits, t, prim = mesh.all_hits(np.zeros((0, 3)), np.zeros((0, 3)))
    np.testing.assert_array_equal(splits, [0])
    assert t.shape == (0,) and prim.shape == (0,) and splits.dtype == np.int64
    assert mesh.count_hits([], []).shape == (0,)


def test_all_hits_is_named_and_gives_rays_and_barycentrics(bumpy):
    """all_hits's Crossings: splits, t, prim as before (and as a tuple),
    each crossing's ray, and with uv=True where it meets its face, in
    float64."""
    vertices, faces = bumpy
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(5)
    origins, directions = helpers.random_rays(rng, vertices, 300)
    found = mesh.all_hits(origins, directions, uv=True)
    splits, t, prim = found
    np.testing.assert_array_equal(splits, found.splits)
    np.testing.assert_array_equal(found.ray, np.repeat(np.arange(300), np.diff(splits)))
    assert set(found.keys()) == {"splits", "t", "prim", "ray", "u", "v"} and found.u.dtype == np.float64
    assert mesh.all_hits(origins, directions).u is None
    tri = vertices[faces[prim]]
    on = (1 - found.u - found.v)[:, None] * tri[:, 0] + found.u[:, None] * tri[:, 1] + found.v[:, None] * tri[:, 2]
    along = origins[found.ray] + t[:, None].astype(np.float64) * directions[found.ray]
    np.testing.assert_allclose(on, along, atol=1e-5)
    assert (found.u >= -1e-9).all() and (found.v >= -1e-9).all() and (found.u + found.v <= 1 + 1e-9).all()


def test_all_hits_over_many_tasks_and_chunks_is_one_list_in_ray_order(bumpy):
    """More rays than one chunk between Ctrl-C checks (65,536), so hundreds
    of tasks' lists are copied into one on every thread: each column lines
    up with count_hits and with the same rays' answers one thread and a
    ray at a time."""
    vertices, faces = bumpy
    mesh = strata_rt.Mesh(vertices, faces)
    rng = np.random.default_rng(6)
    origins, directions = helpers.random_rays(rng, vertices, 70_000)
    found = mesh.all_hits(origins, directions, uv=True)
    counts = mesh.count_hits(origins, directions)
    assert found.splits[0] == 0 and counts.sum() > 70_000
    np.testing.assert_array_equal(np.diff(found.splits), counts)
    np.testing.assert_array_equal(found.ray, np.repeat(np.arange(70_000), counts))
    one = mesh.all_hits(origins, directions, uv=True, threads=1)
    for key in found.keys():
        np.testing.assert_array_equal(found[key], one[key])
    for i in rng.choice(70_000, 40, replace=False):
        alone = mesh.all_hits(origins[i:i + 1], directions[i:i + 1], uv=True)
        rows = slice(found.splits[i], found.splits[i + 1])
        for key in ("t", "prim", "u", "v"):
            np.testing.assert_array_equal(found[key][rows], alone[key])


def test_crossings_count_in_words_and_are_a_mapping_that_unpacks(bumpy):
    mesh = strata_rt.Mesh(*bumpy)
    rng = np.random.default_rng(6)
    origins, directions = helpers.random_rays(rng, bumpy[0], 40)
    found = mesh.all_hits(origins, directions)
    i = int(np.flatnonzero(np.diff(found.splits) == 2)[0])
    assert repr(mesh.all_hits(origins[i], directions[i])).startswith("Crossings(1 ray, 2 crossings; keys")
    one = mesh.all_hits(origins[i], directions[i], t_max=found.t[found.splits[i]])
    assert repr(one) == "Crossings(1 ray, 1 crossing; keys splits, t, prim, ray)"
    # Still a tuple of splits, t, prim by position; names otherwise.
    splits, t, prim = found
    assert found[0] is not None and np.array_equal(found[-1], prim)
    with pytest.raises(IndexError):
        found[3]
    with pytest.raises(TypeError, match=r'indexed by name \(found\["t"\]'):
        found[1.5]
    assert [k for k, _ in found.items()] == found.keys() == ["splits", "t", "prim", "ray"]
    assert found.get("u") is None and found.get("u", 0) == 0 and "u" not in found and 0 not in found
    np.testing.assert_array_equal(found.get("ray"), found.ray)
    assert len(found.values()) == 4

"""Every bad input raises a Python exception whose message names what was
wrong; nothing crashes the interpreter; Ctrl-C stops a long query."""

import os
import signal
import threading
import time
import warnings

import numpy as np
import pytest

import helpers
import strata_rt

V, F = helpers.cube()
MESH = strata_rt.Mesh(V, F)
O = np.array([[0.0, 0.0, 5.0], [0.5, 0.5, 5.0]])
D = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])


def raises(call, *words, kind=ValueError):
    """`call()` raises `kind` with every one of `words` in its message."""
    with pytest.raises(kind) as info:
        call()
    message = str(info.value)
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"
    return message


MESH_CASES = {
    "vertices of 2 columns": (lambda: strata_rt.Mesh(np.zeros((4, 2)), F[:1] % 4), ["vertices", "(n, 3)", "(4, 2)"]),
    "vertices of 1 dimension": (lambda: strata_rt.Mesh(np.zeros(9), F[:1]), ["vertices", "(n, 3)", "(9,)"]),
    "vertices of strings": (lambda: strata_rt.Mesh([["a", "b", "c"]], [[0, 0, 0]]), ["vertices", "dtype"]),
    "ragged vertices": (lambda: strata_rt.Mesh([[0, 0, 0], [1, 2]], [[0, 1, 0]]), ["vertices"]),
    "a NaN vertex": (lambda: strata_rt.Mesh(np.where(np.arange(24).reshape(8, 3) == 4, np.nan, V), F), ["vertices[1]", "not finite"]),
    "an infinite vertex": (lambda: strata_rt.Mesh(np.where(np.arange(24).reshape(8, 3) == 23, np.inf, V), F), ["vertices[7]", "not finite"]),
    "a vertex beyond float32": (lambda: strata_rt.Mesh(V * np.array([1, 1, 1e39]), F), ["vertices[0]", "not finite as float32", "-1e39]"]),
    # Quoted as given, not as it lies relative to the mesh's centre.
    "a NaN vertex far out": (lambda: strata_rt.Mesh(np.where(np.arange(24).reshape(8, 3) == 4, np.nan, V + 1000), F), ["vertices[1]", "[999.0, NaN, 1001.0]"]),
    "float faces": (lambda: strata_rt.Mesh(V, F.astype(np.float64)), ["faces", "integers", "float64"]),
    "faces of 4 columns": (lambda: strata_rt.Mesh(V, np.zeros((2, 4), dtype=np.int64)), ["faces", "(n, 3)", "(2, 4)"]),
    "an index past the end": (lambda: strata_rt.Mesh(V, np.vstack([F, [[0, 1, 8]]])), ["faces[12][2] = 8", "8 vertices"]),
    "a negative index": (lambda: strata_rt.Mesh(V, np.vstack([F[:3], [[-1, 1, 2]]]).astype(np.int32)), ["faces[3][0] = -1"]),
    "a huge unsigned index": (lambda: strata_rt.Mesh(V, np.array([[0, 1, 2**40]], dtype=np.uint64)), ["faces[0][2]", "out of range"]),
}


@pytest.mark.parametrize("name", list(MESH_CASES))
def test_bad_meshes_are_refused_by_name(name):
    call, words = MESH_CASES[name]
    raises(call, *words)


RAY_QUERIES = ["intersect", "occluded", "all_hits", "count_hits"]

RAY_CASES = {
    "origins of 2 columns": (dict(origins=np.zeros((2, 2))), ["origins", "(n, 3)", "(2, 2)"]),
    "directions of 1 dimension": (dict(directions=np.ones(6)), ["directions", "(n, 3)", "(6,)"]),
    "lengths that differ": (dict(directions=np.ones((3, 3))), ["origins and directions", "same length, or one of them one row", "2 and 3"]),
    "a NaN origin": (dict(origins=np.array([[0, 0, 5], [np.nan, 0, 5]])), ["origins[1]", "not finite"]),
    "an infinite origin": (dict(origins=np.array([[0, 0, np.inf], [0, 0, 5]])), ["origins[0]", "not finite"]),
    "a NaN direction": (dict(directions=np.array([[0, 0, -1], [0, np.nan, -1]])), ["directions[1]", "not finite"]),
    "a zero direction": (dict(directions=np.array([[0, 0, -1], [0, 0, 0]])), ["directions[1]", "is zero"]),
    "complex origins": (dict(origins=O.astype(np.complex64)), ["origins", "dtype"]),
    "a negative t_max": (dict(t_max=-1.0), ["t_max", ">= 0", "-1"]),
    "a NaN t_max": (dict(t_max=float("nan")), ["t_max", ">= 0"]),
    "a negative t_max of one ray": (dict(t_max=np.array([1.0, -2.0])), ["t_max[1]", ">= 0"]),
    "t_max of another length": (dict(t_max=np.ones(3)), ["t_max", "3 values for 2 rays"]),
    "t_max of 2 dimensions": (dict(t_max=np.ones((2, 1))), ["t_max", "(n,)", "(2, 1)"]),
    "no threads": (dict(threads=0), ["threads", "got 0"]),
    "negative threads": (dict(threads=-2), ["threads", "got -2"]),
    "too many threads": (dict(threads=10**6), ["threads", "from 1 to 4096", "got 1000000"]),
    "threads past 64 bits": (dict(threads=10**30), ["threads", "got 1000000000000000000000000000000"]),
    "a negative t_min": (dict(t_min=-1.0), ["t_min", ">= 0", "-1"]),
    "an unknown bad_rays": (dict(bad_rays="skip"), ["bad_rays", '"raise" or "miss"', "skip"]),
}


@pytest.mark.parametrize("query", RAY_QUERIES)
@pytest.mark.parametrize("name", list(RAY_CASES))
def test_bad_rays_are_refused_by_name(query, name):
    change, words = RAY_CASES[name]
    args = {"origins": O, "directions": D}
    args.update({k: v for k, v in change.items() if k in ("origins", "directions")})
    options = {k: v for k, v in change.items() if k not in ("origins", "directions")}
    raises(lambda: getattr(MESH, query)(args["origins"], args["directions"], **options), *words)


# A value of the wrong type: a TypeError that names the argument and what
# it got (pyo3's own said "'float' object cannot be interpreted as an
# integer", "must be real number, not list", or took True for 1).
RAY_TYPE_CASES = {
    "threads of a float": (dict(threads=1.5), ["threads must be a whole number of threads", "got float 1.5"]),
    "threads of True": (dict(threads=True), ["threads", "got bool True"]),
    "threads of numpy's True": (dict(threads=np.True_), ["threads", "True"]),
    "threads of a str": (dict(threads="2"), ["threads", "got str '2'"]),
    "t_min of a list": (dict(t_min=[0, 0, 0, 0]), ["t_min must be a number", "got list [0, 0, 0, 0]"]),
    "t_min of an array": (dict(t_min=np.zeros(2)), ["t_min", "got ndarray of shape (2,)"]),
    "t_min of True": (dict(t_min=True), ["t_min", "got bool True"]),
    "t_min as text": (dict(t_min="0"), ["t_min", "got str '0'"]),
    "t_max of True": (dict(t_max=True), ["t_max", "got bool True"]),
    "t_max as text": (dict(t_max="far"), ["t_max", "number", "got str 'far'"]),
    "bad_rays of an int": (dict(bad_rays=1), ["bad_rays", "got int 1"]),
}


@pytest.mark.parametrize("query", RAY_QUERIES)
@pytest.mark.parametrize("name", list(RAY_TYPE_CASES))
def test_wrong_types_are_refused_by_name(query, name):
    options, words = RAY_TYPE_CASES[name]
    raises(lambda: getattr(MESH, query)(O, D, **options), *words, kind=TypeError)


POINT_TYPE_CASES = {
    "threads of a float": ("contains", dict(threads=2.0), ["threads", "got float 2.0"]),
    "signed as text": ("closest_point", dict(signed="yes"), ["signed must be True or False", "got str 'yes'"]),
    "signed of 1": ("closest_point", dict(signed=1), ["signed", "got int 1"]),
    "max_distance of True": ("closest_point", dict(max_distance=True), ["max_distance", "got bool True"]),
    "max_distance as text": ("closest_point", dict(max_distance="near"), ["max_distance", "got str 'near'"]),
}


@pytest.mark.parametrize("name", list(POINT_TYPE_CASES))
def test_wrong_point_query_types_are_refused_by_name(name):
    query, options, words = POINT_TYPE_CASES[name]
    raises(lambda: getattr(MESH, query)(O, **options), *words, kind=TypeError)


def test_numbers_and_flags_of_numpy_types_are_taken():
    want = MESH.intersect(O, D, threads=2, t_min=0.5, t_max=9.0)
    got = MESH.intersect(O, D, threads=np.int64(2), t_min=np.float32(0.5), t_max=np.float64(9))
    np.testing.assert_array_equal(got.t, want.t)
    assert np.isfinite(got.t).all()
    near = MESH.closest_point(O, signed=np.True_, max_distance=np.int32(10), threads=np.uint8(1))
    np.testing.assert_array_equal(near.distance, MESH.closest_point(O, signed=True).distance)
    raises(lambda: MESH.all_hits(O, D, uv="yes"), "uv must be True or False", kind=TypeError)
    assert MESH.all_hits(O, D, uv=np.True_).u is not None
    assert MESH.intersect(O, D, t_min=None, threads=None, bad_rays="miss").t.shape == (2,)


@pytest.mark.parametrize("query", RAY_QUERIES)
def test_a_bad_origin_is_quoted_as_given_far_from_the_origin(query):
    # The mesh is traced relative to its centre; the error quotes the row
    # the caller gave, not the row moved there.
    far = strata_rt.Mesh(V + [500_123.0, 5_000_456.0, 100.0], F)
    o = np.array([[500_123.0, 5_000_456.0, 110.0], [np.nan, 5_000_456.0, 110.0]])
    d = np.array([[0.0, 0.0, -1.0]] * 2)
    raises(lambda: getattr(far, query)(o, d), "origins[1]", "[NaN, 5000456.0, 110.0]")


@pytest.mark.parametrize("query", RAY_QUERIES)
def test_the_first_bad_ray_is_named_past_the_first_chunk(query):
    # Rays are read a chunk of 65,536 at a time as the walks go: the error
    # still names the first bad row of all, not the first of a later chunk,
    # and bad_rays="miss" makes exactly those rows misses.
    n = 140_000
    o = np.tile(O[:1], (n, 1))
    d = np.tile(D[:1], (n, 1))
    o[[70_001, 139_000], 2] = np.nan
    d[100_000] = 0.0
    raises(lambda: getattr(MESH, query)(o, d), "origins[70001]", "not finite")
    d[5] = np.nan
    raises(lambda: getattr(MESH, query)(o, d), "directions[5]", "not finite")
    kept = getattr(MESH, query)(o, d, bad_rays="miss")
    clean = getattr(MESH, query)(O[:1], D[:1])
    if query == "all_hits":
        counts = np.diff(kept.splits)
        bad = np.zeros(n, bool)
        bad[[5, 70_001, 100_000, 139_000]] = True
        assert (counts[bad] == 0).all() and (counts[~bad] == len(clean.t)).all()
    else:
        answer = kept.prim if query == "intersect" else np.asarray(kept)
        first = clean.prim if query == "intersect" else np.asarray(clean)
        missed = np.flatnonzero(answer != first[0])
        assert list(missed) == [5, 70_001, 100_000, 139_000]


POINT_CASES = {
    "points of 2 columns": (dict(points=np.zeros((3, 2))), ["points", "(n, 3)", "(3, 2)"]),
    "a NaN point": (dict(points=np.array([[0, 0, 0], [0, 0, np.nan]])), ["points[1]", "not finite"]),
    "no threads": (dict(points=O, threads=0), ["threads"]),
}


@pytest.mark.parametrize("query", ["contains", "closest_point"])
@pytest.mark.parametrize("name", list(POINT_CASES))
def test_bad_points_are_refused_by_name(query, name):
    kwargs, words = POINT_CASES[name]
    raises(lambda: getattr(MESH, query)(**kwargs), *words)


def test_a_negative_max_distance_is_refused():
    raises(lambda: MESH.closest_point(O, max_distance=-1.0), "max_distance", ">= 0")


def test_bad_files_give_strata_s_one_line_message(tmp_path):
    missing = tmp_path / "nothing.obj"
    message = raises(lambda: strata_rt.Mesh.load(missing), str(missing), kind=FileNotFoundError)
    assert "\n" not in message
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    message = raises(lambda: strata_rt.Mesh.load(bad), str(bad), kind=strata_rt.InputError)
    assert "\n" not in message
    assert issubclass(strata_rt.InputError, ValueError)
    odd = tmp_path / "mesh.xyz"
    odd.write_text("")
    raises(lambda: strata_rt.Mesh.load(odd), str(odd), kind=strata_rt.InputError)


@pytest.mark.parametrize(
    "name, unused, used",
    [
        ("m.obj", "v 0 0 0\nv nan nan nan\nv 1 0 0\nv 0 1 0\nf 1 3 4\n", "f 1 2 3\n"),
        ("m.off", "OFF\n4 1 0\n0 0 0\nnan nan nan\n1 0 0\n0 1 0\n3 0 2 3\n", None),
        (
            "m.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
            "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\nnan nan nan\n1 0 0\n0 1 0\n3 0 2 3\n",
            None,
        ),
    ],
)
def test_a_file_s_vertex_no_face_uses_may_be_nan(tmp_path, name, unused, used):
    """As from arrays and as trimesh reads it: a file's NaN vertex that no
    face uses loads (left out of ``vertices``); one a face uses raises
    strata's one-line message naming the file and the lines."""
    path = tmp_path / name
    path.write_text(unused)
    mesh = strata_rt.Mesh.load(path)
    np.testing.assert_array_equal(mesh.vertices[mesh.faces], [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    if used:
        path.write_text(unused + used)
        message = raises(lambda: strata_rt.Mesh.load(path), str(path), "line 6", "vertex on line 2", kind=strata_rt.InputError)
        assert "\n" not in message


@pytest.mark.parametrize("name, text", [("points.obj", "v 0 0 0\nv 1 0 0\n"), ("empty.stl", "solid s\nendsolid s\n")])
def test_a_file_read_leniently_warns_in_strata_s_words(tmp_path, name, text):
    """What strata's loaders read as other tools do but say a word about
    (here a file without faces) is a UserWarning naming the file, as the
    strata command prints it; the mesh loads."""
    path = tmp_path / name
    path.write_text(text)
    with pytest.warns(UserWarning, match="no faces|no triangles") as said:
        mesh = strata_rt.Mesh.load(path)
    assert len(mesh) == 0 and str(path) in str(said[0].message)


def test_a_file_s_looks_are_not_read(tmp_path):
    """Mesh.load reads a file's faces alone: an OBJ whose material library
    has a mistake and names a texture that is not there loads without a
    word (a render of it is an error naming the library's line)."""
    (tmp_path / "looks.mtl").write_text("newmtl a\nKd red\nmap_Kd gone.png\n")
    path = tmp_path / "quad.obj"
    path.write_text("mtllib looks.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl a\nf 1 2 3 4\nusemtl b\nf 1 3 4\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = strata_rt.Mesh.load(path)
    assert len(mesh) == 3
    hit = mesh.intersect([[0.25, 0.1, 1.0]], [[0, 0, -1]])
    assert hit.prim[0] in (0, 1) and hit.t[0] == 1.0


def test_a_path_is_a_str_a_path_like_or_bytes(tmp_path):
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    for path in (obj, str(obj), os.fsencode(obj)):
        assert len(strata_rt.Mesh.load(path)) == 1
    raises(lambda: strata_rt.Mesh.load(os.fsencode(tmp_path / "none.obj")), "none.obj", kind=FileNotFoundError)
    raises(lambda: strata_rt.Mesh.load(3), "path must be a path", "got int 3", kind=TypeError)
    raises(lambda: strata_rt.render(os.fsencode(tmp_path / "none.toml")), "none.toml", kind=FileNotFoundError)
    raises(lambda: strata_rt.render(3.5), "scene must be a path", "got float 3.5", kind=TypeError)


SCENE = helpers.REPO / "scenes" / "seed.toml"

RENDER_CASES = {
    "spp 0": (dict(spp=0), ["spp"]),
    "a negative width": (dict(width=-5), ["width", "-5"]),
    "a huge height": (dict(height=100_000), ["height", "larger than"]),
    "an unknown sampler": (dict(sampler="halton"), ["sampler", "halton"]),
    "an unknown schedule": (dict(schedule="later"), ["schedule", "later"]),
    "a short background": (dict(background=[1, 2]), ["background"]),
    "a negative background": (dict(background=[1, -2, 0]), ["background"]),
    "a crop outside": (dict(width=32, height=24, crop=(0, 0, 64, 8)), ["crop"]),
    "a crop of 3 numbers": (dict(crop=(0, 0, 4)), ["crop"]),
    "an unknown AOV": (dict(aovs=["albedo", "shadow"]), ["aovs", "shadow"]),
    "a set without =": (dict(set=["render.spp"]), ["set", "KEY=VALUE"]),
    "a set of an object": (dict(set={"camera.fov": object()}), ["camera.fov"]),
    "no threads": (dict(threads=0), ["threads"]),
    "a noise of 0": (dict(noise=0.0), ["noise", "above 0"]),
    "noise with passes": (dict(noise=0.05, passes=4), ["passes", "noise"]),
    "an unknown tone curve": (dict(tonemap="aces"), ["tonemap", "aces"]),
}


@pytest.mark.parametrize("name", list(RENDER_CASES))
def test_bad_render_settings_are_refused_by_name(name):
    settings, words = RENDER_CASES[name]
    raises(lambda: strata_rt.render(SCENE, **settings), *words)


RENDER_TYPE_CASES = {
    "a width of a float": (dict(width=16.5), ["width must be an int", "got float 16.5"]),
    "spp of True": (dict(spp=True), ["spp", "got bool True"]),
    "a seed as text": (dict(seed="7"), ["seed", "got str '7'"]),
    "threads of a float": (dict(threads=2.0), ["threads", "got float 2.0"]),
    "passes of a list": (dict(passes=[2]), ["passes", "got list [2]"]),
    "noise as text": (dict(noise="low"), ["noise must be a number", "got str 'low'"]),
    "exposure of True": (dict(exposure=True), ["exposure", "got bool True"]),
    "a sampler of an int": (dict(sampler=1), ["sampler", "got int 1"]),
    "a tone curve as bytes": (dict(tonemap=b"filmic"), ["tonemap", "got bytes b'filmic'"]),
}


@pytest.mark.parametrize("name", list(RENDER_TYPE_CASES))
def test_wrong_render_types_are_refused_by_name(name):
    settings, words = RENDER_TYPE_CASES[name]
    raises(lambda: strata_rt.render(SCENE, **settings), *words, kind=TypeError)


def test_a_bad_edit_is_blamed_on_the_set_argument_not_a_command_line():
    """strata says "<command line>: --set camera.foo: …" of a bad --set;
    from Python the edit came from render's set argument, and a camera the
    model lacks from its camera argument."""
    small = dict(width=8, height=8, spp=1)
    for edit in ({"camera.foo": 1}, ["camera.foo=1"]):
        message = raises(lambda: strata_rt.render(SCENE, set=edit, **small), kind=strata_rt.InputError)
        assert message.startswith('set["camera.foo"]: unknown key'), message
    message = raises(lambda: strata_rt.render(SCENE, set={"camera.fov": None, "camera.nope": None}, **small), kind=strata_rt.InputError)
    assert message.startswith('set["camera.nope"]'), message
    message = raises(lambda: strata_rt.render(SCENE, set={"render.spp": 0}, **small), kind=strata_rt.InputError)
    assert message.startswith('set["render.spp"] = 0: ') and "at least 1" in message, message
    box = helpers.REPO / "scenes" / "meshes" / "box.gltf"
    message = raises(lambda: strata_rt.render(box, camera=3, **small), "no camera 3", kind=strata_rt.InputError)
    assert message.startswith("camera: "), message


def test_bad_scenes_give_strata_s_one_line_message(tmp_path):
    raises(lambda: strata_rt.render(tmp_path / "none.toml"), "none.toml", kind=FileNotFoundError)
    message = raises(
        lambda: strata_rt.render(SCENE, width=8, height=8, set={"camera.nope": 1}),
        "camera.nope",
        kind=strata_rt.InputError,
    )
    assert "\n" not in message
    broken = tmp_path / "broken.toml"
    broken.write_text("[render]\nspp = -3\n")
    raises(lambda: strata_rt.render(broken), "broken.toml", "spp", kind=strata_rt.InputError)
    with pytest.raises(TypeError):
        strata_rt.render(SCENE, spps=4)  # a misspelt setting


def test_ctrl_c_stops_a_long_query(bumpy):
    """SIGINT, sent again and again while a query of 4M rays runs, stops
    it with KeyboardInterrupt; the mesh answers correctly afterwards."""
    mesh = strata_rt.Mesh(*bumpy)
    rng = np.random.default_rng(3)
    o, d = helpers.random_rays(rng, bumpy[0], 4_000_000)
    o, d = o.astype(np.float32), d.astype(np.float32)
    stop = threading.Event()

    def on_sigint(signum, frame):
        if not stop.is_set():
            stop.set()
            raise KeyboardInterrupt

    def send():
        while not stop.is_set():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.002)

    previous = signal.signal(signal.SIGINT, on_sigint)
    sender = threading.Thread(target=send)
    try:
        with pytest.raises(KeyboardInterrupt):
            sender.start()
            mesh.intersect(o, d)
    finally:
        stop.set()
        sender.join()
        signal.signal(signal.SIGINT, previous)
    small = mesh.intersect(o[:1000], d[:1000])
    np.testing.assert_array_equal(small.prim, mesh.intersect(o[:1000], d[:1000], threads=1).prim)


def test_the_source_folder_imported_by_mistake_says_so(tmp_path):
    # Python started inside python/ finds the source folder first, which
    # has no compiled module: the error says what happened and what to do.
    import shutil
    import subprocess
    import sys

    source = helpers.REPO / "python" / "strata_rt"
    shutil.copytree(source, tmp_path / "strata_rt", ignore=shutil.ignore_patterns("_native*.so", "*.pyd"))
    done = subprocess.run([sys.executable, "-c", "import strata_rt"], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert "source folder" in last and "pip install ./python" in last, last

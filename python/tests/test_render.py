"""render equals the CLI's EXR output bit for bit: the image, the AOVs,
--set edits and crops."""

import json
import os
import subprocess

import numpy as np
import pytest

import helpers
import strata_rt
from conftest import missing

OpenEXR = pytest.importorskip("OpenEXR", reason="OpenEXR (tools/requirements.txt) reads the CLI's EXR")


@pytest.fixture(scope="module")
def strata_bin():
    path = os.environ.get("STRATA_BIN", str(helpers.REPO / "target" / "release" / "strata"))
    if not os.path.exists(path):
        missing(f"the strata binary {path} (cargo build --release, or set STRATA_BIN)")
    return path


def cli_exr(strata_bin, tmp_path, scene, args):
    """The channels of `strata render SCENE ARGS -o out.exr`, by name."""
    out = tmp_path / "out.exr"
    subprocess.run([strata_bin, "render", str(scene), "-o", str(out), "--quiet", *args], check=True)
    with OpenEXR.File(str(out), separate_channels=True) as f:
        return {name: np.asarray(c.pixels) for name, c in f.channels().items()}


def same_bits(a, b):
    a, b = np.ascontiguousarray(a, dtype=np.float32), np.ascontiguousarray(b, dtype=np.float32)
    assert a.shape == b.shape
    np.testing.assert_array_equal(a.view(np.uint32), b.view(np.uint32))


CASES = [
    # (scene, CLI flags, render() settings)
    ("seed.toml", ["--width", "48", "--height", "36", "--spp", "4"], dict(width=48, height=36, spp=4)),
    (
        "mesh.toml",
        ["--width", "40", "--height", "30", "--spp", "2", "--seed", "7", "--sampler", "random",
         "--set", "camera.fov=30", "--set", "lights[0].intensity=[9,8,7]"],
        dict(width=40, height=30, spp=2, seed=7, sampler="random",
             set={"camera.fov": 30, "lights[0].intensity": [9, 8, 7]}),
    ),
    (
        "glossy.toml",
        ["--width", "40", "--height", "32", "--spp", "3", "--crop", "8,4,30,20", "--background", "0.1,0.2,0.3"],
        dict(width=40, height=32, spp=3, crop=(8, 4, 30, 20), background=[0.1, 0.2, 0.3]),
    ),
    # A model file as it comes: the scene `strata render MODEL` makes
    # around it (its own camera and lights, or the studio's), edited.
    ("meshes/box.gltf", ["--width", "32", "--height", "24", "--spp", "2"], dict(width=32, height=24, spp=2)),
    (
        "meshes/box.gltf",
        ["--width", "32", "--height", "24", "--spp", "2", "--camera", "auto"],
        dict(width=32, height=24, spp=2, camera="auto"),
    ),
    (
        "meshes/icosphere.obj",
        ["--width", "36", "--height", "30", "--spp", "3", "--set", "camera.fov=30"],
        dict(width=36, height=30, spp=3, set={"camera.fov": 30}),
    ),
]


@pytest.mark.parametrize("scene,flags,settings", CASES, ids=[" ".join([c[0], *c[1][6:]]) for c in CASES])
def test_render_equals_the_cli_exr_bit_for_bit(strata_bin, tmp_path, scene, flags, settings):
    path = helpers.REPO / "scenes" / scene
    exr = cli_exr(strata_bin, tmp_path, path, [*flags, "--aov", "albedo,normal,depth"])
    image, aovs = strata_rt.render(path, aovs=True, **settings)
    assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] == 3
    same_bits(image, np.stack([exr["R"], exr["G"], exr["B"]], axis=-1))
    same_bits(aovs["albedo"], np.stack([exr[f"albedo.{c}"] for c in "RGB"], axis=-1))
    same_bits(aovs["normal"], np.stack([exr[f"normal.{c}"] for c in "XYZ"], axis=-1))
    same_bits(aovs["depth"], exr["depth.Z"])
    assert image.max() > 0, "a black image proves little"
    # Threads, passes and packets change the time, never a pixel; the
    # set= strings of --set give the same image as the dict.
    again = strata_rt.render(str(path), threads=1, passes=2, packets="off", **settings)
    same_bits(again, image)


def test_set_strings_work_as_the_flag_does():
    path = helpers.REPO / "scenes" / "mesh.toml"
    a = strata_rt.render(path, width=16, height=12, set=["camera.fov=30", "render.spp=2"])
    b = strata_rt.render(path, width=16, height=12, set={"camera.fov": 30.0, "render.spp": 2})
    same_bits(a, b)
    c = strata_rt.render(path, width=16, height=12, spp=2)
    assert not np.array_equal(a, c), "the edit changed nothing"


def test_set_none_removes_a_key_as_an_empty_flag_value_does():
    # mesh.toml sets camera.fov = 35; removed, the default (40) frames wider.
    path = helpers.REPO / "scenes" / "mesh.toml"
    a = strata_rt.render(path, width=16, height=12, spp=1, set={"camera.fov": None})
    b = strata_rt.render(path, width=16, height=12, spp=1, set=["camera.fov="])
    same_bits(a, b)
    c = strata_rt.render(path, width=16, height=12, spp=1, set={"camera.fov": 40.0})
    same_bits(a, c)
    d = strata_rt.render(path, width=16, height=12, spp=1)
    assert not np.array_equal(a, d), "removing the key changed nothing"


def test_a_scene_as_text_or_dict_renders_as_its_file(monkeypatch):
    """TOML text and a dict of tables render as the same file does, bit
    for bit; their relative paths resolve against the working directory."""
    import tomllib

    settings = dict(width=40, height=30, spp=2)
    for name in ["seed.toml", "mesh.toml"]:
        path = helpers.REPO / "scenes" / name
        from_file = strata_rt.render(path, **settings)
        text = path.read_text()
        monkeypatch.chdir(path.parent)
        same_bits(strata_rt.render(text, **settings), from_file)
        same_bits(strata_rt.render(tomllib.loads(text), **settings), from_file)
        # Edits and overrides apply to a dict as to the file.
        same_bits(
            strata_rt.render(tomllib.loads(text), set={"camera.fov": 30}, **settings),
            strata_rt.render(path, set={"camera.fov": 30}, **settings),
        )


def test_a_bad_scene_as_text_or_dict_names_where():
    with pytest.raises(strata_rt.InputError, match=r"<scene>.*spp"):
        strata_rt.render({"render": {"spp": "many"}})
    with pytest.raises(strata_rt.InputError, match=r"<scene>.*line 2"):
        strata_rt.render("[render]\nwidth = = 3\n")
    with pytest.raises(ValueError, match=r"scene: table keys must be strings"):
        strata_rt.render({"render": {1: 2}})
    with pytest.raises(TypeError, match=r"scene must be a path, TOML text or a dict"):
        strata_rt.render(42)
    with pytest.raises(FileNotFoundError):
        strata_rt.render("no-such-scene.toml")


def test_camera_picks_a_model_files_camera_and_nothing_else(tmp_path):
    # The box with two cameras of its own (glTF nodes), front and above.
    gltf = json.loads((helpers.REPO / "scenes" / "meshes" / "box.gltf").read_text())
    gltf["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}] * 2
    gltf["nodes"] += [{"camera": 0, "translation": [0, 0.5, 4]},
                      {"camera": 1, "translation": [0, 5, 0], "rotation": [-0.7071068, 0, 0, 0.7071068]}]
    gltf["scenes"][0]["nodes"] += [2, 3]
    box = tmp_path / "box.gltf"
    box.write_text(json.dumps(gltf))
    small = dict(width=16, height=12, spp=1)
    first, second, auto = (strata_rt.render(box, camera=c, **small) for c in (0, 1, "auto"))
    np.testing.assert_array_equal(strata_rt.render(box, **small), first)
    assert not np.array_equal(first, second) and not np.array_equal(first, auto)
    with pytest.raises(ValueError, match="camera must be a camera number"):
        strata_rt.render(box, camera="side", **small)
    with pytest.raises(ValueError, match="camera must be a camera number"):
        strata_rt.render(box, camera=-1, **small)
    with pytest.raises(strata_rt.InputError, match="camera"):
        strata_rt.render(box, camera=7, **small)
    with pytest.raises(ValueError, match="camera applies to a model file"):
        strata_rt.render(helpers.REPO / "scenes" / "seed.toml", camera=0, **small)

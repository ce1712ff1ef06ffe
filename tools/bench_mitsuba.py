#!/usr/bin/env python3
"""strata against Mitsuba 3 on strata's own scenes.

    tools/.venv/bin/python tools/bench_mitsuba.py [SCENE.toml ...]
        [--strata target/release/strata] [--threads 1] [--runs 5]
        [--spp N] [--ref-spp 1024] [--same-within 1] [--below L]
        [--variant llvm_ad_rgb]

Without scenes: scenes/large/dragon-rect.toml, scenes/seed-mc.toml,
scenes/soft-shadow.toml, scenes/env-constant.toml and scenes/env-sky.toml.
Each strata scene is translated into a Mitsuba
scene dict: perspective camera (strata's fov is vertical: fov_axis "y"),
box pixel filter, two-sided diffuse BSDFs, a rect light as a `rectangle`
with a one-sided `area` emitter facing edge_u x edge_v, point and
directional lights, an environment light as a `constant` emitter or an
`envmap` (its lat-long layout is Mitsuba's; strata looks texels up
nearest, Mitsuba bilinearly, so Mitsuba gets the map repeated 8x along
each axis, on which its bilinear lookup is strata's nearest one but for a
sixteenth of a texel at each edge), a plane as a large rectangle, spheres, triangles (each a
one-face PLY under tools/.cache/), PLY/OBJ meshes
(flat-shaded, as strata shades meshes without normals; an ASCII PLY is given
to Mitsuba as a binary copy, which it loads several times faster, and strata
renders a copy of the scene file, beside it, that names the same binary
copy), a
metallic-roughness metal (metallic = 1) as a `principled` BSDF, and the `direct`
integrator (emitter_samples = strata's shadow_samples, bsdf_samples = 1) with the `independent`
sampler; a scene with `integrator = "path"` gets Mitsuba's `path` integrator
(max_depth = strata's + 2). strata's direct light has the same expectation (one light sample
per hit; no diffuse interreflection). A scene the translation cannot
express (specular or glossy materials, emission, textures, a background,
disk or sphere lights, CSG, cylinders, transforms, ...) is skipped with
the reason. A thin-lens camera is Mitsuba's `thinlens` (the same lens
radius and plane of focus, the lens sampled uniformly).

Per scene:
  1. A Mitsuba reference at --ref-spp (cached under tools/.cache/).
  2. The same-image check: strata (stratified) at --ref-spp against the
     reference: the mean of each of 3x3 image regions must agree within
     --same-within percent (1; regions darker than 1% of the brightest
     are compared against that floor). Otherwise the region means are
     printed and the scene is not compared. dragon-gold needs 2: the
     gold of its top-left region is about 1% darker in Mitsuba, whose
     rays start a fixed 1e-4 off their surface (a quarter of a dragon
     triangle's edge); strata offset as Mitsuba does agrees within 0.05%
     (docs/mitsuba.md, "dragon-gold's last percent"). The per-pixel RMSE
     between the two images is printed too: the noise of two --ref-spp
     renders where they agree pixel by pixel, more where blur, edges or
     highlights differ, which region means average away.
  3. Equal spp (the scene's spp, or --spp): Mitsuba (independent sampler)
     and strata (--sampler random) alternate --runs times on --threads
     threads. Mitsuba renders once first (its JIT compiles the kernel;
     later renders hit the kernel cache), so its timed renders exclude
     compilation, as strata's render phase excludes its load and BVH
     build. Medians; RMSE of each against the reference (mean over runs).
     With --below L, also the RMSE over the pixels whose reference
     (mean of R, G, B) is under L: an image's RMSE is mostly that of its
     few pixels that see a light (on cornell-planes, the light's edges:
     84% of the squared error at 32 spp), and --below 1 shows the noise
     on the surfaces the light falls on.
  4. Equal RMSE: the fewest spp at which strata (stratified; its RMSE
     the mean over three seeds) is at most Mitsuba's RMSE, found by
     doubling from 1 spp and then bisecting; the whole strata process
     (wall, including its start, load, BVH build and EXR, but not
     --stats, which a render needs no more than Mitsuba's does) against
     Mitsuba's load_dict (median of --runs loads) + warm render (median
     of --runs renders at its spp, which write no file, each timed beside
     one of strata's runs: the machine's speed drifts between steps).
     The render phase printed beside it is from one more strata run,
     with --stats, not timed.
  5. Equal RMSE with strata's noise target (--noise E, ceiling
     --noise-spp): the largest E whose RMSE (mean over three seeds) is at
     most Mitsuba's, found by halving or doubling E from 0.5 and then
     bisecting between the last two in log space (four steps); timed as
     in 4, Mitsuba's renders again beside strata's runs (every pixel
     takes 4 samples before the first decision). Mitsuba
     has no noise target of its own, so this compares strata at its best
     with Mitsuba's uniform sampling (--noise-spp 0 skips it).
  Steps 4 and 5 also print the 3x3 region means of their three seeds'
  mean image against the reference: RMSE counts a systematic offset only
  beside the noise, and the noise target's images of path-traced scenes
  came out 1 to 3% darker than the reference where uniform ones did not
  (docs/mitsuba.md), so a lower ratio there is not the same image.

Run on a quiet machine: these are wall-clock figures.
"""

import argparse
import hashlib
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_SCENES = ["scenes/large/dragon-rect.toml", "scenes/seed-mc.toml", "scenes/soft-shadow.toml",
                  "scenes/env-constant.toml", "scenes/env-sky.toml"]
# How many times each texel of an environment map is repeated along each
# axis for Mitsuba: its bilinear lookup on the repeated map is strata's
# nearest lookup on the original but within 1/16 texel of each edge.
ENVMAP_REPEAT = 8
# Dr.Jit's LLVM backend, first found: $DRJIT_LIBLLVM_PATH, the LLVM 22 the
# Rust toolchain ships (LLVM 19 aborts in instruction selection on AVX-512
# machines; 14 and 15 fail to load or compile kernels), Debian's LLVM 19.
LLVM_CANDIDATES = ["~/.rustup/toolchains/stable-*/lib/libLLVM.so.*",
                   "~/.rustup/toolchains/*/lib/libLLVM.so.*",
                   "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"]
# Seeds whose mean RMSE decides whether strata has reached Mitsuba's error.
RMSE_SEEDS = 3


class Unsupported(Exception):
    pass


def v3(x):
    return [float(c) for c in x]


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    n = math.sqrt(sum(c * c for c in a))
    return [c / n for c in a]


def frame_matrix(x, y, z, o):
    """4x4 row-major matrix with columns x, y, z, o."""
    return [[x[i], y[i], z[i], o[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]


def translate(path, mi):
    """strata scene file -> (Mitsuba dict, render settings). Raises Unsupported.
    settings["inputs"] lists the files the dict holds as data, not names
    (environment maps), for the reference's cache key."""
    import numpy as np

    with open(path, "rb") as f:
        doc = tomllib.load(f)
    base = os.path.dirname(os.path.abspath(path))
    problems = []  # everything the translation cannot express, reported together
    r = doc.get("render", {})
    for key in r:
        if key not in ("width", "height", "spp", "shadow_samples", "seed", "sampler",
                       "light_sampling", "max_depth", "reflection_samples", "background",
                       "glossy_sampling", "integrator"):
            problems.append(f"render.{key}")
    if any(c != 0 for c in r.get("background", [0, 0, 0])):
        problems.append("a background radiance (Mitsuba's constant emitter would also light the scene)")
    settings = {"width": r.get("width", 640), "height": r.get("height", 480), "spp": r.get("spp", 1),
                "inputs": [], "binary_copies": {}}

    cam = doc.get("camera", {})
    kind = cam.get("type", "perspective")
    if kind not in ("perspective", "thin_lens"):
        problems.append(f"a {kind} camera")
    for key in cam:
        if key not in ("type", "position", "look_at", "up", "fov") + (
                ("aperture", "focus_distance") if kind == "thin_lens" else ()):
            problems.append(f"camera.{key}")
    position = v3(cam.get("position", [0, 1, 6]))
    look_at = v3(cam.get("look_at", [0, 0.5, 0]))
    # strata's thin lens is Mitsuba's `thinlens`: a lens of radius
    # `aperture` sampled uniformly over its disc, focused on the plane
    # `focus_distance` along the view axis (default: the distance to
    # look_at); with no aperture it is the pinhole.
    lens = {}
    if kind == "thin_lens" and float(cam.get("aperture", 0.0)) > 0.0:
        focus = cam.get("focus_distance", math.dist(position, look_at))
        lens = {"type": "thinlens", "aperture_radius": float(cam["aperture"]),
                "focus_distance": float(focus)}
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        # strata's shadow_samples light samples per hit, and one BSDF sample.
        "integrator": {"type": "direct", "emitter_samples": int(r.get("shadow_samples", 1)),
                       "bsdf_samples": 1}
        if r.get("integrator", "distribution") != "path" else
        # strata's max_depth D bounds the bounces (light reflects at most
        # D + 1 times); Mitsuba's counts path segments from the camera, so
        # D + 2. Both end paths by Russian roulette (unbiased).
        {"type": "path", "max_depth": int(r.get("max_depth", 5)) + 2},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam.get("fov", 40.0)),
            "to_world": T().look_at(origin=position, target=look_at,
                                    up=v3(cam.get("up", [0, 1, 0]))),
            **lens,
            "film": {"type": "hdrfilm", "width": settings["width"], "height": settings["height"],
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": settings["spp"]},
        },
    }

    bsdfs = {}
    for name, m in doc.get("materials", {}).items():
        if "base_color" in m or "metallic" in m or "roughness" in m:
            # glTF's metallic-roughness material. For a metal (metallic 1)
            # Mitsuba's principled BSDF is the same model: GGX sampled by
            # visible normals with Schlick's Fresnel from base_color, and no
            # diffuse lobe (its weight is 1 - metallic). It differs in
            # Smith's masking (separable; strata's is height-correlated),
            # which moved dragon-gold's regions by under 0.1%. Dielectric
            # ones differ (Disney's diffuse against Lambert's): not
            # translated.
            extra = [key for key in m if key not in ("base_color", "metallic", "roughness")]
            if float(m.get("metallic", 0.0)) != 1.0 or extra:
                problems.append(f"material {name!r}: metallic-roughness other than a metal "
                                f"(metallic = 1, no other keys)")
                continue
            bsdfs[name] = {"type": "twosided", "material": {
                "type": "principled", "metallic": 1.0,
                "base_color": {"type": "rgb", "value": v3(m.get("base_color", [0.8] * 3))},
                "roughness": float(m.get("roughness", 0.5))}}
            continue
        # ior and fresnel are inactive without a glass layer; zeros are defaults.
        extra = [key for key, value in m.items() if key not in ("diffuse", "ior", "fresnel")
                 and not ((isinstance(value, list) and not any(value)) or value == 0)]
        if extra:
            problems.append(f"material {name!r}: {', '.join(extra)} (beyond a diffuse BSDF)")
        bsdfs[name] = {"type": "twosided", "material": {
            "type": "diffuse", "reflectance": {"type": "rgb", "value": v3(m.get("diffuse", [0.8] * 3))}}}

    for i, light in enumerate(doc.get("lights", [])):
        kind = light.get("type")
        if kind == "point":
            scene[f"light{i}"] = {"type": "point", "position": v3(light["position"]),
                                  "intensity": {"type": "rgb", "value": v3(light["intensity"])}}
        elif kind == "directional":
            scene[f"light{i}"] = {"type": "directional", "direction": v3(light["direction"]),
                                  "irradiance": {"type": "rgb", "value": v3(light["irradiance"])}}
        elif kind == "rect":
            c, eu, ev = v3(light["corner"]), v3(light["edge_u"]), v3(light["edge_v"])
            n = norm(cross(eu, ev))  # strata's rect emits towards edge_u x edge_v
            center = [c[k] + 0.5 * (eu[k] + ev[k]) for k in range(3)]
            # Mitsuba's rectangle is [-1, 1]^2 at z = 0, emitting towards +z.
            half_u = [0.5 * x for x in eu]
            half_v = [0.5 * x for x in ev]
            scene[f"light{i}"] = {
                "type": "rectangle",
                "to_world": T(frame_matrix(half_u, half_v, n, center)),
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": v3(light["radiance"])}},
                # Its back: black, as strata's rect light shows nothing from behind.
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
            }
        elif kind == "environment":
            scale = light.get("scale", 1.0)
            scale = v3([scale] * 3 if isinstance(scale, (int, float)) else scale)
            rotate = light.get("rotate")
            to_world = T().rotate(v3(rotate[:3]), float(rotate[3])) if rotate else T()
            if "map" in light:
                file = os.path.normpath(os.path.join(base, light["map"]))
                settings["inputs"].append(file)
                texels = np.array(mi.Bitmap(file), copy=True)[:, :, :3].astype(np.float32)
                texels *= np.array(scale, dtype=np.float32)
                texels = np.repeat(np.repeat(texels, ENVMAP_REPEAT, 0), ENVMAP_REPEAT, 1)
                scene[f"light{i}"] = {"type": "envmap", "bitmap": mi.Bitmap(texels), "to_world": to_world}
            else:
                radiance = light["radiance"]
                radiance = v3([radiance] * 3 if isinstance(radiance, (int, float)) else radiance)
                scene[f"light{i}"] = {"type": "constant", "radiance": {
                    "type": "rgb", "value": [radiance[k] * scale[k] for k in range(3)]}}
        else:
            problems.append(f"a {kind} light")

    for i, obj in enumerate(doc.get("objects", [])):
        for key in obj:
            if key not in ("sphere", "plane", "triangle", "mesh", "material", "name", "instances"):
                problems.append(f"objects[{i}].{key}")
        mat = obj.get("material")
        if mat not in bsdfs:
            problems.append(f"objects[{i}] without a named material")
            continue
        bsdf = bsdfs[mat]
        if "sphere" in obj:
            s = obj["sphere"]
            scene[f"obj{i}"] = {"type": "sphere", "center": v3(s.get("center", [0, 0, 0])),
                                "radius": float(s["radius"]), "bsdf": bsdf}
        elif "plane" in obj:
            p = obj["plane"]
            n = norm(v3(p["normal"]))
            a = [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]
            u = norm(cross(a, n))
            v = cross(n, u)
            size = 1000.0  # half-width: a plane, as far as any of these views reach
            scene[f"obj{i}"] = {
                "type": "rectangle",
                "to_world": T(frame_matrix([size * x for x in u], [size * x for x in v], n,
                                           v3(p.get("point", [0, 0, 0])))),
                "bsdf": bsdf,
            }
        elif "triangle" in obj:
            scene[f"obj{i}"] = {"type": "ply", "filename": triangle_ply([v3(v) for v in obj["triangle"]["v"]]),
                                "face_normals": True, "bsdf": bsdf}
        elif "mesh" in obj:
            mesh = os.path.normpath(os.path.join(base, obj["mesh"]))
            ext = os.path.splitext(mesh)[1].lower()
            if ext not in (".ply", ".obj"):
                problems.append(f"mesh {mesh}")
            if ext == ".ply":
                copy = binary_ply(mi, mesh)
                if copy != mesh:
                    settings["binary_copies"][obj["mesh"]] = copy
                mesh = copy
            shape = {"type": ext[1:], "filename": mesh, "face_normals": True, "bsdf": bsdf}
            if "instances" in obj:
                # One shapegroup holding the mesh, one instance per line of
                # the instances file (row-major 3x4 object-to-world).
                scene[f"group{i}"] = {"type": "shapegroup", "mesh": shape}
                with open(os.path.join(base, obj["instances"])) as f:
                    rows = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
                for k, line in enumerate(rows):
                    m = [float(x) for x in line.replace(",", " ").split()]
                    matrix = [m[0:4], m[4:8], m[8:12], [0.0, 0.0, 0.0, 1.0]]
                    scene[f"obj{i}-{k}"] = {"type": "instance", "shapegroup": {"type": "ref", "id": f"group{i}"},
                                            "to_world": T(matrix)}
            else:
                scene[f"obj{i}"] = shape
        elif "instances" in obj:
            problems.append(f"objects[{i}].instances on a shape other than a mesh")
        else:
            problems.append(f"objects[{i}] has no sphere, plane, triangle or mesh")
    if problems:
        raise Unsupported("; ".join(problems))
    return scene, settings


def triangle_ply(corners):
    """A PLY of the one triangle `corners` (under tools/.cache/, named by
    its coordinates), for Mitsuba, which has no triangle shape of its own.
    The coordinates are written as float32 bits, as strata reads them."""
    import struct

    data = b"".join(struct.pack("<3f", *c) for c in corners)
    out = os.path.join(HERE, ".cache", f"triangle-{hashlib.sha256(data).hexdigest()[:16]}.ply")
    if not os.path.exists(out):
        os.makedirs(os.path.dirname(out), exist_ok=True)
        header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                  b"property float x\nproperty float y\nproperty float z\n"
                  b"element face 1\nproperty list uchar int vertex_indices\nend_header\n")
        with open(out + ".tmp", "wb") as f:
            f.write(header + data + struct.pack("<B3i", 3, 0, 1, 2))
        os.replace(out + ".tmp", out)
    return out


def binary_ply(mi, path):
    """`path`, or where it is ASCII a binary copy (under tools/.cache/),
    which Mitsuba reads several times faster: its load at its best."""
    with open(path, "rb") as f:
        if b"format ascii" not in f.read(512):
            return path
    out = os.path.join(HERE, ".cache", f"{os.path.splitext(os.path.basename(path))[0]}-"
                                       f"{os.path.getsize(path)}-binary.ply")
    if not os.path.exists(out):
        os.makedirs(os.path.dirname(out), exist_ok=True)
        mesh = mi.load_dict({"type": "ply", "filename": path, "face_normals": True})
        mesh.write_ply(out + ".tmp")
        os.replace(out + ".tmp", out)
    return out


THREADS = 1

# The scene strata renders for each scene file: the file itself, or a copy
# beside it that names the binary copies Mitsuba reads (`same_meshes`).
STRATA_SCENES = {}


def same_meshes(path, copies):
    """A copy of scene `path` beside it (so its other relative paths still
    hold) whose meshes are `copies`' binary PLYs: strata reads the same
    files Mitsuba does, not the slower ASCII originals."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for original, copy in copies.items():
        for quote in ('"', "'"):
            text = text.replace(f"{quote}{original}{quote}", json.dumps(os.path.abspath(copy)))
    left = [o.get("mesh") for o in tomllib.loads(text).get("objects", []) if o.get("mesh") in copies]
    if left:
        print(f"bench_mitsuba.py: {path}: cannot point strata at the binary copies of "
              f"{', '.join(left)} (write the mesh path as a plain quoted string)", file=sys.stderr)
        sys.exit(2)
    base, name = os.path.split(os.path.abspath(path))
    out = os.path.join(base, f".{os.path.splitext(name)[0]}-bench-binary.toml")
    with open(out, "w", encoding="utf-8") as f:
        f.write(text)
    return out


def read_exr(mi, np, path):
    import drjit as dr

    # Mitsuba 3.9.1's EXR reader deadlocks on a one-thread pool: read on two.
    dr.set_thread_count(max(2, THREADS))
    img = np.array(mi.Bitmap(path), copy=True)[:, :, :3].astype(np.float64)
    dr.set_thread_count(THREADS)
    return img


def rmse(np, a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def over_seeds(mi, np, ref, out, render):
    """`render(seed)` (writing `out`) for RMSE_SEEDS seeds: the mean of
    their RMSEs against `ref`, and their mean image (for `bias`)."""
    imgs = []
    for seed in range(RMSE_SEEDS):
        render(seed)
        imgs.append(read_exr(mi, np, out))
    return statistics.mean(rmse(np, img, ref) for img in imgs), sum(imgs) / len(imgs)


def bias(np, mean_img, ref):
    """How far the mean of a few seeds' images sits from the reference,
    region by region (3x3, as the same-image check): RMSE counts a
    systematic offset only beside the noise, so an estimator biased by a
    few percent (a noise target's pixels that stop before they meet a rare
    bright path, docs/mitsuba.md) can still reach Mitsuba's RMSE."""
    devs = region_deviations(np, mean_img, ref)[2]
    return (f"its {RMSE_SEEDS} seeds' mean image, 3x3 region means against the reference: "
            + " ".join(f"{100 * d:+.1f}%" for d in devs))


def region_deviations(np, img, ref):
    """The 3x3 region means of `ref` and of `img`, and each region's
    relative deviation, against the larger of the reference's mean and a
    floor of 1% of its brightest region (so that a dark region's noise
    does not count as a difference)."""
    ms, ss = region_means(np, ref), region_means(np, img)
    floor = 0.01 * max(ms)
    return ms, ss, [(s - m) / max(m, floor) for m, s in zip(ms, ss)]


def region_means(np, img, k=3):
    h, w = img.shape[:2]
    return [float(img[h * i // k:h * (i + 1) // k, w * j // k:w * (j + 1) // k].mean())
            for i in range(k) for j in range(k)]


def quiet(limit=0.5):
    """Waits, at most `limit` seconds, until this process's threads have
    stopped using the CPU, so that the next timed run (strata's or
    Mitsuba's) starts on idle cores: Dr.Jit's workers spin for about
    11 ms after each render (this process used 22 ms of CPU in the 20 ms
    after a warm cornell-planes render on two threads, and 23 ms in the
    200 ms after it), and a strata process started at once took 28.5 ms
    against 25.3 ms started 200 ms later (docs/mitsuba.md)."""
    end = time.perf_counter() + limit
    while time.perf_counter() < end:
        cpu = time.process_time()
        time.sleep(0.005)
        if time.process_time() - cpu < 0.0005:
            return


def run_strata(args, scene, spp, sampler, out, seed=0, noise=None, stats=False):
    """strata's wall time, and with `stats` its render phase (from
    `--stats`, written to OUT.json), else None: a run timed as a whole
    process writes its image alone, as a user's render does (the stats
    file's fsync and the memory figures' reads cost a 1-pixel render
    1.5 ms)."""
    cmd = [args.strata, "render", STRATA_SCENES.get(scene, scene), "-q", "--threads", str(args.threads), "--spp", str(spp),
           "--seed", str(seed), "-o", out]
    if stats:
        cmd += ["--stats", out + ".json"]
    # The noise target samples as it must (its own sampler); else the one asked.
    cmd += ["--noise", str(noise)] if noise is not None else ["--sampler", sampler]
    quiet()
    t = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT)
    wall = time.perf_counter() - t
    if not stats:
        return wall, None
    with open(out + ".json") as f:
        return wall, json.load(f)["time"]["render_s"]


def bench_scene(args, mi, dr, np, path, tmp):
    name = os.path.splitext(os.path.basename(path))[0]
    try:
        desc, settings = translate(path, mi)
    except Unsupported as e:
        print(f"{name}: skipped: the Mitsuba translation cannot express {e}")
        return None
    spp = args.spp or settings["spp"]
    if settings["binary_copies"]:
        STRATA_SCENES[path] = same_meshes(path, settings["binary_copies"])

    def load():
        quiet()
        t = time.perf_counter()
        loaded = mi.load_dict(desc)
        return loaded, time.perf_counter() - t

    scene, load_s = load()

    cpu = []  # Mitsuba's CPU seconds per wall second while rendering: its thread use

    def mitsuba(n, seed):
        quiet()
        t, c = time.perf_counter(), time.process_time()
        img = np.array(mi.render(scene, spp=n, seed=seed), copy=True).astype(np.float64)
        t = time.perf_counter() - t
        cpu.append((time.process_time() - c) / t)
        return img, t

    # 1. The reference, cached by the scene file, its meshes' sizes and the spp.
    inputs = b"".join(open(f, "rb").read() for f in settings["inputs"])
    key = hashlib.sha256(open(path, "rb").read() + inputs + json.dumps(
        [args.ref_spp, mi.__version__, ENVMAP_REPEAT, sorted(str(v.get("filename", "")) + str(
            os.path.getsize(v["filename"]) if "filename" in v else "") for v in desc.values()
            if isinstance(v, dict))]).encode()).hexdigest()[:16]
    cache = os.path.join(HERE, ".cache", f"mitsuba-{name}-{args.ref_spp}spp-{key}.npy")
    if os.path.exists(cache):
        ref = np.load(cache)
    else:
        # In passes of at most 256 spp (memory), with distinct seeds.
        passes = max(1, args.ref_spp // 256)
        ref = sum(mitsuba(args.ref_spp // passes, 1000 + k)[0] for k in range(passes)) / passes
        os.makedirs(os.path.dirname(cache), exist_ok=True)
        np.save(cache, ref)

    # 2. Same image?
    check = os.path.join(tmp, f"{name}-check.exr")
    run_strata(args, path, args.ref_spp, "stratified", check)
    mine = read_exr(mi, np, check)
    ms, ss, devs = region_deviations(np, mine, ref)
    bad = [i for i, d in enumerate(devs) if abs(d) > args.same_within / 100]
    if mine.shape != ref.shape or bad:
        print(f"{name}: NOT COMPARED: the renderers disagree at {args.ref_spp} spp "
              f"(3x3 region means, row-major; regions {bad} differ by more than {args.same_within:g}%):")
        print("  mitsuba " + " ".join(f"{m:.5f}" for m in ms))
        print("  strata  " + " ".join(f"{s:.5f}" for s in ss))
        return None
    worst = max(abs(d) for d in devs)
    # Per pixel too: blur, edges and highlights that region means average
    # away (a lens of twice the radius, a plane of focus 8% nearer).
    print(f"{name}: same image: 3x3 region means agree within {100 * worst:.2f}% at {args.ref_spp} spp; "
          f"per-pixel RMSE {rmse(np, mine, ref):.5f} between the two {args.ref_spp}-spp images")

    # 3. Equal spp, alternating; Mitsuba warmed up (JIT) first.
    first_t = mitsuba(spp, 1)[1]
    m_times, m_err, s_render, s_wall, s_err = [], [], [], [], []
    dim = ref.mean(axis=2) < args.below if args.below else None
    if dim is not None and not dim.any():
        print(f"  --below {args.below:g}: no pixel of the reference is under it")
        dim = None
    m_dim, s_dim = [], []
    for k in range(args.runs):
        img, t = mitsuba(spp, 2 + k)
        m_times.append(t)
        m_err.append(rmse(np, img, ref))
        out = os.path.join(tmp, f"{name}-rnd.exr")
        wall, render_s = run_strata(args, path, spp, "random", out, seed=k, stats=True)
        s_render.append(render_s)
        s_wall.append(wall)
        mine = read_exr(mi, np, out)
        s_err.append(rmse(np, mine, ref))
        if dim is not None:
            m_dim.append(rmse(np, img[dim], ref[dim]))
            s_dim.append(rmse(np, mine[dim], ref[dim]))
    med = statistics.median
    m_rmse, s_rmse = statistics.mean(m_err), statistics.mean(s_err)
    print(f"  equal spp ({spp}, random / independent sampler, {args.threads} thread(s), "
          f"median of {args.runs}):")
    print(f"    mitsuba render {med(m_times):.3f} s (first render, with JIT compile: {first_t:.3f} s; "
          f"load_dict {load_s:.3f} s)  RMSE {m_rmse:.5f}")
    print(f"    strata  render {med(s_render):.3f} s (whole process {med(s_wall):.3f} s)  "
          f"RMSE {s_rmse:.5f}")
    print(f"    strata / mitsuba render time {med(s_render) / med(m_times):.2f} "
          f"(mitsuba used {med(cpu[-args.runs:]):.2f} CPU s per wall s)")
    if dim is not None:
        m_d, s_d = statistics.mean(m_dim), statistics.mean(s_dim)
        # Efficiency: 1 / (time x MSE); strata's over Mitsuba's.
        gain = (med(m_times) * m_d ** 2) / (med(s_render) * s_d ** 2)
        print(f"    pixels under {args.below:g} in the reference ({int(dim.sum())} of {dim.size}): RMSE mitsuba "
              f"{m_d:.5f}, strata {s_d:.5f}; strata's efficiency (1 / (render time x MSE)) "
              f"{gain:.2f}x mitsuba's")

    # 4. Equal RMSE: the fewest spp at which strata (stratified) has at most
    # Mitsuba's RMSE, both averaged over runs with different seeds: doubling
    # from 1 spp, then bisecting between the last two counts (strata takes
    # any sample count, and a power of two can overshoot by nearly 2x).
    seed_means = {}

    def strata_rmse(n):
        out = os.path.join(tmp, f"{name}-strat.exr")
        err, seed_means[n] = over_seeds(mi, np, ref, out, lambda seed: run_strata(
            args, path, n, "stratified", out, seed=seed))
        return err

    lo, n, found = 0, 1, None
    while n <= 4 * args.ref_spp:
        e = strata_rmse(n)
        if e <= m_rmse:
            found = (n, e)
            break
        lo, n = n, n * 2
    if found is None:
        print(f"  equal RMSE: strata did not reach Mitsuba's RMSE {m_rmse:.5f} by {n // 2} spp")
        return None
    hi = found[0]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        e = strata_rmse(mid)
        if e <= m_rmse:
            hi, found = mid, (mid, e)
        else:
            lo = mid
    n, e = found
    # Mitsuba's load, timed like strata's whole process: the median of
    # --runs loads (the first, above, included), so that one slow load on
    # this shared machine does not stand for Mitsuba. Each repeat load, and
    # a warm render of Mitsuba's at its spp, alternates with one strata
    # run, so both see the same machine (its speed drifted by a third
    # between step 3 and this one).
    loads = [load_s]
    walls, m_times = [], []
    strat = os.path.join(tmp, f"{name}-strat.exr")
    for k in range(args.runs):
        if k > 0:
            loads.append(load()[1])
        m_times.append(mitsuba(spp, 100 + k)[1])
        walls.append(run_strata(args, path, n, "stratified", strat)[0])
    # The render phase, for the record, from one more run (not timed).
    render_s = run_strata(args, path, n, "stratified", strat, stats=True)[1]
    load_med = med(loads)
    mitsuba_total = load_med + med(m_times)
    print(f"  equal RMSE: strata stratified at {n} spp: RMSE {e:.5f} <= mitsuba's {m_rmse:.5f} at {spp} spp "
          f"(means over {RMSE_SEEDS} seeds and {args.runs} runs); {bias(np, seed_means[n], ref)}")
    print(f"    strata whole process {med(walls):.3f} s (render {render_s:.3f} s) vs mitsuba "
          f"load_dict {load_med:.3f} s (median of {len(loads)}: {min(loads):.3f} to {max(loads):.3f} s) "
          f"+ warm render {med(m_times):.3f} s = {mitsuba_total:.3f} s: ratio {med(walls) / mitsuba_total:.2f}")
    if args.noise_spp > 0:
        noise_target(args, mi, np, path, name, tmp, ref, m_rmse, loads, (mitsuba, spp))
    return True


def noise_target(args, mi, np, path, name, tmp, ref, m_rmse, loads, m_render):
    """Step 5: the largest noise target whose RMSE is at most Mitsuba's;
    `m_render` is Mitsuba's warm render and its spp, timed again beside
    strata's runs."""
    mitsuba, m_spp = m_render
    med = statistics.median
    out = os.path.join(tmp, f"{name}-noise.exr")

    seed_means = {}

    def noise_rmse(e):
        err, seed_means[e] = over_seeds(mi, np, ref, out, lambda seed: run_strata(
            args, path, args.noise_spp, None, out, seed=seed, noise=f"{e:.5g}"))
        return err

    # Bracket: lo meets Mitsuba's RMSE, hi (larger) does not.
    lo, hi, found = None, None, None
    e = 0.5
    while 1e-3 < e < 64:
        err = noise_rmse(e)
        if err <= m_rmse:
            lo, found = e, (e, err)
            if hi is not None:
                break
            e *= 2
        else:
            hi = e
            if lo is not None:
                break
            e /= 2
    if found is None:
        print(f"  noise target: no E between 1e-3 and 64 reached Mitsuba's RMSE {m_rmse:.5f}")
        return
    if hi is not None:
        for _ in range(4):
            mid = math.sqrt(lo * hi)
            err = noise_rmse(mid)
            if err <= m_rmse:
                lo, found = mid, (mid, err)
            else:
                hi = mid
    e, err = found
    walls = []
    # Mitsuba's warm render timed again, alternating with strata's runs.
    m_times = []
    for k in range(args.runs):
        m_times.append(mitsuba(m_spp, 200 + k)[1])
        walls.append(run_strata(args, path, args.noise_spp, None, out, noise=f"{e:.5g}")[0])
    # The render phase and the samples taken, from one more run (not timed).
    render_s = run_strata(args, path, args.noise_spp, None, out, noise=f"{e:.5g}", stats=True)[1]
    with open(out + ".json") as f:
        spp = json.load(f).get("mean_spp", float("nan"))
    mitsuba_total = med(loads) + med(m_times)
    print(f"  equal RMSE, noise target: strata --noise {e:.4g} (ceiling {args.noise_spp} spp, "
          f"{spp:.1f} spp on average): RMSE {err:.5f} <= mitsuba's {m_rmse:.5f}; "
          f"{bias(np, seed_means[e], ref)}")
    print(f"    strata whole process {med(walls):.3f} s (render {render_s:.3f} s) vs mitsuba "
          f"load_dict {med(loads):.3f} s + warm render {med(m_times):.3f} s = {mitsuba_total:.3f} s: "
          f"ratio {med(walls) / mitsuba_total:.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", default=DEFAULT_SCENES)
    ap.add_argument("--strata", default=os.path.join(ROOT, "target", "release", "strata"))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--spp", type=int, default=0, help="equal-spp sample count (default: the scene's)")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--same-within", type=float, default=1.0,
                    help="step 2's tolerance for the 3x3 region means, in percent")
    ap.add_argument("--below", type=float, default=0.0,
                    help="also report step 3's RMSE over pixels whose reference is under this level")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--noise-spp", type=int, default=4096,
                    help="step 5's sample ceiling for strata's noise target (0: skip step 5)")
    args = ap.parse_args()
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        import glob
        found = [f for pattern in LLVM_CANDIDATES for f in sorted(glob.glob(os.path.expanduser(pattern)))]
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = found[0]
    import numpy as np
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    global THREADS
    THREADS = args.threads
    dr.set_thread_count(args.threads)
    print(f"mitsuba {mi.__version__} ({args.variant}, LLVM {os.environ.get('DRJIT_LIBLLVM_PATH', 'none')}), strata {args.strata}, {args.threads} thread(s), "
          f"{args.runs} runs, reference {args.ref_spp} spp")
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for path in args.scenes:
                bench_scene(args, mi, dr, np, path, tmp)
    finally:
        for copy in STRATA_SCENES.values():
            os.remove(copy)


if __name__ == "__main__":
    sys.exit(main())

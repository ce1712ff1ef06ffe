#!/usr/bin/env python3
"""Mitsuba 3's first image of scenes/large/dragon-sub2.toml, for issue 49's
comparison in docs/performance.md: load_dict (it reads the PLY and builds
its BVH) and one 1-spp 320x240 render with the direct integrator, on 2
threads, timed from load_dict to the evaluated image (Python's start and
Mitsuba's import not counted).

    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install -r tools/requirements-mitsuba.txt
    /tmp/mi/bin/python tools/first_image_mitsuba.py assets/dragon-sub2.ply

The llvm variant needs libLLVM (apt-get install libllvm19).
"""
import os, sys, time
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)
T = mi.ScalarTransform4f
ply = sys.argv[1]
start = time.perf_counter()
scene = mi.load_dict({
    "type": "scene",
    "integrator": {"type": "direct"},
    "sensor": {"type": "perspective", "fov": 35.0, "fov_axis": "y",
               "to_world": T().look_at(origin=[0, 0.2, 0.45], target=[0, 0.12, 0], up=[0, 1, 0]),
               "film": {"type": "hdrfilm", "width": 320, "height": 240},
               "sampler": {"type": "independent", "sample_count": 1}},
    "dragon": {"type": "ply", "filename": ply,
               "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.3, 0.6, 0.4]}}},
    "floor": {"type": "rectangle", "to_world": T().translate([0, 0.0527, 0]).rotate([1, 0, 0], -90).scale(100)},
    "sun": {"type": "directional", "direction": [0.4, -1.0, -0.5],
            "irradiance": {"type": "rgb", "value": [0.8, 0.8, 0.75]}},
})
loaded = time.perf_counter()
img = mi.render(scene)
dr.eval(img); dr.sync_thread()
done = time.perf_counter()
print(f"load_dict {loaded - start:.3f} s, render {done - loaded:.3f} s, first image {done - start:.3f} s")

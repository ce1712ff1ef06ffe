"""trimesh's own ray tests (its ``tests/test_ray.py``) with strata's
intersector swapped in for both of trimesh's engines.

The file comes from trimesh's source distribution, of the trimesh version
installed: ``$STRATA_RT_TRIMESH_TESTS`` (a folder holding test_ray.py), or
target/trimesh-tests/<version>/, filled once by ``pip download --no-binary``
(skipped, or failed under STRATA_RT_REQUIRE_ALL, when neither works). The
source distribution has the tests but not their helper module or model
files, so ``generic`` is played here by a module that makes the meshes the
tests load (a unit cube and a unit sphere, as trimesh's models are) and
installs strata's intersector; the tests that need other files, or
another library, are listed in NOT_RUN with why.
"""

import importlib.util
import logging
import os
import subprocess
import sys
import tarfile
import tempfile
import time
import types
from pathlib import Path

import numpy as np
import pytest

import helpers
from conftest import missing
from strata_rt.trimesh import RayMeshIntersector

trimesh = pytest.importorskip("trimesh", reason="trimesh is in tools/requirements.txt")

#: Tests of test_ray.py not run, and why.
NOT_RUN = {
    "test_rays": "reads ray_data from trimesh's test data, which its source distribution lacks",
    "test_on_edge": "loads 7_8ths_cube.stl, which its source distribution lacks",
    "test_contain_single": "loads teapot.stl, which its source distribution lacks",
    "test_contains_cavity": "needs a boolean engine (manifold3d), not a ray engine",
    "test_embree_duplicate_hits": (
        "counts a hit at t = 0 (the ray starts on the surface); strata's rays start just after "
        "their origin, (0, t_max], so that a ray leaving a surface does not hit it again"
    ),
}


class StrataEngine(RayMeshIntersector):
    """strata's intersector under the names and arguments of trimesh's engines."""

    def __init__(self, mesh, **_options):
        super().__init__(mesh)


def trimesh_test_file() -> Path:
    """trimesh's tests/test_ray.py for the installed version, fetched once."""
    own = os.environ.get("STRATA_RT_TRIMESH_TESTS")
    if own:
        return Path(own) / "test_ray.py"
    version = trimesh.__version__
    cache = helpers.REPO / "target" / "trimesh-tests" / version
    path = cache / "test_ray.py"
    if path.exists():
        return path
    with tempfile.TemporaryDirectory() as tmp:
        got = subprocess.run(
            [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:",
             f"trimesh=={version}", "-d", tmp, "-q"],
            capture_output=True, text=True, timeout=300,
        )
        sdists = list(Path(tmp).glob("trimesh-*.tar.gz"))
        if got.returncode != 0 or not sdists:
            return path
        with tarfile.open(sdists[0]) as tar:
            member = tar.getmember(f"trimesh-{version}/tests/test_ray.py")
            cache.mkdir(parents=True, exist_ok=True)
            path.write_bytes(tar.extractfile(member).read())
    return path


def get_mesh(name, use_embree=True, **_):
    """The models test_ray.py loads, made here: trimesh's unit_cube.STL is
    the cube [-0.5, 0.5]³ and unit_sphere.STL a unit sphere."""
    if name == "unit_cube.STL":
        mesh = trimesh.creation.box()
    elif name == "unit_sphere.STL":
        mesh = trimesh.creation.icosphere(subdivisions=2)
    else:  # pragma: no cover - NOT_RUN lists the tests that need others
        raise FileNotFoundError(name)
    mesh.ray = StrataEngine(mesh)
    return mesh


def generic():
    g = types.ModuleType("generic")
    g.np, g.trimesh, g.time = np, trimesh, time
    g.log = logging.getLogger("trimesh_tests")
    g.random = np.random.random
    g.get_mesh = get_mesh
    g.data = {}
    return g


def load_tests(monkeypatch):
    path = trimesh_test_file()
    if not path.exists():
        missing(f"trimesh's tests/test_ray.py (pip download --no-binary :all: trimesh=={trimesh.__version__})")
    monkeypatch.setitem(sys.modules, "generic", generic())
    # Both of trimesh's engines are strata's, whichever a test asks for.
    monkeypatch.setattr(trimesh.ray.ray_triangle, "RayMeshIntersector", StrataEngine)
    monkeypatch.setattr(trimesh.ray, "ray_pyembree", types.SimpleNamespace(RayMeshIntersector=StrataEngine))
    spec = importlib.util.spec_from_file_location("trimesh_test_ray", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_trimesh_s_ray_tests_pass_on_strata(monkeypatch):
    module = load_tests(monkeypatch)
    tests = sorted(n for n in dir(module) if n.startswith("test_"))
    ran = []
    for name in tests:
        if name in NOT_RUN:
            continue
        getattr(module, name)()
        ran.append(name)
    assert len(ran) >= 6, ran
    # A mesh built by the tests gets strata's engine.
    assert isinstance(trimesh.creation.box(use_embree=True).ray, StrataEngine)
    assert isinstance(trimesh.creation.box(use_embree=False).ray, StrataEngine)
    assert set(NOT_RUN) <= set(tests)

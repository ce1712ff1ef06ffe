"""Every Python example in the README and docs/python.md runs as written.

Each ```python block runs in a fresh namespace, from the repository's root
(the examples' paths are relative to it), after a prelude that gives the
names the examples take as given: ``np``, ``strata_rt``, ``vertices``
and ``faces`` (a closed icosphere) and its ``mesh``, ``origins`` and
``directions`` (rays at it), ``points``, ``light`` and ``normals``. A block that raises fails the test, naming its
file and line.
"""

import os
import re

import numpy as np
import pytest

import helpers
import strata_rt
from conftest import missing

FILES = ["README.md", "docs/python.md"]


def blocks():
    """(file, line, code) of every ```python block of FILES."""
    out = []
    for name in FILES:
        text = (helpers.REPO / name).read_text()
        for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M):
            out.append((name, text[: m.start()].count("\n") + 1, m.group(1)))
    return out


def prelude():
    vertices, faces = helpers.icosphere(2)
    rng = np.random.default_rng(3)
    origins = rng.normal(size=(64, 3)) * 3
    directions = -origins + rng.normal(size=(64, 3)) * 0.2
    points = rng.uniform(-1.5, 1.5, size=(64, 3))
    normals = helpers.unit(points)
    return {
        "np": np,
        "strata_rt": strata_rt,
        "mesh": strata_rt.Mesh(vertices, faces),
        "vertices": vertices,
        "faces": faces,
        "origins": origins,
        "directions": directions,
        "points": points,
        "light": np.array([0.0, 5.0, 0.0]),
        "normals": normals,
    }


def test_the_docs_have_python_examples():
    assert len(blocks()) >= 8, [f"{f}:{line}" for f, line, _ in blocks()]


@pytest.mark.parametrize("name,line,code", blocks(), ids=[f"{f}:{l}" for f, l, _ in blocks()])
def test_an_example_runs(name, line, code, monkeypatch):
    if "bunny.obj" in code and helpers.bunny_path() is None:
        missing("assets/bunny.obj (fetch it with `tools/fetch-assets --only bunny`)")
    monkeypatch.chdir(helpers.REPO)
    namespace = prelude()
    try:
        exec(compile(code, f"{name}:{line}", "exec"), namespace)
    except Exception as err:  # noqa: BLE001 - the report names the block
        pytest.fail(f"{name}, the example at line {line}, raised {type(err).__name__}: {err}")

"""Fixtures of the strata_rt tests: the meshes they share.

Run them with ``tools/.venv/bin/python -m pytest python/tests`` after
``maturin develop --release -m python/Cargo.toml`` (what ``cargo test
--release --test suite python::`` does). A test that needs the Stanford bunny or
the strata binary skips when it is missing, with a message saying how to
get it, unless STRATA_RT_REQUIRE_ALL is set (as the cargo test sets it),
which turns that skip into a failure.
"""

import os

import numpy as np
import pytest

import helpers


def missing(what: str) -> None:
    """Skip (or, under STRATA_RT_REQUIRE_ALL, fail) for want of `what`."""
    if os.environ.get("STRATA_RT_REQUIRE_ALL"):
        pytest.fail(f"{what} is missing and STRATA_RT_REQUIRE_ALL is set")
    pytest.skip(f"{what} is missing")


@pytest.fixture(scope="session")
def bunny():
    """The Stanford bunny as (vertices, faces) of its OBJ file (float64, int64)."""
    path = helpers.bunny_path()
    if path is None:
        missing("assets/bunny.obj (fetch it with `tools/fetch-assets --only bunny`)")
    return helpers.read_obj(path)


@pytest.fixture(scope="session")
def closed_bunny(bunny):
    """The bunny with each of its holes closed by a fan: a watertight mesh."""
    return helpers.close_holes(*bunny)


@pytest.fixture(scope="session")
def bumpy():
    """A generated closed, non-convex mesh (3,120 triangles)."""
    return helpers.bumpy_sphere()


@pytest.fixture
def rng():
    return np.random.default_rng(12345)

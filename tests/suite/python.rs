//! The Python package (python/, imported as `strata_rt`): built into
//! tools/.venv with `maturin develop --release` and tested there with
//! pytest (python/tests): its answers against Embree (embreex, robust
//! mode), float64 brute force and trimesh's own engine, crossings at
//! shared edges and vertices, `render` against the CLI's EXR bit for bit,
//! and every bad input. `cargo test --release --test suite python:: -- --nocapture`
//! prints pytest's report.
//!
//! What it needs from outside the crate, as the Embree tests do
//! (tests/suite/embree/setup.rs): tools/.venv, created when missing and filled
//! from tools/requirements.txt when it lacks a package, and the bunny
//! (tools/fetch-assets). It fails, never skips, when either is impossible;
//! the pytest run is told so (STRATA_RT_REQUIRE_ALL), so none of its tests
//! skips either.
//!
//! The build is the workspace's own: maturin runs cargo on python/ with
//! the same target/ and Cargo.lock, after this test's `cargo test` has let
//! go of target/'s lock (cargo holds it while it compiles, not while tests
//! run).

use crate::common::process::{repo, run};
use crate::embree::setup;

use std::process::Command;

/// What the tests import from tools/.venv (maturin is a program there).
const IMPORTS: &str = "import numpy, embreex.rtcore_scene, pytest, trimesh, rtree, OpenEXR";

#[test]
fn the_python_package_builds_and_passes_its_tests() {
    let python = setup::venv_python(IMPORTS, &["maturin"]);
    let bunny = setup::bunny();
    let repo = repo();
    run(
        Command::new(setup::venv().join("bin/maturin"))
            .args(["develop", "--release", "--manifest-path"])
            .arg(repo.join("python/Cargo.toml"))
            .env("VIRTUAL_ENV", setup::venv())
            .current_dir(repo),
        "building strata_rt into tools/.venv (maturin develop --release)",
    );
    let output = Command::new(&python)
        .args(["-m", "pytest", "-q", "-rfEs", "-p", "no:cacheprovider"])
        .arg(repo.join("python/tests"))
        .env("STRATA_BIN", env!("CARGO_BIN_EXE_strata"))
        .env("STRATA_RT_BUNNY", &bunny)
        .env("STRATA_RT_REQUIRE_ALL", "1")
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .current_dir(repo)
        .output()
        .expect("run pytest in tools/.venv");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stdout}");
    assert!(
        output.status.success(),
        "pytest python/tests failed ({}):\n{stdout}\n{stderr}",
        output.status
    );
}

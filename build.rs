//! Records which build this is, so that partial renders and checkpoints of
//! different builds are not mixed: `STRATA_VERSION` is the package version,
//! plus `+git.<commit>` when built from a git checkout.

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
}

/// Asks cargo to rerun this script when `path` changes (for a folder: when
/// anything in it does), if it exists: cargo counts a missing path as
/// changed, so it would rerun the script, and rebuild the crate, on every
/// build.
fn watch(path: &Path) -> bool {
    let exists = path.exists();
    if exists {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    exists
}

fn main() {
    let version = env!("CARGO_PKG_VERSION");
    let full = match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(commit) => format!("{version}+git.{commit}"),
        None => version.to_string(),
    };
    println!("cargo:rustc-env=STRATA_VERSION={full}");
    println!("cargo:rerun-if-changed=build.rs");
    let Some(dir) = git(&["rev-parse", "--git-dir"]) else {
        return;
    };
    // HEAD moves by a checkout, which rewrites HEAD itself (a branch's
    // name, or a commit when detached) ...
    watch(&Path::new(&dir).join("HEAD"));
    let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) else {
        return;
    };
    // ... or by a commit to the branch it names, which rewrites the
    // branch's loose ref. Without one (no commit yet, or refs packed by
    // `git gc`) git writes it into the nearest folder of refs that
    // exists, so watch that folder, and the packed refs that hold it
    // meanwhile. A repository in the reftable format keeps every ref in
    // `reftable/`.
    let common = PathBuf::from(git(&["rev-parse", "--git-common-dir"]).unwrap_or(dir));
    let refs = common.join("refs");
    let loose = common.join(&branch);
    if let Some(nearest) = loose
        .ancestors()
        .take_while(|p| p.starts_with(&refs))
        .find(|p| p.exists())
    {
        watch(nearest);
    }
    if !loose.is_file() {
        watch(&common.join("packed-refs"));
    }
    watch(&common.join("reftable"));
}

//! The Slurm recipe of docs/distributed.md, run for real: tools/slurm/check.sh
//! starts a throwaway one-node Slurm cluster, submits the documented
//! tools/slurm/render.sbatch unchanged as an array of 4, merges the parts and
//! compares the image with a single-process render byte for byte. Without
//! Slurm (or root) the check is skipped, except under CI (`CI` set), which
//! installs Slurm and so must run it. The document must show the script
//! exactly as it is.

use crate::common::process::repo;
use std::path::Path;
use std::process::Command;

/// tools/slurm/check.sh's exit status when it cannot run here.
const SKIPPED: i32 = 77;

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The contents of every fenced code block of a Markdown text.
fn code_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.split_inclusive('\n') {
        if line.starts_with("```") {
            match current.take() {
                Some(block) => blocks.push(block),
                None => current = Some(String::new()),
            }
        } else if let Some(block) = current.as_mut() {
            block.push_str(line);
        }
    }
    assert!(current.is_none(), "unclosed code block");
    blocks
}

#[test]
fn documented_sbatch_script_is_the_file() {
    let doc = read(&repo().join("docs/distributed.md"));
    let script = read(&repo().join("tools/slurm/render.sbatch"));
    let shown: Vec<String> = code_blocks(&doc)
        .into_iter()
        .filter(|b| b.contains("#SBATCH"))
        .collect();
    assert_eq!(
        shown.len(),
        1,
        "docs/distributed.md should show one sbatch script"
    );
    assert!(
        shown[0] == script,
        "the sbatch script in docs/distributed.md differs from tools/slurm/render.sbatch:\n\
         --- doc\n{}--- file\n{}",
        shown[0],
        script
    );
}

#[test]
fn slurm_array_job_merges_to_the_single_process_image() {
    let check = repo().join("tools/slurm/check.sh");
    let out = Command::new("bash")
        .arg(&check)
        .arg(env!("CARGO_BIN_EXE_strata"))
        .current_dir(repo())
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", check.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    print!("{stdout}");
    eprint!("{stderr}");
    match out.status.code() {
        Some(0) => {}
        Some(SKIPPED) if std::env::var_os("CI").is_none() => {
            crate::common::skipped(
                "slurm::slurm_array_job_merges_to_the_single_process_image",
                &format!(
                    "{} (install slurm-wlm and munge, and run as root)",
                    stdout
                        .lines()
                        .last()
                        .unwrap_or("")
                        .trim_start_matches("slurm check: SKIPPED: ")
                ),
            );
        }
        Some(SKIPPED) => panic!(
            "CI is set, so the Slurm check must run: .ci/run installs slurm-wlm and munge, \
             and it needs root ({})",
            stdout.trim()
        ),
        _ => panic!(
            "tools/slurm/check.sh failed ({}): {}",
            out.status,
            stdout.lines().last().unwrap_or("no output")
        ),
    }
}

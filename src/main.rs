//! The `strata` command line: argument parsing and dispatch only.

mod cli;

use std::process::ExitCode;

/// The system's allocator, with large blocks on huge pages where they are
/// cheap to write first (`STRATA_HUGE_PAGES`, docs/cli.md).
#[global_allocator]
static ALLOCATOR: strata::accel::allocator::HugePageAllocator =
    strata::accel::allocator::HugePageAllocator;

fn main() -> ExitCode {
    cli::cpu::require_built_for_features();
    let args = cli::flags::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(cli::CliError::Input(e)) => {
            // A scene's several mistakes: one `error:` line each.
            for e in e.into_each() {
                eprintln!("error: {e}");
            }
            ExitCode::from(2)
        }
        Err(cli::CliError::Internal(e)) => {
            eprintln!("internal error: {e}");
            ExitCode::from(1)
        }
    }
}

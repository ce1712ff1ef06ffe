//! `strata merge`: combine the `.strata` parts of a sliced render.

use super::render::is_partial_path;
use super::CliError;
use clap::Args;
use std::path::PathBuf;
use strata::error::InputError;
use strata::output::image::{write_image, ImageFormat};
use strata::partial::format::{read_partial, write_partial};
use strata::partial::merge::merge_partials;

#[derive(Debug, Args, Clone)]
pub struct MergeArgs {
    /// The parts: .strata files from `strata render --slice k/P`, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output: .png or .exr (needs every slice 0..P), or .strata (a merged
    /// part: any contiguous run of slices, for merging in stages).
    #[arg(short, long)]
    pub output: PathBuf,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: MergeArgs) -> Result<(), CliError> {
    let partial_output = is_partial_path(&args.output);
    if !partial_output && ImageFormat::from_path(&args.output).is_none() {
        return Err(InputError::new(
            "<command line>",
            "--output",
            "must end in .png, .exr or .strata",
        )
        .into());
    }
    let mut parts = Vec::with_capacity(args.parts.len());
    for path in &args.parts {
        let part = read_partial(path).map_err(|e| InputError::file(path, e))?;
        parts.push((path.clone(), part));
    }
    let n = parts.len();
    let merged = merge_partials(parts, !partial_output)?;
    let h = &merged.header;
    if partial_output {
        write_partial(&args.output, h, &merged.film)
            .map_err(|e| InputError::file(&args.output, format!("cannot write: {e}")))?;
    } else {
        write_image(&args.output, &merged.film.to_rgb(), h.width, h.height)
            .map_err(|e| InputError::file(&args.output, e))?;
    }
    if let Some(bad) = merged.film.first_invalid {
        eprintln!(
            "warning: {} samples were NaN, infinite or negative and were dropped; first at pixel ({}, {}) sample {}",
            merged.film.invalid, bad.x, bad.y, bad.sample
        );
    }
    if !args.quiet {
        println!(
            "merged {n} parts: slices {}, {}x{} {} spp (samples {}..{}) -> {}",
            h.slices_text(),
            h.width,
            h.height,
            h.spp,
            h.samples.start,
            h.samples.end,
            args.output.display()
        );
    }
    Ok(())
}

//! `strata render`.

use super::CliError;
use clap::Args;
use std::path::PathBuf;
use strata::error::InputError;
use strata::output::image::write_image;
use strata::partial::format::{read_partial, write_partial, PartialHeader};
use strata::render::stats::RenderStats;
use strata::render::{render, RenderOptions, Schedule, SliceSpec};
use strata::scene::{load_scene, RenderOverrides};

#[derive(Debug, Args, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML). Default: scenes/seed.toml.
    pub scene: Option<PathBuf>,
    /// Output: .png (sRGB, 8-bit), .exr (linear float), or .strata (the
    /// film's exact sums, for `strata merge`; required with --slice k/P, P > 1).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Render settings; each overrides the scene file's `[render]` value.
    #[command(flatten)]
    pub settings: RenderOverrides,
    /// Worker threads (default: all cores). The image is identical for any count.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Render only slice k of P of every pixel's samples (0-based k), e.g. 3/8,
    /// into a .strata part; `strata merge` combines the P parts.
    #[arg(long, value_name = "k/P")]
    pub slice: Option<String>,
    /// Save the accumulated film to FILE (.strata) after every pass, atomically.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Continue from the --checkpoint file if it exists (it must be of the
    /// same scene, settings and slice); the result is bit-identical to an
    /// uninterrupted render.
    #[arg(long, requires = "checkpoint")]
    pub resume: bool,
    /// Progressive passes (each a progress tick and a checkpoint); capped by
    /// the sample count.
    #[arg(long, default_value_t = strata::render::schedule::DEFAULT_PASSES,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub passes: u32,
    /// slices: work stealing over sample slices of pixel batches; regions: one
    /// static band of rows per thread, a baseline for `strata scaling`.
    #[arg(long, default_value = "slices")]
    pub schedule: Schedule,
    /// Trace coherent batches (one pixel's camera samples, the shadow rays
    /// from one hit to one light) as 8-ray packets: auto where measured to pay
    /// (camera batches of 7 or more rays), on, or off. The image is
    /// bit-identical in every mode.
    #[arg(long, default_value = "auto")]
    pub packets: strata::shade::PacketMode,
    /// BVH build effort; auto picks by primitive count.
    #[arg(long, default_value = "auto")]
    pub bvh_quality: strata::accel::BuildQuality,
    /// Write statistics (rays by kind, Mrays/s, phase times, peak RSS) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Replay one sample (pixel x, y and sample index) and print its path instead of rendering.
    #[arg(long, value_name = "X,Y,SAMPLE")]
    pub debug_sample: Option<strata::render::replay::SampleId>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

impl Default for RenderArgs {
    fn default() -> Self {
        use clap::FromArgMatches;
        let cmd = <Self as Args>::augment_args(clap::Command::new("strata"));
        Self::from_arg_matches(&cmd.get_matches_from(["strata"])).expect("defaults parse")
    }
}

pub fn run(args: RenderArgs) -> Result<(), CliError> {
    let scene_path = args
        .scene
        .clone()
        .unwrap_or_else(|| PathBuf::from("scenes/seed.toml"));
    let partial_output = is_partial_path(&args.output);
    if !partial_output && strata::output::image::ImageFormat::from_path(&args.output).is_none() {
        return Err(InputError::new(
            "<command line>",
            "--output",
            "must end in .png, .exr or .strata",
        )
        .into());
    }
    // Parsed here, not by clap, so that a bad value is one line like every other input error.
    let slice = match &args.slice {
        None => SliceSpec::WHOLE,
        Some(text) => text
            .parse::<SliceSpec>()
            .map_err(|e| InputError::new("<command line>", "--slice", e))?,
    };
    if slice.count > 1 && !partial_output {
        return Err(InputError::new(
            "<command line>",
            "--slice",
            format!(
                "slice {}/{} is a partial render: write it to a .strata file (-o part_{}.strata) and combine the parts with `strata merge`",
                slice.index, slice.count, slice.index
            ),
        )
        .into());
    }
    if let Some(ck) = &args.checkpoint {
        if !is_partial_path(ck) {
            return Err(
                InputError::new("<command line>", "--checkpoint", "must end in .strata").into(),
            );
        }
    }
    let (scene, timings) = load_scene(&scene_path, &args.settings, args.bvh_quality)?;
    if let Some(id) = args.debug_sample {
        let (value, events) = strata::render::replay::replay(&scene, id)
            .map_err(|e| InputError::new("<command line>", "--debug-sample", e))?;
        print!("{}", strata::render::replay::describe(id, value, &events));
        return Ok(());
    }
    let s = &scene.settings;
    let full = slice.samples(s.spp);
    let header = PartialHeader::for_scene(&scene, slice, full.clone());

    let (initial, resume_from) = match (&args.checkpoint, args.resume) {
        (Some(ck), true) if ck.exists() => {
            let part = read_partial(ck).map_err(|e| InputError::file(ck, e))?;
            let done = part
                .header
                .resume_point(&header)
                .map_err(|e| InputError::file(ck, e))?;
            if !args.quiet {
                eprintln!(
                    "resuming from {}: samples {}..{} of {}..{} done",
                    ck.display(),
                    full.start,
                    done,
                    full.start,
                    full.end
                );
            }
            (Some(part.film), Some(done))
        }
        (Some(ck), true) => {
            if !args.quiet {
                eprintln!(
                    "no checkpoint at {} yet; starting from the first sample",
                    ck.display()
                );
            }
            (None, None)
        }
        _ => (None, None),
    };

    let opts = RenderOptions {
        threads: args.threads,
        slice,
        schedule: args.schedule,
        quiet: args.quiet,
        passes: args.passes,
        resume_from,
        packets: args.packets,
    };
    let mut checkpoint_failed = false;
    let outcome = render(&scene, &opts, initial, |film, done| {
        let Some(ck) = &args.checkpoint else {
            return;
        };
        let h = PartialHeader {
            samples: full.start..done,
            ..header.clone()
        };
        if let Err(e) = write_partial(ck, &h, film) {
            if !checkpoint_failed {
                eprintln!("warning: {}: cannot write checkpoint: {e}", ck.display());
                checkpoint_failed = true;
            }
        }
    });
    if partial_output {
        write_partial(&args.output, &header, &outcome.film)
            .map_err(|e| InputError::file(&args.output, format!("cannot write: {e}")))?;
    } else {
        write_image(&args.output, &outcome.film.to_rgb(), s.width, s.height)
            .map_err(|e| InputError::file(&args.output, e))?;
    }

    if outcome.counts.glossy_rejected > 0 && !args.quiet {
        eprintln!(
            "note: {} glossy directions fell below their surface and were rejected (counted, not traced)",
            outcome.counts.glossy_rejected
        );
    }
    if let Some(bad) = outcome.film.first_invalid {
        eprintln!(
            "warning: {} samples were NaN, infinite or negative and were dropped; first at pixel ({}, {}) sample {} (replay it with --debug-sample {},{},{})",
            outcome.film.invalid, bad.x, bad.y, bad.sample, bad.x, bad.y, bad.sample
        );
    }
    let stats = RenderStats::new(&scene_path, &scene, &timings, &opts, &outcome);
    if let Some(path) = &args.stats {
        strata::output::atomic::write_bytes_atomic(path, stats.to_json().as_bytes())
            .map_err(|e| InputError::file(path, format!("cannot write: {e}")))?;
    }
    if !args.quiet {
        println!("{}", stats.summary(&args.output));
    }
    Ok(())
}

/// Whether `path` names a partial render (`.strata`).
pub fn is_partial_path(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("strata"))
}

//! `strata converge`: error against time and against spp, per sampling method.

use super::CliError;
use clap::Args;
use std::path::PathBuf;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::experiment::column_key;
use strata::experiment::converge::{self, Point, METHODS};
use strata::output::chart::write_svg;
use strata::scene::{load_scene, RenderOverrides};

/// The columns of the table `strata converge` prints (and of its CSV).
const COLUMNS: [(&str, &str); 5] = [
    ("method", "the sampling method (docs/converge.md)"),
    ("spp", "samples per pixel of the render"),
    ("seconds", "median wall time of its renders (--repeats)"),
    (
        "RMSE",
        "root mean square error against the reference, over pixels and channels",
    ),
    (
        "relMSE",
        "relative MSE: the mean of (value - reference)^2 / (reference^2 + 0.01)",
    ),
];

#[derive(Debug, Args, Clone)]
#[command(after_help = "Every column of the table: strata converge --help.")]
#[command(after_long_help = format!("The table's columns:\n{}", column_key(&COLUMNS)))]
pub struct ConvergeArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Reference image (linear EXR) of the same size. Without it, a reference
    /// is rendered first with --reference-spp samples and saved beside the CSV.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference (keep it 16 times --max-spp
    /// or more, or the error curves flatten at the reference's own noise).
    #[arg(long, default_value_t = converge::DEFAULT_REFERENCE_SPP, value_parser = clap::value_parser!(u32).range(1..))]
    pub reference_spp: u32,
    /// Largest spp measured (powers of two from 1).
    #[arg(long, default_value_t = converge::DEFAULT_MAX_SPP, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_spp: u32,
    /// Output CSV: method, spp, seconds, RMSE, relative MSE.
    #[arg(long, default_value = "converge.csv")]
    pub csv: PathBuf,
    /// Output chart (SVG): RMSE against time and against spp, log-log, slope in the legend.
    #[arg(long, default_value = "converge.svg")]
    pub chart: PathBuf,
    /// Image width (overrides the scene).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    pub height: Option<u32>,
    /// Renders per point; the median time is reported (machines are noisy).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Worker threads (default: all cores).
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// Also measure adaptive sampling (stratified+is with `--noise E`) at
    /// each of these noise targets, e.g. 0.1,0.05,0.025: rows named
    /// adaptive@E whose spp is the mean over the image; after the table,
    /// each one's time against the best uniform method's at the same RMSE.
    #[arg(long, value_delimiter = ',', value_name = "E,...")]
    pub noise: Vec<f32>,
    /// The adaptive renders' ceiling of samples per pixel (default: 4
    /// times --max-spp).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub noise_spp: Option<u32>,
    /// No progress bar and no notes on standard error; the table still goes
    /// to standard output.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: ConvergeArgs) -> Result<(), CliError> {
    // Every flag is checked before the reference is rendered, which takes
    // most of the run.
    if let Some(e) = args.noise.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
        return Err(InputError::flag(
            format!("--noise {e}"),
            "must be relative errors above 0, such as 0.05,0.025",
        )
        .into());
    }
    super::writable(&args.csv, "--csv", &["csv"])?;
    super::writable(&args.chart, "--chart", &["svg"])?;
    if args.reference.is_none() {
        super::writable(&reference_path(&args), "--csv", &[])?;
    }
    let overrides = RenderOverrides {
        width: args.width,
        height: args.height,
        ..RenderOverrides::default()
    };
    let (scene, _) = load_scene(&args.scene, &overrides, BuildQuality::Auto)?;
    let (w, h) = (scene.settings.width, scene.settings.height);
    let reference = match &args.reference {
        Some(path) => {
            let (pixels, rw, rh) =
                strata::output::image::read_image(path).map_err(|e| InputError::file(path, e))?;
            if (rw, rh) != (w, h) {
                return Err(
                    InputError::file(path, format!("is {rw}x{rh}, the render is {w}x{h}")).into(),
                );
            }
            pixels
        }
        None => {
            let path = reference_path(&args);
            if !args.quiet {
                eprintln!(
                    "no --reference given: rendering a {}-spp reference with {} sampling, saved to {}",
                    args.reference_spp,
                    converge::REFERENCE_METHOD.name,
                    path.display()
                );
            }
            let pixels = converge::reference(
                &scene,
                args.reference_spp,
                args.threads,
                super::progress::RenderBar::new(args.quiet),
            );
            strata::output::image::write_image(&path, &pixels, w, h)
                .map_err(|e| InputError::file(&path, e))?;
            pixels
        }
    };
    // The table is the command's answer: -q silences only the progress
    // and the notes on standard error.
    println!(
        "{:<28} {:>6} {:>10} {:>12} {:>12}",
        "method", "spp", "seconds", "RMSE", "relMSE"
    );
    let row = |p: &Point| {
        let method = match p.noise {
            Some(e) => format!("{}@{e}", p.method),
            None => p.method.to_string(),
        };
        println!(
            "{:<28} {:>6} {:>10.4} {:>12.4e} {:>12.4e}",
            method,
            p.mean_spp.round(),
            p.seconds,
            p.rmse,
            p.rel_mse
        );
    };
    let mut points = converge::measure(
        &scene,
        &reference,
        &METHODS,
        args.max_spp,
        args.threads,
        args.repeats,
        row,
    );
    let ceiling = args.noise_spp.unwrap_or(
        args.max_spp
            .saturating_mul(4)
            .min(strata::scene::settings::MAX_SPP),
    );
    let adaptive = converge::measure_adaptive(
        &scene,
        &reference,
        &args.noise,
        ceiling,
        args.threads,
        args.repeats,
        row,
    );
    if !args.quiet {
        for p in &adaptive {
            let e = p.noise.unwrap_or_default();
            match converge::uniform_time_at(&points, p.rmse) {
                Some((t, m)) => eprintln!(
                    "adaptive@{e}: RMSE {:.4e} in {:.4} s; the best uniform method ({m}) takes {t:.4} s to it: {:.2}x its time",
                    p.rmse,
                    p.seconds,
                    p.seconds / t
                ),
                None => eprintln!(
                    "adaptive@{e}: RMSE {:.4e} in {:.4} s, outside the uniform curves (raise --max-spp)",
                    p.rmse, p.seconds
                ),
            }
        }
    }
    points.extend(adaptive);
    write_outputs(&args, &points)
}

/// Where a rendered reference is saved: beside the CSV.
fn reference_path(args: &ConvergeArgs) -> PathBuf {
    args.csv.with_extension("reference.exr")
}

fn write_outputs(args: &ConvergeArgs, points: &[Point]) -> Result<(), CliError> {
    let mut csv = String::from("method,spp,seconds,rmse,rel_mse,noise,mean_spp\n");
    for p in points {
        let noise = p.noise.map_or(String::new(), |e| e.to_string());
        csv.push_str(&format!(
            "{},{},{},{},{},{noise},{}\n",
            p.method, p.spp, p.seconds, p.rmse, p.rel_mse, p.mean_spp
        ));
    }
    strata::output::atomic::write_bytes_atomic(&args.csv, csv.as_bytes())
        .map_err(|e| InputError::file(&args.csv, format!("cannot write: {e}")))?;
    let title = args
        .scene
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let panels = converge::chart_panels(&title, points);
    write_svg(&args.chart, &panels, 560, 420).map_err(|e| InputError::file(&args.chart, e))?;
    // Standard output holds only the table, for piping.
    if !args.quiet {
        eprintln!("wrote {} and {}", args.csv.display(), args.chart.display());
    }
    Ok(())
}

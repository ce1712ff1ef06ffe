//! `strata merge`: combine the `.strata` parts of a sliced render.

use super::render::is_partial_path;
use super::CliError;
use clap::Args;
use std::path::PathBuf;
use strata::error::{InputError, COMMAND_LINE};
use strata::output::atomic::check_target;
use strata::output::image::{write_image, ImageFormat};
use strata::output::tonemap::Tonemap;
use strata::partial::format::{read_partial, write_partial, Partial, PIXEL_BYTES};
use strata::partial::merge::{merge_partials, MergeRules};
use strata::render::film::render_bytes_per_pixel;
use strata::render::Warning;
use strata::system::budget::bytes_text;

#[derive(Debug, Args, Clone)]
pub struct MergeArgs {
    /// The parts: .strata files from `strata render --slice k/P`, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output: .png or .exr (needs every slice 0..P), or .strata (a merged
    /// part: any contiguous run of slices, for merging in stages).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Preview what the parts hold so far: unfinished checkpoints and
    /// missing slices are accepted, and each pixel is the mean of the samples
    /// there are. Needs an image output.
    #[arg(long)]
    pub partial: bool,
    /// Merge parts written by different builds of strata (their samples need
    /// not agree bit for bit).
    #[arg(long)]
    pub force: bool,
    /// Stops for an 8-bit output (PNG): radiance times 2^exposure. Default:
    /// the exposure the parts were rendered with ([render] exposure).
    #[arg(long, value_name = "STOPS", allow_hyphen_values = true)]
    pub exposure: Option<f32>,
    /// Tone curve of an 8-bit output: clamp or filmic. Default: the parts'
    /// own ([render] tonemap). EXR stays linear.
    #[arg(long)]
    pub tonemap: Option<Tonemap>,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: MergeArgs) -> Result<(), CliError> {
    let partial_output = is_partial_path(&args.output);
    let extensions: &[&str] = if args.partial {
        &["png", "exr"]
    } else {
        &["png", "exr", "strata"]
    };
    check_target(&args.output, extensions)
        .map_err(|e| InputError::new("<command line>", "--output", e))?;
    if let Some(part) = args
        .parts
        .iter()
        .find(|p| super::same_file(p, &args.output))
    {
        let why = format!(
            "'{}' is one of the parts it merges: write the merge to a file of its own",
            part.display()
        );
        return Err(InputError::new("<command line>", "--output", why).into());
    }
    check_memory(&args.parts, !partial_output)?;
    if let Some(e) = args.exposure.filter(|e| !e.is_finite()) {
        let why = format!(
            "{e} is not a number of stops{}",
            strata::scene::settings::past_float32(e)
        );
        return Err(InputError::new(COMMAND_LINE, "--exposure", why).into());
    }
    let mut parts: Vec<(PathBuf, Partial)> = Vec::with_capacity(args.parts.len());
    // An EXR is the film itself, which no exposure or curve changes: its
    // parts show as the first does, whatever each was rendered with.
    let exr = ImageFormat::from_path(&args.output) == Some(ImageFormat::Exr);
    for path in &args.parts {
        let mut part = read_partial(path).map_err(|e| InputError::file(path, e))?;
        // The flags replace the display the parts carry: it shows the film,
        // and does not change it.
        let shown = match parts.first() {
            Some((_, first)) if exr => (first.header.exposure, first.header.tonemap),
            _ => (part.header.exposure, part.header.tonemap),
        };
        let h = &mut part.header;
        h.exposure = args.exposure.unwrap_or(shown.0);
        h.tonemap = args.tonemap.unwrap_or(shown.1);
        parts.push((path.clone(), part));
    }
    let n = parts.len();
    let rules = MergeRules {
        require_all: !partial_output,
        preview: args.partial,
        force: args.force,
    };
    let merged = merge_partials(parts, rules)?;
    let h = &merged.header;
    if partial_output {
        write_partial(&args.output, h, &merged.film)
            .map_err(|e| InputError::file(&args.output, format!("cannot write: {e}")))?;
    } else {
        let mut pixels = merged.film.to_rgb();
        if ImageFormat::from_path(&args.output) != Some(ImageFormat::Exr) {
            strata::output::tonemap::apply(&mut pixels, h.exposure, h.tonemap);
        }
        write_image(&args.output, &pixels, h.width, h.height)
            .map_err(|e| InputError::file(&args.output, e))?;
    }
    super::warn(Warning::dropped(&merged.film));
    if !args.quiet {
        let parts = super::count(n, "part", "parts");
        let what = if args.partial {
            format!(
                "preview of {parts}: {:.1} of {} spp per pixel on average",
                merged.film.mean_samples(),
                h.spp
            )
        } else {
            format!(
                "merged {parts}: slices {}, samples {}..{} of {} spp",
                h.slices_text(),
                h.samples.start,
                h.samples.end,
                h.spp
            )
        };
        println!(
            "{what}, {}x{} -> {}",
            h.width,
            h.height,
            args.output.display()
        );
    }
    Ok(())
}

/// Whether merging `parts` fits in this machine's memory, weighed before
/// any is read: a merge holds every part's film at once (as many bytes
/// as its file, less a header), and with `image` the image made from them.
fn check_memory(parts: &[PathBuf], image: bool) -> Result<(), CliError> {
    // A file that cannot be read is named when it is read.
    let lengths: Vec<u64> = parts
        .iter()
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .collect();
    let films: u128 = lengths.iter().map(|&l| u128::from(l)).sum();
    let largest = lengths.iter().max().copied().unwrap_or(0);
    let pixels = u128::from(largest / PIXEL_BYTES);
    let per_pixel = render_bytes_per_pixel(false, true) - render_bytes_per_pixel(false, false);
    let need = films
        + if image {
            pixels * u128::from(per_pixel)
        } else {
            0
        };
    let what = format_args!(
        "merging {}, whose films ({}) are held at once{},",
        super::count(parts.len(), "part", "parts"),
        bytes_text(films),
        if image { " with the image" } else { "" }
    );
    strata::system::budget::check(need, what).map_err(|m| {
        let advice = "; merge a few at a time into .strata parts (-o a.strata), then merge those";
        InputError::new(COMMAND_LINE, "PARTS", format!("{m}{advice}")).into()
    })
}

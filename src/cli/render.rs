//! `strata render`.

use super::progress::RenderBar;
use super::CliError;
use clap::Args;
use std::path::PathBuf;
use std::sync::Arc;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::output::exr::{Attribute, ExrImage};
use strata::output::image::{write_image, ImageFormat};
use strata::partial::format::{read_partial, write_partial, PartialHeader};
use strata::render::aov::{self, Aov, AovSum};
use strata::render::stats::RenderStats;
use strata::render::timeline::{Phase, Timeline};
use strata::render::{
    each_pass, is_current_pool, on_current_pool, render, Film, RenderOptions, Schedule, SliceSpec,
    Window,
};
use strata::sampling::SamplerKind;
use strata::scene::edit::Edit;
use strata::scene::model::is_model_path;
use strata::scene::{
    compile, load_edited_scene, model, parse, LoadTimings, RenderOverrides, Scene,
};

#[derive(Debug, Args, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML), or a model file (.glb, .gltf, .obj, .ply, .off, .stl) to
    /// render as it comes: with its own camera and lights where it has
    /// them, else framed from a three-quarter view under default lights.
    /// Without one, the built-in seed scene (the same as the repository's
    /// scenes/seed.toml).
    pub scene: Option<PathBuf>,
    /// With a model file: render from its camera N (0-based) instead of
    /// the first, or `auto`: strata's framing camera (a three-quarter
    /// view that fits the model) even when the file has cameras.
    #[arg(long, value_name = "N|auto")]
    pub camera: Option<model::CameraChoice>,
    /// With a model file: write the scene made for it to FILE (.toml,
    /// atomically), to edit and render again with `strata render FILE`.
    #[arg(long, value_name = "FILE.toml")]
    pub save_scene: Option<PathBuf>,
    /// Output: .png (sRGB, 8-bit), .exr (linear float), or .strata (the
    /// film's exact sums, for `strata merge`; required with --slice k/P, P > 1).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Render settings; each overrides the scene file's `[render]` value.
    #[command(flatten)]
    pub settings: RenderOverrides,
    /// Change any value of the scene file by its key path, as editing the
    /// file would, e.g. --set camera.fov=30 --set 'lights[0].radiance=[1,1,1]'.
    /// The value is TOML (or a bare word, taken as a string). Repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<Edit>,
    /// Threads for loading, the BVH build and rendering (default: all
    /// cores). The image is identical for any count.
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// Render only slice k of P of every pixel's samples (0-based k), e.g. 3/8,
    /// into a .strata part; `strata merge` combines the P parts.
    #[arg(long, value_name = "k/P")]
    pub slice: Option<String>,
    /// Save the accumulated film to FILE (.strata) after every pass, atomically.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Continue from the --checkpoint file if it exists (it must be of the
    /// same scene, settings, slice and strata build); the result is
    /// bit-identical to an uninterrupted render. Without --resume an existing
    /// checkpoint file is an error, never silently replaced.
    #[arg(long, requires = "checkpoint")]
    pub resume: bool,
    /// Resume from a checkpoint written by a different build of strata.
    #[arg(long, requires = "resume")]
    pub force: bool,
    /// Progressive passes (each a progress tick and a checkpoint); capped by
    /// the sample count. Default: up to 16, each with at least 32 samples
    /// per pixel, since a pixel's samples are traced and lit in batches of
    /// 8 within a pass, each batch walking where the pixel's last one left
    /// the caches (thinner passes are slower, never a different image).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub passes: Option<u32>,
    /// Render passes until this much time is spent (30s, 2m, 1.5h, or
    /// seconds), then write the image and say how many samples per pixel
    /// it reached: passes of 4, 8, 12, 16, … samples, up to --spp
    /// (default 65536 with --time). Not bit-identical by nature: the
    /// samples reached depend on the machine and its load.
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    pub time: Option<f64>,
    /// slices: work stealing over sample slices of work items (64 pixels); regions: one
    /// static band of rows per thread, a baseline for `strata scaling`.
    #[arg(long, default_value = "slices")]
    pub schedule: Schedule,
    /// Trace a batch's coherent rays (one pixel's camera samples, the shadow
    /// rays from their hits to one light sample) as 8-ray packets: auto where
    /// measured to pay (7 or more camera rays), on, or off. The image is
    /// bit-identical in every mode.
    #[arg(long, default_value = "auto")]
    pub packets: strata::shade::PacketMode,
    /// BVH build effort: preview, fastest, fast, auto, medium or high. Auto estimates the rays the render traces (pixels × samples × rays a sample) and builds the preset whose build plus trace time is least (preview, cut straight from the Morton order, for a quick look at a big mesh; high for a long render); --stats and the summary say which and why.
    #[arg(long, default_value = "auto")]
    pub bvh_quality: strata::accel::BuildQuality,
    /// Write statistics (rays by kind, Mrays/s, phase times, peak RSS) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Write a trace of the run (.json, Chrome's trace event format, which
    /// Perfetto and chrome://tracing open): a track per thread with a span
    /// per work item, the load, build, passes and output on the main track,
    /// and rays per second. Its summary goes into --stats. See docs/scaling.md.
    #[arg(long, value_name = "FILE.json")]
    pub timeline: Option<PathBuf>,
    /// Render only the window X0,Y0,X1,Y1 (pixels, half-open) and write an
    /// image of that size. Each pixel gets the samples it gets in the whole
    /// image, so the crop equals that window of a full render bit for bit
    /// (an EXR places it in the full image's display window).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub crop: Option<String>,
    /// Add AOV channels to the EXR output, averaged over each pixel's camera
    /// samples: albedo (albedo.R/G/B, the first hit's diffuse colour),
    /// normal (normal.X/Y/Z, its world-space shading normal), depth
    /// (depth.Z, the distance along the camera ray; inf where a ray
    /// misses), spp (spp, the samples the pixel took: fewer than --spp
    /// where --noise stopped it).
    #[arg(long, value_delimiter = ',', value_name = "AOV,...")]
    pub aov: Vec<Aov>,
    /// Rewrite the output image after every pass (atomically), to watch it
    /// converge; a render stopped part-way leaves the last pass's image.
    /// --passes sets how often.
    #[arg(long)]
    pub progressive: bool,
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

/// The scene `strata` renders when given none: built in, so a bare
/// `strata` works from any directory.
const SEED_SCENE: &str = include_str!("../../scenes/seed.toml");
const SEED_SCENE_NAME: &str = "scenes/seed.toml (built in)";

/// The ceiling of a `--time` render's samples when `--spp` is not given.
pub const TIME_SPP: u32 = 1 << 16;

pub fn run(args: RenderArgs) -> Result<(), CliError> {
    // One pool for the whole command: the load, the build, the render and
    // the output share its threads, started once (a small scene's render
    // took longer to start its own pool than to load).
    on_threads(args.threads, || run_here(args))?
}

fn run_here(mut args: RenderArgs) -> Result<(), CliError> {
    let (slice, partial_output) = check_outputs(&args)?;
    if args.time.is_some() && args.settings.spp.is_none() {
        args.settings.spp = Some(TIME_SPP);
    }
    // Flags that size the image alone are weighed before the scene is read.
    if let (Some(w), Some(h), None) = (args.settings.width, args.settings.height, &args.crop) {
        check_image_memory(&args, w, h)
            .map_err(|m| InputError::flag(format!("--width {w} --height {h}"), m))?;
    }
    let epoch = std::time::Instant::now();
    let (mut scene, timings) = load(&args)?;
    if args.time.is_some() && scene.settings.sampler == SamplerKind::Stratified {
        // As under a noise target (`RenderSettings::merge`): a timed render
        // may stop after any pass, so it draws from the sequence that is
        // stratified at every power-of-two prefix.
        scene.settings.sampler = SamplerKind::Sobol;
    }
    super::warn(&scene.warnings);
    // Recorded for the trace, and for the summary in the statistics.
    let timeline = (args.timeline.is_some() || args.stats.is_some()).then(|| {
        let t = Timeline::new(epoch);
        t.load_and_build(timings.load, timings.bvh_build);
        Arc::new(t)
    });
    let scene_name = scene_name(args.scene.as_deref());
    if let Some(id) = args.debug_sample {
        let (value, events) = strata::render::replay::replay(&scene, id, args.time.is_some())
            .map_err(|e| InputError::new("<command line>", "--debug-sample", e))?;
        print!(
            "{}",
            strata::render::replay::describe(&scene, id, value, &events)
        );
        return Ok(());
    }
    let s = &scene.settings;
    let window = match &args.crop {
        Some(text) => Some(
            Window::crop(text, s.width, s.height)
                .map_err(|e| InputError::new("<command line>", "--crop", e))?,
        ),
        None => None,
    };
    let (w, h) = window
        .as_ref()
        .map_or((s.width, s.height), |w| (w.width(), w.height()));
    check_image_memory(&args, w, h).map_err(|m| image_size_error(&args, m))?;
    let full = slice.samples(s.spp);
    if full.is_empty() {
        // Its part merges as it should (it holds nothing), but a job array
        // of more slices than samples runs tasks that do no work.
        super::warn([format!(
            "slice {}/{} of {} spp holds no samples: split into at most {} slices",
            slice.index, slice.count, s.spp, s.spp
        )]);
    }
    // The header holds the scene's fingerprint, a hash of every triangle:
    // computed only when a .strata file (output or checkpoint) is written.
    let header = (partial_output || args.checkpoint.is_some())
        .then(|| PartialHeader::for_scene(&scene, slice, full.clone()));
    let (initial, resume_from) = match &header {
        Some(header) => resume(&args, header)?,
        None => (None, None),
    };
    // Made here, where its failure is an error, unless a checkpoint gave it.
    let initial = match initial {
        Some(film) => film,
        None => Film::try_new(w, h).map_err(|m| image_size_error(&args, m))?,
    };
    let image = Output {
        args: &args,
        scene: &scene,
        window: window
            .clone()
            .unwrap_or_else(|| Window::whole(s.width, s.height)),
        started: std::time::Instant::now(),
    };

    let opts = RenderOptions {
        threads: args.threads,
        slice,
        schedule: args.schedule,
        passes: args.passes,
        resume_from,
        packets: args.packets,
        window,
        aovs: !args.aov.is_empty(),
        timeline: timeline.clone(),
        budget: args.time,
        cpu_times: false,
    };
    let mut failed = (false, false);
    let checkpoints = each_pass(|film, done| {
        if let (Some(ck), Some(header)) = (&args.checkpoint, &header) {
            let h = PartialHeader {
                samples: full.start..done,
                ..header.clone()
            };
            if let Err(e) = write_partial(ck, &h, film) {
                warn_once(&mut failed.0, ck, &format!("cannot write checkpoint: {e}"));
            }
        }
        if args.progressive && done < full.end {
            if let Err(e) = image.write(film, None, done - full.start) {
                warn_once(&mut failed.1, &args.output, &e);
            }
        }
    });
    let outcome = render(
        &scene,
        &opts,
        Some(initial),
        (RenderBar::new(args.quiet), checkpoints),
    );
    super::warn(&outcome.warnings);
    let output_start = timeline.as_deref().map(Timeline::now);
    if let (true, Some(header)) = (partial_output, &header) {
        write_partial(&args.output, header, &outcome.film)
            .map_err(|e| InputError::file(&args.output, format!("cannot write: {e}")))?;
    } else {
        // The samples the image holds: fewer than asked where a time
        // budget ended the render.
        let held = outcome.done.clamp(full.start, full.end) - full.start;
        image
            .write(&outcome.film, outcome.aov.as_deref(), held)
            .map_err(|e| InputError::file(&args.output, e))?;
    }
    if let (Some(budget), false) = (args.time, args.quiet) {
        let s = &scene.settings;
        let reached = outcome.done;
        let ended = if reached < full.end && outcome.stopped {
            "the budget ended it"
        } else {
            "it finished within the budget"
        };
        println!(
            "time budget {budget} s: {reached} of {} samples per pixel reached in {:.2} s ({ended})",
            s.spp, outcome.seconds
        );
    }
    if let (Some(t), Some(start)) = (&timeline, output_start) {
        t.phase(Phase::Output, start, t.now());
    }
    if let (Some(path), Some(t)) = (&args.timeline, &timeline) {
        let name = format!("strata render {scene_name}");
        strata::output::atomic::write_bytes_atomic(path, t.to_chrome_json(&name).as_bytes())
            .map_err(|e| InputError::file(path, format!("cannot write: {e}")))?;
    }
    // The statistics (the run's peak memory read among them) only where
    // something shows them.
    if shows_figures(&args) {
        let mut stats = RenderStats::new(&scene_name, &scene, &timings, &opts, &outcome);
        stats.timeline = timeline.as_deref().and_then(Timeline::summary);
        if let Some(path) = &args.stats {
            strata::output::atomic::write_bytes_atomic(path, stats.to_json().as_bytes())
                .map_err(|e| InputError::file(path, format!("cannot write: {e}")))?;
        }
        if !args.quiet {
            println!("{}", stats.summary(&args.output));
            if let (Some(path), Some(summary)) = (&args.timeline, &stats.timeline) {
                print!("timeline -> {}\n{}", path.display(), summary.text());
            }
        }
    }
    // The process ends with this command: its memory goes back with it,
    // without each of the scene's arrays freed first (unmapping a huge
    // mesh's gigabyte page by page took a tenth of a second).
    std::mem::forget(scene);
    Ok(())
}

/// Whether the run shows its figures (the summary line, or `--stats`):
/// else it measures none of what only they show (the load's and the
/// run's memory peaks).
fn shows_figures(args: &RenderArgs) -> bool {
    !args.quiet || args.stats.is_some()
}

/// Whether a render of a `width` × `height` window, with the AOVs and
/// output that `args` ask for, fits in this machine's memory.
fn check_image_memory(args: &RenderArgs, width: u32, height: u32) -> Result<(), String> {
    let image = !is_partial_path(&args.output);
    strata::render::film::check_memory(width, height, !args.aov.is_empty(), image)
}

/// An error about the image's size, naming where the size came from: the
/// crop, the flags or `--set` edits that gave a side, or else the scene
/// file's `[render]` keys at their line (or the model file, whose scene
/// strata made).
fn image_size_error(args: &RenderArgs, message: String) -> InputError {
    use strata::scene::parse::within;
    if let Some(crop) = &args.crop {
        return InputError::flag(format!("--crop {crop}"), message);
    }
    let mut given = Vec::new();
    let mut written = Vec::new();
    for (field, flag) in [
        ("width", args.settings.width),
        ("height", args.settings.height),
    ] {
        let key = format!("render.{field}");
        let edit = args
            .set
            .iter()
            .rev()
            .find(|e| within(&key, &e.path) || within(&e.path, &key));
        match (flag, edit) {
            (Some(v), _) => given.push(format!("--{field} {v}")),
            (None, Some(e)) => given.push(e.written()),
            (None, None) => written.push(key),
        }
    }
    if !given.is_empty() {
        return InputError::flag(given.join(" "), message);
    }
    let path = args.scene.as_deref();
    if path.is_some_and(is_model_path) {
        return InputError::file(path.unwrap_or(std::path::Path::new("")), message);
    }
    let text = match path {
        Some(p) => std::fs::read_to_string(p).unwrap_or_default(),
        None => SEED_SCENE.to_string(),
    };
    let map = strata::scene::source_map::SourceMap::new(&text);
    let written: Vec<String> = written.into_iter().filter(|k| map.contains(k)).collect();
    let line = written.first().and_then(|k| map.line_of(k));
    InputError::new(scene_name(path), written.join(", "), message).on_line(line)
}

/// Warn about `path` the first time only.
fn warn_once(warned: &mut bool, path: &std::path::Path, message: &str) {
    if !*warned {
        super::warn([format_args!("{}: {message}", path.display())]);
        *warned = true;
    }
}

/// Writes the render's image: PNG, or EXR with the camera and the render's
/// settings in its header and a crop placed in the whole image.
struct Output<'a> {
    args: &'a RenderArgs,
    scene: &'a Scene,
    window: Window,
    started: std::time::Instant,
}

impl Output<'_> {
    /// The image of `film`, which holds `spp` samples per pixel, with the
    /// AOVs of `aov`.
    fn write(&self, film: &Film, aov: Option<&[AovSum]>, spp: u32) -> Result<(), String> {
        let mut pixels = film.to_rgb();
        let (w, h) = (self.window.width(), self.window.height());
        let s = &self.scene.settings;
        if ImageFormat::from_path(&self.args.output) != Some(ImageFormat::Exr) {
            strata::output::tonemap::apply(&mut pixels, s.exposure, s.tonemap);
            return write_image(&self.args.output, &pixels, w, h);
        }
        let camera = &self.scene.camera;
        let mut exr = ExrImage::rgb(&pixels, w, h);
        if let Some(sums) = aov {
            exr.channels.extend(aov::channels(sums, &self.args.aov));
        }
        exr.origin = (self.window.x.start, self.window.y.start);
        exr.display = (s.width, s.height);
        exr.attributes = vec![
            // OpenEXR's standard camera attributes (row-vector matrices, which
            // are glam's column-major arrays).
            (
                "worldToCamera".into(),
                Attribute::Matrix(camera.world_to_camera().to_cols_array()),
            ),
            (
                "worldToNDC".into(),
                Attribute::Matrix(camera.world_to_ndc().to_cols_array()),
            ),
            ("spp".into(), Attribute::Int(spp as i32)),
            // A double holds every u32 seed exactly.
            ("seed".into(), Attribute::Double(s.seed as f64)),
            ("sampler".into(), Attribute::Text(s.sampler.name().into())),
            (
                "renderTimeSeconds".into(),
                Attribute::Float(self.started.elapsed().as_secs_f32()),
            ),
            (
                "strataVersion".into(),
                Attribute::Text(strata::VERSION.into()),
            ),
        ];
        exr.write(&self.args.output)
    }
}

/// Everything about the command line that can be wrong, checked before any
/// work: the slice, and every file the render will write (extension,
/// directory, permission). Returns the slice and whether the output is a
/// `.strata` part.
fn check_outputs(args: &RenderArgs) -> Result<(SliceSpec, bool), CliError> {
    let flag = |name: &'static str| move |e: String| InputError::new("<command line>", name, e);
    super::writable(&args.output, "--output", &["png", "exr", "strata"])?;
    let partial_output = is_partial_path(&args.output);
    // Parsed here, not by clap, so that a bad value is one line like every other input error.
    let slice = match &args.slice {
        None => SliceSpec::WHOLE,
        Some(text) => text.parse::<SliceSpec>().map_err(flag("--slice"))?,
    };
    if let Some(noise) = args.settings.noise {
        if slice.count > 1 {
            return Err(flag("--slice")(format!(
                "--noise {noise} decides per pixel from all of its samples so far, which a slice's process does not have: render with --noise in one process (--checkpoint lets it stop and resume), or give slices a fixed --spp"
            ))
            .into());
        }
        if let Some(p) = args.passes {
            return Err(flag("--passes")(format!(
                "--passes {p} with --noise {noise}: a noise target's passes are its decision points (after 4, 8, 12, 16, … samples); leave --passes out"
            ))
            .into());
        }
    }
    if let Some(t) = args.time {
        if partial_output {
            return Err(flag("--time")(format!(
                "a .strata part holds every sample of its slice, which a budget of {t} s need not reach: write .png or .exr (--checkpoint keeps the film to continue)"
            ))
            .into());
        }
        if args.passes.is_some() {
            return Err(flag("--passes")(
                "--time renders passes of 4, 8, 12, 16, … samples until the budget is spent; leave --passes out".into(),
            )
            .into());
        }
    }
    if slice.count > 1 && !partial_output {
        return Err(flag("--slice")(format!(
            "slice {}/{} is a partial render: write it to a .strata file (-o part_{}.strata) and combine the parts with `strata merge`",
            slice.index, slice.count, slice.index
        ))
        .into());
    }
    if let Some(path) = &args.stats {
        super::writable(path, "--stats", &["json"])?;
    }
    let model = args.scene.as_deref().is_some_and(is_model_path);
    for (given, name) in [
        (args.camera.is_some(), "--camera"),
        (args.save_scene.is_some(), "--save-scene"),
    ] {
        if given && !model {
            return Err(flag(name)(model::ONLY_FOR_A_MODEL.into()).into());
        }
    }
    if let Some(path) = &args.save_scene {
        super::writable(path, "--save-scene", &["toml"])?;
    }
    if let Some(path) = &args.timeline {
        super::writable(path, "--timeline", &["json"])?;
    }
    // Not the checkpoint: a slice's part may be its own checkpoint
    // (`--checkpoint part_3.strata --resume -o part_3.strata`,
    // docs/distributed.md), the finished part replacing the last pass's.
    super::distinct_files(&[
        ("--output", Some(&args.output)),
        ("--stats", args.stats.as_deref()),
        ("--save-scene", args.save_scene.as_deref()),
        ("--timeline", args.timeline.as_deref()),
    ])?;
    if partial_output || args.checkpoint.is_some() {
        // A part or a checkpoint holds whole images' sums, to be merged.
        if args.crop.is_some() {
            return Err(flag("--crop")(
                "a crop is an image: write it to .png or .exr, without --slice or --checkpoint"
                    .into(),
            )
            .into());
        }
    }
    if !args.aov.is_empty() {
        let twice = (1..args.aov.len()).find(|&i| args.aov[..i].contains(&args.aov[i]));
        if let Some(a) = twice.map(|i| args.aov[i]) {
            return Err(flag("--aov")(format!(
                "{} is named twice: each AOV is one set of channels",
                a.name()
            ))
            .into());
        }
        if ImageFormat::from_path(&args.output) != Some(ImageFormat::Exr) {
            return Err(
                flag("--aov")("AOVs are EXR channels: write the output to .exr".into()).into(),
            );
        }
        if args.checkpoint.is_some() {
            return Err(flag("--aov")(
                "a checkpoint keeps no AOVs: render them without --checkpoint".into(),
            )
            .into());
        }
    }
    if args.progressive && partial_output {
        return Err(flag("--progressive")(
            "rewrites an image after every pass: write a .png or .exr".into(),
        )
        .into());
    }
    if let Some(ck) = &args.checkpoint {
        super::writable(ck, "--checkpoint", &["strata"])?;
        if ck.exists() && !args.resume {
            let held = match read_partial(ck) {
                Ok(p) => format!(
                    "holds samples {}..{} of a render",
                    p.header.samples.start, p.header.samples.end
                ),
                Err(e) => format!("is not a checkpoint strata can read ({e})"),
            };
            return Err(InputError::file(
                ck,
                format!("already exists and {held}; add --resume to continue from it, or delete it to start over"),
            )
            .into());
        }
    }
    Ok((slice, partial_output))
}

/// The scene of the command line, loaded and its BVH built on `--threads`
/// threads as the render runs: a one-thread job (a Slurm task given one
/// CPU, a one-thread benchmark) stays on one core from start to end.
///
/// A load that takes more than a second shows what it is doing (reading,
/// building) on stderr until it ends, unless `--quiet`.
fn load(args: &RenderArgs) -> Result<(Scene, LoadTimings), CliError> {
    let progress = if shows_figures(args) {
        compile::LoadProgress::default()
    } else {
        compile::LoadProgress::unmetered()
    };
    let load = || match args.scene.as_deref() {
        Some(path) if is_model_path(path) => load_model(path, args, &progress),
        Some(path) => Ok(compile::load_edited_scene_with_progress(
            path,
            &args.set,
            &args.settings,
            args.bvh_quality,
            &progress,
        )?),
        None => load_or_seed(None, &args.set, &args.settings, args.bvh_quality),
    };
    std::thread::scope(|scope| {
        let shown = (!args.quiet).then(|| scope.spawn(|| super::progress::show_load(&progress)));
        let loaded = {
            // Finished however the load ends, a panic too: the display's
            // thread, which the scope waits for, then ends.
            let _finished = Finished(&progress);
            on_threads(args.threads, load)
        };
        if let Some(shown) = shown {
            shown.thread().unpark();
            // The display only draws: it cannot fail the load.
            let _ = shown.join();
        }
        loaded?
    })
}

/// The scene made around a model file (see `strata::scene::model`): its
/// notes said on stderr unless `--quiet`, saved first with `--save-scene`,
/// then compiled.
fn load_model(
    path: &std::path::Path,
    args: &RenderArgs,
    progress: &compile::LoadProgress,
) -> Result<(Scene, LoadTimings), CliError> {
    let start = std::time::Instant::now();
    let made = model::model_scene(path, &args.settings, &args.set, args.camera)?;
    if !args.quiet {
        for note in &made.notes {
            eprintln!("note: {note}");
        }
    }
    if let Some(save) = &args.save_scene {
        let text = made.save_text(save)?;
        strata::output::atomic::write_bytes_atomic(save, text.as_bytes()).map_err(|e| {
            InputError::new(
                "<command line>",
                "--save-scene",
                format!("cannot write {}: {e}", save.display()),
            )
        })?;
    }
    Ok(compile::compile_model(
        made,
        &args.settings,
        args.bvh_quality,
        start,
        progress,
    )?)
}

/// Finishes a load's progress when dropped.
struct Finished<'p>(&'p compile::LoadProgress);

impl Drop for Finished<'_> {
    fn drop(&mut self) {
        self.0.finish();
    }
}

/// `work` run on a worker of a pool of `threads` threads (0: the global
/// pool, one thread per core): the pool it is called on where that has as
/// many ([`is_current_pool`], [`on_current_pool`]).
fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> Result<T, CliError> {
    if is_current_pool(threads) {
        return Ok(on_current_pool(work));
    }
    Ok(super::thread_pool(threads)?.install(work))
}

/// The scene at `path`, or the built-in seed scene, with `edits` applied.
pub fn load_or_seed(
    path: Option<&std::path::Path>,
    edits: &[Edit],
    settings: &RenderOverrides,
    quality: BuildQuality,
) -> Result<(Scene, LoadTimings), CliError> {
    Ok(match path {
        Some(path) if is_model_path(path) => {
            model::load_model_file(path, edits, settings, quality, None)?
        }
        Some(path) => load_edited_scene(path, edits, settings, quality)?,
        None => {
            let start = std::time::Instant::now();
            let path = std::path::Path::new(SEED_SCENE_NAME);
            let desc = parse::parse_edited(path, SEED_SCENE, edits)?;
            compile::compile(&desc, path, settings, quality, start)?
        }
    })
}

/// How a scene is named in messages: its path, or the built-in seed.
pub fn scene_name(path: Option<&std::path::Path>) -> String {
    path.map_or(SEED_SCENE_NAME.to_string(), |p| p.display().to_string())
}

/// The film and sample to start from: an existing checkpoint's with
/// --resume, else none.
fn resume(
    args: &RenderArgs,
    header: &PartialHeader,
) -> Result<(Option<Film>, Option<u32>), CliError> {
    let (Some(ck), true) = (&args.checkpoint, args.resume) else {
        return Ok((None, None));
    };
    if !ck.exists() {
        if !args.quiet {
            eprintln!(
                "no checkpoint at {} yet; starting from the first sample",
                ck.display()
            );
        }
        return Ok((None, None));
    }
    let part = read_partial(ck).map_err(|e| InputError::file(ck, e))?;
    let done = part
        .header
        .resume_point(header, args.force)
        .map_err(|e| InputError::file(ck, e))?;
    if !args.quiet {
        let full = &header.samples;
        eprintln!(
            "resuming from {}: samples {}..{} of {}..{} done",
            ck.display(),
            full.start,
            done,
            full.start,
            full.end
        );
    }
    Ok((Some(part.film), Some(done)))
}

/// A duration: `30s`, `2m`, `1.5h`, `250ms`, or a number of seconds.
fn parse_duration(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (number, unit) = match t.find(|c: char| c.is_ascii_alphabetic()) {
        Some(i) => t.split_at(i),
        None => (t, "s"),
    };
    let scale = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        other => {
            return Err(format!(
                "unknown unit '{other}': use ms, s, m or h, as in 30s"
            ))
        }
    };
    match number.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v * scale),
        _ => Err(format!(
            "'{text}' is not a duration above 0, such as 30s or 2m"
        )),
    }
}

/// Whether `path` names a partial render (`.strata`).
pub fn is_partial_path(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("strata"))
}

#[cfg(test)]
mod tests {
    use super::on_threads;

    /// `--threads N` bounds the load and the build as it bounds the
    /// render: the work runs on a pool of exactly N threads, and 0 keeps
    /// the global pool.
    #[test]
    fn loading_runs_on_the_requested_threads() {
        for n in [1, 3] {
            assert!(matches!(on_threads(n, rayon::current_num_threads), Ok(m) if m == n));
        }
        let global = rayon::current_num_threads();
        assert!(matches!(on_threads(0, rayon::current_num_threads), Ok(m) if m == global));
    }
}

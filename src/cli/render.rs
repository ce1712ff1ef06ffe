//! `strata render`.

use super::CliError;
use clap::Args;
use std::path::PathBuf;
use strata::error::InputError;
use strata::output::image::write_image;
use strata::output::stats::{peak_rss_bytes, PhaseTimes, RenderStats};
use strata::render::{render, RenderOptions, Schedule, SliceSpec};
use strata::sampling::SamplerKind;
use strata::scene::{load_scene, RenderOverrides};

#[derive(Debug, Args, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML). Default: scenes/seed.toml.
    pub scene: Option<PathBuf>,
    /// Output image: .png (sRGB, 8-bit) or .exr (linear float).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Image width in pixels (overrides [render] width).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (overrides [render] height).
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera samples per pixel: antialiasing and, for a thin lens, aperture samples.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Shadow rays per area light per hit.
    #[arg(long)]
    pub shadow_samples: Option<u32>,
    /// Rays per glossy reflection (at the first glossy hit; deeper hits trace one).
    #[arg(long)]
    pub reflection_samples: Option<u32>,
    /// Maximum reflection/refraction depth.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// random | stratified (correlated multi-jittered, any sample count).
    #[arg(long)]
    pub sampler: Option<SamplerKind>,
    /// solid_angle (default: spherical rectangles, sphere cones) | area.
    #[arg(long)]
    pub light_sampling: Option<strata::shade::light::LightSampling>,
    /// lobe (default: importance-sample the cosⁿ lobe) | uniform (hemisphere; a baseline).
    #[arg(long)]
    pub glossy_sampling: Option<strata::shade::integrator::GlossySampling>,
    /// Seed of every random number: same seed, same image.
    #[arg(long)]
    pub seed: Option<u32>,
    /// Worker threads (default: all cores). The image is identical for any count.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Render only slice k of P of every pixel's samples (0-based k), e.g. 3/8.
    #[arg(long)]
    pub slice: Option<SliceSpec>,
    /// slices (default, work stealing over sample slices) | regions (static bands, a baseline).
    #[arg(long, default_value = "slices")]
    pub schedule: Schedule,
    /// BVH build effort: fastest | fast | auto | medium | high.
    #[arg(long, default_value = "auto")]
    pub bvh_quality: strata::accel::BuildQuality,
    /// Write statistics (rays by kind, Mrays/s, phase times, peak RSS) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Replay one sample (pixel x, y and sample index) and print its path instead of rendering.
    #[arg(long, value_name = "X,Y,SAMPLE")]
    pub debug_sample: Option<strata::render::debug::SampleId>,
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
    if strata::output::image::ImageFormat::from_path(&args.output).is_none() {
        return Err(
            InputError::new("<command line>", "--output", "must end in .png or .exr").into(),
        );
    }
    let overrides = RenderOverrides {
        width: args.width,
        height: args.height,
        spp: args.spp,
        shadow_samples: args.shadow_samples,
        reflection_samples: args.reflection_samples,
        max_depth: args.max_depth,
        sampler: args.sampler,
        seed: args.seed,
        light_sampling: args.light_sampling,
        glossy_sampling: args.glossy_sampling,
        bvh_quality: args.bvh_quality,
    };
    let (scene, timings) = load_scene(&scene_path, &overrides)?;
    if let Some(id) = args.debug_sample {
        let (value, events) = strata::render::debug::replay(&scene, id)
            .map_err(|e| InputError::new("<command line>", "--debug-sample", e))?;
        print!("{}", strata::render::debug::describe(id, value, &events));
        return Ok(());
    }
    let opts = RenderOptions {
        threads: args.threads,
        slice: args.slice.unwrap_or(SliceSpec::WHOLE),
        schedule: args.schedule,
        quiet: args.quiet,
        ..RenderOptions::default()
    };
    let outcome = render(&scene, &opts, None, |_, _| {});
    let s = &scene.settings;
    write_image(&args.output, &outcome.film.to_rgb(), s.width, s.height)
        .map_err(|e| InputError::file(&args.output, e))?;

    let total = outcome.counts.total();
    let mrays = total as f64 / outcome.seconds.max(1e-9) / 1e6;
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
    if let Some(path) = &args.stats {
        let stats = RenderStats {
            scene: scene_path.display().to_string(),
            width: s.width,
            height: s.height,
            spp: s.spp,
            samples_rendered: [outcome.samples.start, outcome.samples.end],
            sampler: format!("{:?}", s.sampler).to_lowercase(),
            seed: s.seed,
            threads: outcome.threads,
            schedule: format!("{:?}", opts.schedule).to_lowercase(),
            slice: format!("{}/{}", opts.slice.index, opts.slice.count),
            rays: outcome.counts,
            rays_total: total,
            mrays_per_s: mrays,
            time: PhaseTimes {
                load_s: timings.load.as_secs_f64(),
                bvh_build_s: timings.bvh_build.as_secs_f64(),
                render_s: outcome.seconds,
            },
            triangles: scene.triangle_count as usize,
            analytic_shapes: scene.shapes.len(),
            planes: scene.planes.len(),
            bvh_nodes: scene.bvh.nodes.len(),
            bvh_bytes: scene.bvh.memory_bytes(),
            peak_rss_bytes: peak_rss_bytes(),
            invalid_samples: outcome.film.invalid,
            first_invalid_sample: outcome.film.first_invalid,
            clamped_samples: outcome.film.clamped,
        };
        let json =
            serde_json::to_string_pretty(&stats).map_err(|e| CliError::Internal(e.to_string()))?;
        strata::output::atomic::write_bytes_atomic(path, json.as_bytes())
            .map_err(|e| InputError::file(path, format!("cannot write: {e}")))?;
    }
    if !args.quiet {
        println!(
            "{}x{} {} spp: {:.2} M rays ({:.2} camera, {:.2} shadow, {:.2} reflection, {:.2} refraction) in {:.2} s = {:.2} Mrays/s on {} threads (load {:.2} s, BVH {:.2} s) -> {}",
            s.width,
            s.height,
            s.spp,
            total as f64 / 1e6,
            outcome.counts.camera as f64 / 1e6,
            outcome.counts.shadow as f64 / 1e6,
            outcome.counts.reflection as f64 / 1e6,
            outcome.counts.refraction as f64 / 1e6,
            outcome.seconds,
            mrays,
            outcome.threads,
            timings.load.as_secs_f64(),
            timings.bvh_build.as_secs_f64(),
            args.output.display()
        );
    }
    Ok(())
}

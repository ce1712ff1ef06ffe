//! Render settings, declared once. [`RenderOverrides`] is one layer of
//! them, every value optional: the scene file's `[render]` table is one
//! layer, the command line another (its flags are these fields, and their
//! `--help` is these doc comments). [`RenderSettings::merge`] lays them
//! over the defaults, file first, so the command line wins. Python's
//! `strata_rt.render` takes them as keywords of the same names, which
//! tests/suite/python_settings.rs holds to these fields.
//!
//! ```toml
//! [render]
//! width = 640            # pixels, default 640
//! height = 480           # default 480
//! spp = 1                # camera (pixel and lens) samples per pixel
//! shadow_samples = 1     # samples per area light per hit
//! reflection_samples = 1 # rays per glossy hit (the first on a path)
//! max_depth = 5          # reflection and refraction depth
//! sampler = "stratified" # or "random"
//! seed = 0
//! background = [0.0, 0.0, 0.0]   # radiance of rays that hit nothing
//! light_sampling = "solid_angle" # or "area", or "auto" (the path integrator's default)
//! glossy_sampling = "lobe"       # or "uniform"
//! noise = 0.02           # adaptive: samples where the noise is, to this target (spp the ceiling)
//! exposure = 0.0         # stops, for 8-bit outputs (and the noise target's floor)
//! tonemap = "clamp"      # or "filmic", for 8-bit outputs
//! integrator = "distribution"    # or "path": light past the first bounce
//! ```

use crate::error::{InputError, COMMAND_LINE};
use crate::light::LightSampling;
use crate::output::tonemap::Tonemap;
use crate::sampling::SamplerKind;
use glam::Vec3;
use serde::Deserialize;

crate::mode::mode_enum! {
    /// How fuzzy reflections pick directions. `lobe` importance-samples the
    /// cosⁿ lobe; `uniform` samples the hemisphere uniformly (a baseline for
    /// `strata converge` and the variance tests).
    #[derive(Default)]
    pub enum GlossySampling("glossy sampling") {
        #[default]
        Lobe = "lobe",
        Uniform = "uniform",
    }
}

crate::mode::mode_enum! {
    /// Which light transport a render computes. `distribution`: the seed's
    /// distribution ray tracer (direct light from the scene's lights,
    /// mirrors, glass and glossy reflection; no indirect diffuse light).
    /// `path`: a unidirectional path tracer with next-event estimation
    /// (all light transport from the lights and glowing surfaces).
    #[derive(Default)]
    pub enum IntegratorKind("integrator") {
        #[default]
        Distribution = "distribution" | "whitted",
        Path = "path",
    }
}

/// One layer of render settings: the scene file's `[render]` table, or the
/// command line. Absent values fall through to the layer below.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, clap::Args)]
#[serde(deny_unknown_fields)]
pub struct RenderOverrides {
    /// Image width in pixels [scene file: render.width; default 640]
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [scene file: render.height; default 480]
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera samples per pixel: antialiasing and, for a thin lens, aperture
    /// samples [render.spp; default 1]
    #[arg(long)]
    pub spp: Option<u32>,
    /// Shadow rays per area light per hit [render.shadow_samples; default 1]
    #[arg(long)]
    pub shadow_samples: Option<u32>,
    /// Rays per glossy reflection, at the first glossy hit of a path (deeper
    /// hits trace one) [render.reflection_samples; default 1]
    #[arg(long)]
    pub reflection_samples: Option<u32>,
    /// Maximum reflection and refraction depth, at most 256 [render.max_depth;
    /// default 5]
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// stratified: correlated multi-jittered sets of any sample count;
    /// sobol: an Owen-scrambled Sobol sequence, stratified at every
    /// power-of-two prefix; random: independent numbers, a baseline
    /// [render.sampler; default stratified, sobol with --noise or --time]
    #[arg(long)]
    pub sampler: Option<SamplerKind>,
    /// Seed of every random number: same seed, same image [render.seed; default 0]
    #[arg(long)]
    pub seed: Option<u32>,
    /// Radiance of rays that hit nothing, as R,G,B, or one number for a grey
    /// [render.background; default 0,0,0]
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb)]
    #[serde(default, deserialize_with = "super::description::optional_colour")]
    pub background: Option<[f32; 3]>,
    /// solid_angle: spherical rectangles and sphere cones where possible;
    /// area: uniform over the light's surface; auto: as solid_angle, but a
    /// rect light that looks small from the point (under 0.1 sr) by area
    /// [render.light_sampling; default solid_angle, auto under the path
    /// integrator]
    #[arg(long)]
    pub light_sampling: Option<LightSampling>,
    /// lobe: importance-sample the cosⁿ lobe; uniform: the hemisphere, a
    /// baseline [render.glossy_sampling; default lobe]
    #[arg(long)]
    pub glossy_sampling: Option<GlossySampling>,
    /// Adaptive sampling: each pixel takes s/E² samples, s the estimated
    /// standard deviation of its samples' luminance (Neyman's allocation,
    /// which gives the least image error for the samples), and goes on
    /// while any of its 3x3 neighbours does; the image's RMSE is then
    /// about E times the root of the mean s. Judged at pass boundaries
    /// (after 4, 8, 12, 16, 24, … samples); --spp is the ceiling (default
    /// 1024 with --noise).
    /// See docs/cli.md, "Noise target". The image is the same for any
    /// thread count, crop, checkpoint and resume [render.noise; default
    /// none: every pixel takes spp samples]
    #[arg(long, value_name = "E")]
    pub noise: Option<f32>,
    /// Exposure in stops for 8-bit outputs (PNG): +1 doubles every value
    /// before the tone curve; EXR stays linear. The noise target judges
    /// what this shows [render.exposure; default 0]
    #[arg(long, value_name = "STOPS")]
    pub exposure: Option<f32>,
    /// Tone curve of 8-bit outputs: clamp clips values above 1; filmic is
    /// the same below 0.6 and rolls highlights off above, reaching white
    /// only past 32 [render.tonemap; default clamp]
    #[arg(long)]
    pub tonemap: Option<Tonemap>,
    /// Light transport: distribution is the seed's ray tracer (direct
    /// light, mirrors, glass; no light past the first diffuse bounce);
    /// path traces paths of any length with next-event estimation, so
    /// light bounces off walls and glowing surfaces light the room
    /// (docs/scene-format.md) [render.integrator; default distribution
    /// for scene files, path for model files]
    #[arg(long)]
    pub integrator: Option<IntegratorKind>,
}

/// `r,g,b` as three numbers, or one number for a grey, as in the scene file.
fn parse_rgb(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let number = |s: &str| {
        s.parse::<f32>()
            .map_err(|_| format!("'{s}' is not a number"))
    };
    match parts[..] {
        [r, g, b] => Ok([number(r)?, number(g)?, number(b)?]),
        [grey] => Ok([number(grey)?; 3]),
        _ => Err(format!("'{text}' is not three numbers R,G,B or one")),
    }
}

/// Render settings after the scene file and the command line are merged.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub shadow_samples: u32,
    pub reflection_samples: u32,
    pub max_depth: u32,
    pub sampler: SamplerKind,
    pub seed: u32,
    pub background: Vec3,
    pub light_sampling: LightSampling,
    pub glossy_sampling: GlossySampling,
    /// The error each pixel stops at (`render::adaptive`); `None`
    /// renders every pixel's `spp` samples.
    pub noise: Option<f32>,
    /// Stops: 8-bit outputs show radiance times 2^exposure.
    pub exposure: f32,
    pub tonemap: Tonemap,
    pub integrator: IntegratorKind,
}

/// Samples every pixel of a `--noise` render takes before the first
/// decision (`render::adaptive::FIRST_DECISION`, where it is explained).
pub const NOISE_FIRST_DECISION: u32 = 4;

/// The low end of a noise render's expected samples
/// ([`RenderSettings::estimated_spp`]): 8, as when the first decision
/// came after 8 samples and the estimate was measured against the
/// dragon's renders; the earlier first decision stops only cheap pixels
/// sooner, which changes the rays a tree is built for little.
pub const NOISE_ESTIMATE_LOW: u32 = 8;

/// The ceiling of a `--noise` render's samples when no layer gives `spp`.
pub const NOISE_SPP: u32 = 1024;

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            spp: 1,
            shadow_samples: 1,
            reflection_samples: 1,
            max_depth: 5,
            sampler: SamplerKind::default(),
            seed: 0,
            background: Vec3::ZERO,
            light_sampling: LightSampling::default(),
            glossy_sampling: GlossySampling::default(),
            noise: None,
            exposure: 0.0,
            tonemap: Tonemap::default(),
            integrator: IntegratorKind::default(),
        }
    }
}

impl RenderSettings {
    /// The rays a render traces at its first hits: a camera ray per
    /// sample, and per hit one shadow ray per point or directional light
    /// and `shadow_samples` per area light. Reflected, refracted and
    /// deeper rays come on top, so this is a lower bound, for choosing how
    /// much effort a BVH build is worth.
    pub fn first_hit_rays(&self, lights: &[crate::light::Light]) -> u64 {
        let shadow: u64 = lights
            .iter()
            .map(|l| {
                if l.is_area() {
                    self.shadow_samples as u64
                } else {
                    1
                }
            })
            .sum();
        let samples = self.width as u64 * self.height as u64 * self.estimated_spp() as u64;
        samples.saturating_mul(1 + shadow)
    }

    /// The samples per pixel a render is expected to take: `spp`, or
    /// under a noise target, which stops most pixels long before its
    /// ceiling, the geometric mean of [`NOISE_ESTIMATE_LOW`] and the
    /// ceiling (91 of 1024): the dragon under an area light took 18 to 59
    /// a pixel at targets 0.1 to 0.05, and a tree built for 1024 cost
    /// twice the build time for no faster a render (docs/performance.md).
    pub fn estimated_spp(&self) -> u32 {
        match self.noise {
            Some(_) => {
                let geometric = ((NOISE_ESTIMATE_LOW as f64) * self.spp as f64).sqrt();
                (geometric.round() as u32).clamp(self.spp.min(NOISE_ESTIMATE_LOW), self.spp)
            }
            None => self.spp,
        }
    }
}

/// The largest image side and sample count a render accepts.
pub const MAX_SIDE: u32 = 1 << 15;
pub const MAX_SPP: u32 = 1 << 22;

/// What to add to a message about `x` where it is infinite: a number
/// written past float32's range (`1e40`) reads as inf, which the user
/// never wrote.
pub fn past_float32(x: f32) -> &'static str {
    if x.is_infinite() {
        " (inf, or a number written past ±3.4e38, float32's largest)"
    } else {
        ""
    }
}

/// Most bounces `max_depth` allows. The distribution integrator recurses
/// once a reflection or refraction (about 1.4 KB of stack a level), so
/// two facing mirrors at a depth of 1,500 overflowed a worker's 2 MiB
/// stack and aborted the process. 256 leaves a fivefold margin there,
/// and is far past the depths scenes use (at most 8 in the repository's;
/// pbrt-v4's default is 5).
pub const MAX_DEPTH: u32 = 256;

/// A value of one layer of settings that no render can use.
#[derive(Debug, Clone, PartialEq)]
pub struct Unusable {
    /// The `[render]` key: `spp`.
    pub field: &'static str,
    /// The value as the command line writes it: `0`, `0.1,0.1,0.1`.
    pub value: String,
    pub message: String,
}

impl Unusable {
    /// The flag with its value, `--spp 0`: where a command-line value came from.
    pub fn flag(&self) -> String {
        format!("--{} {}", self.field.replace('_', "-"), self.value)
    }

    /// The scene file's key path, `render.spp`.
    pub fn key(&self) -> String {
        format!("render.{}", self.field)
    }

    /// The `--set` edit that gives it, `render.spp=0`.
    pub fn edit(&self) -> String {
        format!("{}={}", self.key(), self.value)
    }

    /// The error of a command-line flag: `<command line>: --spp 0: must be at least 1`.
    pub fn on_command_line(&self) -> InputError {
        InputError::new(COMMAND_LINE, self.flag(), &self.message)
    }
}

impl RenderOverrides {
    /// The first value this layer gives that no render can use.
    pub fn check(&self) -> Result<(), Unusable> {
        let bad = |field: &'static str, value: String, message: String| {
            Err(Unusable {
                field,
                value,
                message,
            })
        };
        for (value, field) in [
            (self.width, "width"),
            (self.height, "height"),
            (self.spp, "spp"),
            (self.shadow_samples, "shadow_samples"),
            (self.reflection_samples, "reflection_samples"),
        ] {
            if value == Some(0) {
                return bad(field, "0".into(), "must be at least 1".into());
            }
        }
        for (value, field) in [(self.width, "width"), (self.height, "height")] {
            if let Some(v) = value.filter(|&v| v > MAX_SIDE) {
                let message = format!("image larger than {MAX_SIDE} pixels on a side");
                return bad(field, v.to_string(), message);
            }
        }
        if let Some(v) = self.max_depth.filter(|&v| v > MAX_DEPTH) {
            return bad(
                "max_depth",
                v.to_string(),
                format!("at most {MAX_DEPTH} bounces"),
            );
        }
        if let Some(v) = self.spp.filter(|&v| v > MAX_SPP) {
            return bad(
                "spp",
                v.to_string(),
                format!("more than {MAX_SPP} samples per pixel"),
            );
        }
        if let Some(e) = self.noise.filter(|e| !(e.is_finite() && *e > 0.0)) {
            let message =
                "must be an error above 0, such as 0.02 (2% where the luminance is 1)".to_string();
            return bad("noise", e.to_string(), message + past_float32(e));
        }
        if let Some(e) = self
            .exposure
            .filter(|e| !(e.is_finite() && e.abs() <= 64.0))
        {
            let message = "must be a number of stops between -64 and 64".to_string();
            return bad("exposure", e.to_string(), message + past_float32(e));
        }
        if let Some(c) = self.background {
            if !c.iter().all(|x| x.is_finite() && *x >= 0.0) {
                let message = "must be finite and not negative".to_string();
                return bad("background", rgb_text(c), message);
            }
        }
        Ok(())
    }
}

/// A colour as `--background` takes it: `0.1,0.2,0.3`, or `0.1` for a grey.
pub fn rgb_text(c: [f32; 3]) -> String {
    if c[0].to_bits() == c[1].to_bits() && c[1].to_bits() == c[2].to_bits() {
        return c[0].to_string();
    }
    format!("{},{},{}", c[0], c[1], c[2])
}

impl RenderSettings {
    /// The defaults with each layer laid over them in turn (the scene file,
    /// then the command line): a value a later layer gives wins. Check each
    /// layer with [`RenderOverrides::check`] first.
    pub fn merge(layers: &[&RenderOverrides]) -> Self {
        let mut s = Self::default();
        let (mut spp_given, mut sampler_given, mut light_sampling_given) = (false, false, false);
        for layer in layers {
            let RenderOverrides {
                width,
                height,
                spp,
                shadow_samples,
                reflection_samples,
                max_depth,
                sampler,
                seed,
                background,
                light_sampling,
                glossy_sampling,
                noise,
                exposure,
                tonemap,
                integrator,
            } = **layer;
            spp_given |= spp.is_some();
            sampler_given |= sampler.is_some();
            light_sampling_given |= light_sampling.is_some();
            s.width = width.unwrap_or(s.width);
            s.height = height.unwrap_or(s.height);
            s.spp = spp.unwrap_or(s.spp);
            s.shadow_samples = shadow_samples.unwrap_or(s.shadow_samples);
            s.reflection_samples = reflection_samples.unwrap_or(s.reflection_samples);
            s.max_depth = max_depth.unwrap_or(s.max_depth);
            s.sampler = sampler.unwrap_or(s.sampler);
            s.seed = seed.unwrap_or(s.seed);
            s.background = background.map_or(s.background, Vec3::from);
            s.light_sampling = light_sampling.unwrap_or(s.light_sampling);
            s.glossy_sampling = glossy_sampling.unwrap_or(s.glossy_sampling);
            s.noise = noise.or(s.noise);
            s.exposure = exposure.unwrap_or(s.exposure);
            s.tonemap = tonemap.unwrap_or(s.tonemap);
            s.integrator = integrator.unwrap_or(s.integrator);
        }
        if s.noise.is_some() && !spp_given {
            s.spp = NOISE_SPP;
        }
        // A pixel of a noise target may stop after any pass: the sequence
        // that is stratified at every power-of-two prefix serves it as one
        // set (`sampling::sobol`), where the multi-jittered sets would need
        // a set per pass (docs/converge.md measures the difference).
        if s.noise.is_some() && !sampler_given {
            s.sampler = SamplerKind::Sobol;
        }
        // Spherical rectangles where a rect light looks large, area where it
        // looks small: nearly the same noise for less work there (cornell
        // 7 to 8% faster for 0.4% more RMSE; docs/mitsuba.md, "Rect lights
        // by area where they look small").
        // The seed's integrator keeps solid_angle, so that its scenes
        // render as they always have.
        if s.integrator == IntegratorKind::Path && !light_sampling_given {
            s.light_sampling = LightSampling::Auto;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A render's expected samples: its count, or under a noise target the
    /// geometric mean of 8 and the ceiling, never past the ceiling; the
    /// rays auto's tree is chosen for follow it.
    #[test]
    fn a_noise_render_is_expected_to_stop_between_8_samples_and_its_ceiling() {
        let mut s = RenderSettings {
            spp: 1024,
            ..RenderSettings::default()
        };
        assert_eq!(s.estimated_spp(), 1024);
        let uniform = s.first_hit_rays(&[]);
        s.noise = Some(0.05);
        assert_eq!(s.estimated_spp(), 91);
        assert_eq!(s.first_hit_rays(&[]) * 1024, uniform * 91);
        for (spp, expected) in [(16, 11), (8, 8), (4, 4), (1, 1)] {
            s.spp = spp;
            assert_eq!(s.estimated_spp(), expected, "spp {spp}");
        }
    }

    /// A noise target draws from the Sobol sequence unless a layer names
    /// a sampler.
    #[test]
    fn a_noise_target_samples_sobol_unless_a_sampler_is_given() {
        let noise = RenderOverrides {
            noise: Some(0.05),
            ..Default::default()
        };
        assert_eq!(RenderSettings::merge(&[&noise]).sampler, SamplerKind::Sobol);
        assert_eq!(RenderSettings::merge(&[]).sampler, SamplerKind::Stratified);
        let stratified = RenderOverrides {
            sampler: Some(SamplerKind::Stratified),
            ..Default::default()
        };
        for layers in [[&stratified, &noise], [&noise, &stratified]] {
            assert_eq!(
                RenderSettings::merge(&layers).sampler,
                SamplerKind::Stratified
            );
        }
    }

    /// The path integrator samples rect lights by `auto` unless a layer
    /// names a method; the seed's integrator keeps `solid_angle`.
    #[test]
    fn the_path_integrator_samples_lights_by_auto_unless_a_method_is_given() {
        let path = RenderOverrides {
            integrator: Some(IntegratorKind::Path),
            ..Default::default()
        };
        let light = |layers: &[&RenderOverrides]| RenderSettings::merge(layers).light_sampling;
        assert_eq!(light(&[&path]), LightSampling::Auto);
        assert_eq!(light(&[]), LightSampling::SolidAngle);
        for method in [LightSampling::Area, LightSampling::SolidAngle] {
            let given = RenderOverrides {
                light_sampling: Some(method),
                ..Default::default()
            };
            assert_eq!(light(&[&given, &path]), method);
            assert_eq!(light(&[&path, &given]), method);
        }
    }

    #[test]
    fn later_layers_win_and_absent_values_fall_through() {
        let file = RenderOverrides {
            width: Some(320),
            spp: Some(16),
            sampler: Some(SamplerKind::Random),
            ..Default::default()
        };
        let cli = RenderOverrides {
            spp: Some(4),
            background: Some([0.5, 0.25, 0.0]),
            ..Default::default()
        };
        let s = RenderSettings::merge(&[&file, &cli]);
        assert_eq!((s.width, s.height, s.spp), (320, 480, 4));
        assert_eq!(s.sampler, SamplerKind::Random);
        assert_eq!(s.background, Vec3::new(0.5, 0.25, 0.0));
        assert_eq!(RenderSettings::merge(&[]), RenderSettings::default());
    }

    #[test]
    fn check_names_the_first_unusable_value() {
        let zero = RenderOverrides {
            shadow_samples: Some(0),
            ..Default::default()
        };
        let e = zero.check().unwrap_err();
        assert_eq!(
            (e.flag(), e.edit()),
            (
                "--shadow-samples 0".into(),
                "render.shadow_samples=0".into()
            )
        );
        let huge = RenderOverrides {
            height: Some(MAX_SIDE + 1),
            ..Default::default()
        };
        assert_eq!(huge.check().unwrap_err().flag(), "--height 32769");
        let nan = RenderOverrides {
            background: Some([0.0, f32::NAN, 0.0]),
            ..Default::default()
        };
        let e = nan.check().unwrap_err();
        assert_eq!((e.field, e.value.as_str()), ("background", "0,NaN,0"));
        assert!(RenderOverrides::default().check().is_ok());
    }

    #[test]
    fn colours_parse_from_the_command_line() {
        assert_eq!(parse_rgb("1, 0.5,0"), Ok([1.0, 0.5, 0.0]));
        assert_eq!(parse_rgb("0.25"), Ok([0.25; 3]));
        assert!(parse_rgb("1,2").is_err());
        assert!(parse_rgb("a,b,c").is_err());
    }
}

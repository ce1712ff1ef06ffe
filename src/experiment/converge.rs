//! Error against time: render at spp 1, 2, 4, … for each sampling method
//! and measure RMSE against a reference (pbrt-v4 logs the same per pass
//! with `--mse-reference-image`); and, with noise targets, the adaptive
//! method (`render::adaptive`) beside them, with the time the best
//! uniform method takes to the same RMSE.

use crate::light::LightSampling;
use crate::output::chart::{log_log_slope, Panel, Series};
use crate::render::{render, Observer, RenderOptions};
use crate::sampling::SamplerKind;
use crate::scene::settings::GlossySampling;
use crate::scene::Scene;
use glam::Vec3;

/// One sampling configuration compared by `strata converge`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Method {
    pub name: &'static str,
    pub sampler: SamplerKind,
    pub light: LightSampling,
    pub glossy: GlossySampling,
}

/// Random; stratified; stratified plus importance sampling (lobe-sampled
/// glossy rays, solid-angle light samples); the same with area light
/// sampling, to isolate what solid-angle sampling buys; and importance
/// sampling drawn from the Sobol sequence, the adaptive method's own
/// sampling at a fixed count, so that what a noise target saves is
/// measured against the best uniform setting, its own included.
pub const METHODS: [Method; 5] = [
    Method {
        name: "random",
        sampler: SamplerKind::Random,
        light: LightSampling::Area,
        glossy: GlossySampling::Uniform,
    },
    Method {
        name: "stratified",
        sampler: SamplerKind::Stratified,
        light: LightSampling::Area,
        glossy: GlossySampling::Uniform,
    },
    Method {
        name: "stratified+is",
        sampler: SamplerKind::Stratified,
        light: LightSampling::SolidAngle,
        glossy: GlossySampling::Lobe,
    },
    Method {
        name: "stratified+is/area-lights",
        sampler: SamplerKind::Stratified,
        light: LightSampling::Area,
        glossy: GlossySampling::Lobe,
    },
    Method {
        name: "sobol+is",
        sampler: SamplerKind::Sobol,
        light: LightSampling::SolidAngle,
        glossy: GlossySampling::Lobe,
    },
];

/// `strata converge`'s default largest sample count and reference sample
/// count: 16 times apart, so the reference's own noise stays below the
/// curves, and small enough that the default run is a quick look (the
/// timing is in docs/converge.md); pass
/// larger ones for a chart to keep.
pub const DEFAULT_MAX_SPP: u32 = 64;
pub const DEFAULT_REFERENCE_SPP: u32 = 1024;

/// The best method, used for references.
pub const REFERENCE_METHOD: Method = METHODS[2];

#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub method: &'static str,
    /// Samples per pixel: the ceiling of an adaptive render.
    pub spp: u32,
    /// An adaptive render's noise target.
    pub noise: Option<f32>,
    /// Samples per pixel on average over the image.
    pub mean_spp: f64,
    pub seconds: f64,
    pub rmse: f64,
    pub rel_mse: f64,
}

/// RMSE and relative MSE (mean of (x − r)² / (r² + 0.01), per channel).
pub fn image_error(image: &[Vec3], reference: &[Vec3]) -> (f64, f64) {
    assert_eq!(image.len(), reference.len());
    let mut se = 0.0f64;
    let mut rel = 0.0f64;
    for (x, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let d = (x[c] - r[c]) as f64;
            se += d * d;
            rel += d * d / ((r[c] as f64).powi(2) + 0.01);
        }
    }
    let n = (image.len() * 3) as f64;
    ((se / n).sqrt(), rel / n)
}

/// The scene with one method's sampling and a sample count.
pub fn configured(scene: &Scene, method: &Method, spp: u32) -> Scene {
    let mut s = scene.clone();
    s.settings.sampler = method.sampler;
    s.settings.light_sampling = method.light;
    s.settings.glossy_sampling = method.glossy;
    s.settings.spp = spp;
    s
}

/// Render a reference image with the best method, telling `observer` how it goes.
pub fn reference(scene: &Scene, spp: u32, threads: usize, observer: impl Observer) -> Vec<Vec3> {
    let s = configured(scene, &REFERENCE_METHOD, spp);
    let opts = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    render(&s, &opts, None, observer).film.to_rgb()
}

/// Measure every method at spp 1, 2, 4, … `max_spp`, calling `on_point` as
/// results arrive. Each render is repeated `repeats` times and the median
/// time kept: the image is the same every time (same seed), the time is not.
pub fn measure(
    scene: &Scene,
    reference: &[Vec3],
    methods: &[Method],
    max_spp: u32,
    threads: usize,
    repeats: u32,
    mut on_point: impl FnMut(&Point),
) -> Vec<Point> {
    let mut points = Vec::new();
    for method in methods {
        let mut spp = 1;
        while spp <= max_spp {
            let s = configured(scene, method, spp);
            let opts = RenderOptions {
                threads,
                passes: Some(1),
                ..RenderOptions::default()
            };
            let mut times = Vec::new();
            let mut image = Vec::new();
            for _ in 0..repeats.max(1) {
                let outcome = render(&s, &opts, None, ());
                times.push(outcome.seconds);
                image = outcome.film.to_rgb();
            }
            times.sort_by(f64::total_cmp);
            let (rmse, rel_mse) = image_error(&image, reference);
            let p = Point {
                method: method.name,
                spp,
                noise: None,
                mean_spp: spp as f64,
                seconds: times[times.len() / 2],
                rmse,
                rel_mse,
            };
            on_point(&p);
            points.push(p);
            spp *= 2;
        }
    }
    points
}

/// The adaptive method's name in tables, CSV and charts: the reference
/// method's importance sampling with a noise target, `spp` the ceiling,
/// drawing from the Sobol sequence as `--noise` does by default.
pub const ADAPTIVE: &str = "adaptive";

/// Measure the adaptive method at each noise target of `targets` with
/// `ceiling` samples per pixel at most, as [`measure`] does the others.
pub fn measure_adaptive(
    scene: &Scene,
    reference: &[Vec3],
    targets: &[f32],
    ceiling: u32,
    threads: usize,
    repeats: u32,
    mut on_point: impl FnMut(&Point),
) -> Vec<Point> {
    let mut points = Vec::new();
    for &noise in targets {
        let mut s = configured(scene, &REFERENCE_METHOD, ceiling);
        s.settings.noise = Some(noise);
        // The sampler a noise target draws from by default.
        s.settings.sampler = SamplerKind::Sobol;
        let opts = RenderOptions {
            threads,
            ..RenderOptions::default()
        };
        let mut times = Vec::new();
        let mut film = None;
        for _ in 0..repeats.max(1) {
            let outcome = render(&s, &opts, None, ());
            times.push(outcome.seconds);
            film = Some(outcome.film);
        }
        let film = film.expect("at least one render");
        times.sort_by(f64::total_cmp);
        let (rmse, rel_mse) = image_error(&film.to_rgb(), reference);
        let p = Point {
            method: ADAPTIVE,
            spp: ceiling,
            noise: Some(noise),
            mean_spp: film.mean_samples(),
            seconds: times[times.len() / 2],
            rmse,
            rel_mse,
        };
        on_point(&p);
        points.push(p);
    }
    points
}

/// The least time any uniform method of `points` takes to `rmse`, and
/// which method: each method's (time, RMSE) points joined by straight
/// lines on log-log axes, read where they cross `rmse`; `None` where no
/// method's points reach down to it.
pub fn uniform_time_at(points: &[Point], rmse: f64) -> Option<(f64, &'static str)> {
    let mut best: Option<(f64, &'static str)> = None;
    for m in METHODS {
        let pts: Vec<&Point> = points
            .iter()
            .filter(|p| p.method == m.name && p.noise.is_none())
            .collect();
        for pair in pts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (hi, lo) = (a.rmse.max(b.rmse), a.rmse.min(b.rmse));
            if !(lo <= rmse && rmse <= hi) || hi == lo {
                continue;
            }
            let t = (rmse.ln() - a.rmse.ln()) / (b.rmse.ln() - a.rmse.ln());
            let seconds = (a.seconds.ln() + t * (b.seconds.ln() - a.seconds.ln())).exp();
            if best.is_none_or(|(s, _)| seconds < s) {
                best = Some((seconds, m.name));
            }
        }
    }
    best
}

/// The chart `strata converge` draws: RMSE against time and against spp,
/// log-log, a line per method (in `METHODS` order) labelled with its slope
/// against spp.
pub fn chart_panels(title: &str, points: &[Point]) -> Vec<Panel> {
    let mut by_time = Vec::new();
    let mut by_spp = Vec::new();
    for m in METHODS {
        let pts: Vec<&Point> = points.iter().filter(|p| p.method == m.name).collect();
        let spp_pts: Vec<(f64, f64)> = pts.iter().map(|p| (p.spp as f64, p.rmse)).collect();
        let slope = log_log_slope(&spp_pts).map_or("n/a".to_string(), |s| format!("{s:.2}"));
        let label = format!("{} (slope {slope})", m.name);
        by_time.push(Series::new(
            label.clone(),
            pts.iter().map(|p| (p.seconds, p.rmse)).collect(),
        ));
        by_spp.push(Series::new(label, spp_pts));
    }
    let adaptive: Vec<&Point> = points.iter().filter(|p| p.noise.is_some()).collect();
    if !adaptive.is_empty() {
        let label = format!("{ADAPTIVE} (noise targets, mean spp)");
        by_time.push(Series::new(
            label.clone(),
            adaptive.iter().map(|p| (p.seconds, p.rmse)).collect(),
        ));
        by_spp.push(Series::new(
            label,
            adaptive.iter().map(|p| (p.mean_spp, p.rmse)).collect(),
        ));
    }
    vec![
        Panel {
            title: format!("{title}: RMSE against time"),
            x_label: "seconds".into(),
            y_label: "RMSE".into(),
            log_x: true,
            log_y: true,
            integer_x: false,
            series: by_time,
        },
        Panel {
            title: format!("{title}: RMSE against samples per pixel"),
            x_label: "spp".into(),
            y_label: "RMSE".into(),
            log_x: true,
            log_y: true,
            integer_x: true,
            series: by_spp,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::chart::{legend_text, same_as};

    #[test]
    fn error_is_zero_for_identical_images_and_scales_with_the_difference() {
        let r = vec![Vec3::splat(0.5); 10];
        assert_eq!(image_error(&r, &r), (0.0, 0.0));
        let x: Vec<Vec3> = r.iter().map(|v| *v + Vec3::splat(0.1)).collect();
        let (rmse, _) = image_error(&x, &r);
        assert!((rmse - 0.1).abs() < 1e-6);
    }

    #[test]
    fn chart_panels_plot_each_method_and_name_those_that_coincide() {
        // The fourth method's errors equal the second's (as on a scene
        // with nothing for its importance sampling to change), and the
        // fifth's the first's, at other times.
        let mut points = Vec::new();
        for (k, m) in METHODS.iter().enumerate() {
            let rmse_of = match k {
                3 => 1,
                4 => 0,
                _ => k,
            };
            for spp in [1u32, 2, 4, 8] {
                points.push(Point {
                    method: m.name,
                    spp,
                    noise: None,
                    mean_spp: spp as f64,
                    seconds: 0.01 * spp as f64 * (1.0 + k as f64),
                    rmse: 0.1 / (1.0 + rmse_of as f64) / (spp as f64).sqrt(),
                    rel_mse: 0.0,
                });
            }
        }
        let panels = chart_panels("scene.toml", &points);
        let (time, spp) = (&panels[0], &panels[1]);
        assert!(time.log_x && time.log_y && !time.integer_x);
        assert!(spp.log_x && spp.log_y && spp.integer_x);
        assert_eq!(spp.series.len(), METHODS.len());
        assert_eq!(spp.series[0].label, "random (slope -0.50)");
        assert_eq!(same_as(time), [None; 5], "times differ");
        let same = same_as(spp);
        assert_eq!(same, [None, None, None, Some(1), Some(0)]);
        assert_eq!(
            legend_text(spp, 3, &same),
            "stratified+is/area-lights (slope -0.50) (same as stratified (slope -0.50))"
        );
        // The stratified+is line crosses 0.1/3/2 = 0.0167 at spp 4, 0.12 s;
        // random (twice the error) reaches it only at 16 spp, off its
        // points; an error below every point has no uniform time.
        let (t, m) = uniform_time_at(&points, 0.1 / 3.0 / 2.0).unwrap();
        assert!((t - 0.12).abs() < 1e-9 && m == "stratified+is", "{t} {m}");
        assert_eq!(uniform_time_at(&points, 1e-4), None);
    }
}

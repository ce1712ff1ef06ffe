//! Monte Carlo estimators, checked statistically: unbiasedness against a
//! high-spp reference, convergence slopes, importance-sampling variance,
//! limits that must converge to the delta cases, and stability where the
//! methods fail.
//!
//! Each check renders a 1×1 image through a narrow camera aimed at the
//! region of interest (a penumbra, a glossy highlight, a defocused edge), so
//! the pixel value is the integral under test and thousands of independent
//! renders cost little.

use crate::common::scene;
use glam::Vec3;
use strata::light::LightSampling;
use strata::render::film::PixelSum;
use strata::render::schedule::render_pixel;
use strata::sampling::SamplerKind;
use strata::scene::settings::GlossySampling;
use strata::scene::Scene;
use strata::shade::Integrator;

#[derive(Debug, Clone, Copy)]
struct Method {
    name: &'static str,
    sampler: SamplerKind,
    light: LightSampling,
    glossy: GlossySampling,
}

const RANDOM: Method = Method {
    name: "random",
    sampler: SamplerKind::Random,
    light: LightSampling::Area,
    glossy: GlossySampling::Uniform,
};
const STRATIFIED: Method = Method {
    name: "stratified",
    sampler: SamplerKind::Stratified,
    light: LightSampling::Area,
    glossy: GlossySampling::Uniform,
};
const STRATIFIED_IS: Method = Method {
    name: "stratified+is",
    sampler: SamplerKind::Stratified,
    light: LightSampling::SolidAngle,
    glossy: GlossySampling::Lobe,
};
const STRATIFIED_IS_AREA: Method = Method {
    name: "stratified+is, area lights",
    sampler: SamplerKind::Stratified,
    light: LightSampling::Area,
    glossy: GlossySampling::Lobe,
};
const METHODS: [Method; 4] = [RANDOM, STRATIFIED, STRATIFIED_IS, STRATIFIED_IS_AREA];

/// The single pixel's value (first channel) for one seed and sample count.
fn pixel(scene: &Scene, m: Method, seed: u32, spp: u32) -> f64 {
    let mut s = scene.clone();
    s.settings.sampler = m.sampler;
    s.settings.light_sampling = m.light;
    s.settings.glossy_sampling = m.glossy;
    s.settings.seed = seed;
    s.settings.spp = spp;
    let mut integrator = Integrator::new(&s);
    let mut acc = PixelSum::default();
    render_pixel(&mut integrator, &s, 0, 0..spp, &mut acc);
    assert_eq!(acc.invalid, 0, "no NaN or infinite samples");
    acc.sum[0] as f64 / strata::render::film::FIXED_SCALE / acc.count as f64
}

fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A high-spp reference with its own standard error.
fn reference(scene: &Scene) -> (f64, f64) {
    let values: Vec<f64> = (0..16)
        .map(|seed| pixel(scene, STRATIFIED_IS, 1000 + seed, 4096))
        .collect();
    mean_and_se(&values)
}

/// A 1×1 camera looking at `target` from `from` with a tiny field of view.
fn spot(from: Vec3, target: Vec3) -> String {
    format!(
        "[render]\nwidth = 1\nheight = 1\nmax_depth = 3\n[camera]\nposition = {:?}\nlook_at = {:?}\nfov = 0.5\n",
        from.to_array(),
        target.to_array()
    )
}

const PENUMBRA_WORLD: &str = r#"
[materials.white]
diffuse = [0.8, 0.8, 0.8]
[[lights]]
type = "rect"
corner = [-0.5, 2.0, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
radiance = [4.0, 4.0, 4.0]
[[objects]]
plane = { normal = [0.0, 1.0, 0.0] }
material = "white"
[[objects]]
sphere = { center = [0.0, 0.8, 0.0], radius = 0.4 }
material = "white"
"#;

/// A floor point in the sphere's penumbra.
fn penumbra() -> Scene {
    scene(&format!(
        "{}{PENUMBRA_WORLD}",
        spot(Vec3::new(0.0, 3.0, 3.0), Vec3::new(0.55, 0.0, 0.0))
    ))
}

/// A glossy floor reflecting a bright sphere light and a dim wall.
fn glossy_highlight(exponent: f32) -> Scene {
    glossy_scene(exponent, 0.3)
}

/// The same with a light of radius `radius`: a big light keeps uniform
/// hemisphere sampling's estimate far enough from heavy-tailed for a
/// 64-seed z-test, so even the baseline can be checked for bias.
fn glossy_scene(exponent: f32, radius: f32) -> Scene {
    scene(&format!(
        "{}[materials.gloss]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 1.0\nglossiness = {exponent}\n\
         [materials.wall]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [0.3, 0.3, 0.3]\n\
         [[lights]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, -2.0]\nradius = {radius}\nradiance = [10.0, 10.0, 10.0]\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"gloss\"\n\
         [[objects]]\nplane = {{ point = [0.0, 0.0, -6.0], normal = [0.0, 0.0, 1.0] }}\nmaterial = \"wall\"\n",
        // Aim at the floor point that mirrors the light's centre, slightly off it.
        spot(Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.05, 0.0, 0.0))
    ))
}

/// The edge of an out-of-focus emitter seen through a thin lens.
fn defocused_edge() -> Scene {
    scene(
        "[render]\nwidth = 1\nheight = 1\n[camera]\ntype = \"thin_lens\"\nposition = [0.0, 0.0, 5.0]\nlook_at = [1.0, 0.0, 0.0]\n\
         fov = 0.5\naperture = 0.2\nfocus_distance = 2.0\n\
         [materials.glow]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\n\
         [[objects]]\nsphere = { center = [0.0, 0.0, 0.0], radius = 1.0 }\nmaterial = \"glow\"\n",
    )
}

#[test]
fn every_method_is_unbiased_on_penumbra_glossy_highlight_and_defocused_edge() {
    for (region, scene) in [
        ("penumbra", penumbra()),
        ("glossy", glossy_scene(20.0, 1.2)),
        ("defocus", defocused_edge()),
    ] {
        let (r, r_se) = reference(&scene);
        assert!(r > 0.01, "{region}: the reference sees light ({r})");
        for m in METHODS {
            for spp in [1u32, 2, 3, 7, 16, 32] {
                let values: Vec<f64> = (0..64).map(|seed| pixel(&scene, m, seed, spp)).collect();
                let (mean, se) = mean_and_se(&values);
                let z = (mean - r) / (se * se + r_se * r_se).sqrt().max(1e-12);
                assert!(
                    z.abs() < 4.0,
                    "{region} {} spp {spp}: mean {mean} vs reference {r} (z = {z:.2})",
                    m.name
                );
            }
        }
    }
}

/// Slope of log RMSE against log spp, over 4..1024.
fn convergence_slope(scene: &Scene, m: Method, reference: f64) -> f64 {
    let mut pts = Vec::new();
    for spp in [4u32, 16, 64, 256, 1024] {
        let mse = (0..48)
            .map(|seed| (pixel(scene, m, 5000 + seed, spp) - reference).powi(2))
            .sum::<f64>()
            / 48.0;
        pts.push(((spp as f64).ln(), 0.5 * mse.ln()));
    }
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn convergence_slopes_on_a_penumbra() {
    let scene = penumbra();
    let (r, _) = reference(&scene);
    let random = convergence_slope(&scene, RANDOM, r);
    let stratified = convergence_slope(&scene, STRATIFIED, r);
    eprintln!("penumbra RMSE slopes: random {random:.3}, stratified {stratified:.3}");
    assert!((random + 0.5).abs() <= 0.08, "random slope {random}");
    assert!(stratified < -0.65, "stratified slope {stratified}");
}

fn variance(scene: &Scene, m: Method, spp: u32) -> f64 {
    let values: Vec<f64> = (0..128)
        .map(|seed| pixel(scene, m, 9000 + seed, spp))
        .collect();
    let (_, se) = mean_and_se(&values);
    se * se * values.len() as f64
}

#[test]
fn importance_sampling_the_lobe_cuts_glossy_variance_at_least_fourfold() {
    for exponent in [10.0, 1000.0] {
        let scene = glossy_highlight(exponent);
        let uniform = variance(&scene, STRATIFIED, 4);
        let lobe = variance(
            &scene,
            Method {
                glossy: GlossySampling::Lobe,
                ..STRATIFIED
            },
            4,
        );
        eprintln!(
            "glossy n = {exponent}: variance uniform {uniform:.3e}, lobe {lobe:.3e}, ratio {:.1}",
            uniform / lobe
        );
        assert!(
            lobe <= uniform / 4.0,
            "n = {exponent}: lobe {lobe} vs uniform {uniform}"
        );
    }
}

#[test]
fn solid_angle_sampling_beats_area_sampling_near_a_large_light() {
    // A floor point right under a big, close rect light: area sampling's 1/r² blows up.
    let text = format!(
        "{}[materials.white]\ndiffuse = [0.8, 0.8, 0.8]\n[[lights]]\ntype = \"rect\"\ncorner = [-2.0, 0.2, -2.0]\n\
         edge_u = [4.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 4.0]\nradiance = [1.0, 1.0, 1.0]\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"white\"\n",
        spot(Vec3::new(0.0, 0.1, 0.5), Vec3::new(0.0, 0.0, 0.0))
    );
    let s = scene(&text);
    let area = variance(&s, STRATIFIED_IS_AREA, 4);
    let solid = variance(&s, STRATIFIED_IS, 4);
    eprintln!("close light: variance area {area:.3e}, solid angle {solid:.3e}");
    assert!(solid < area / 4.0, "solid angle {solid} vs area {area}");
}

#[test]
fn a_shrinking_rect_light_converges_to_the_point_light() {
    // One-sided Lambertian rect of area A and radiance L has on-axis intensity
    // L·A; under the light it must match a point light of that intensity.
    let size = 1e-3f32;
    let l = 1.0 / (size * size);
    let rect = format!(
        "{}[materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n[[lights]]\ntype = \"rect\"\ncorner = [{}, 2.0, {}]\n\
         edge_u = [{size}, 0.0, 0.0]\nedge_v = [0.0, 0.0, {size}]\nradiance = [{l}, {l}, {l}]\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"white\"\n",
        spot(Vec3::new(0.0, 3.0, 0.3), Vec3::new(0.0, 0.0, 0.0)),
        -size / 2.0,
        -size / 2.0
    );
    let point = format!(
        "{}[materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\n\
         intensity = [1.0, 1.0, 1.0]\n[[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"white\"\n",
        spot(Vec3::new(0.0, 3.0, 0.3), Vec3::new(0.0, 0.0, 0.0))
    );
    for m in [STRATIFIED_IS, STRATIFIED_IS_AREA] {
        let a = pixel(&scene(&rect), m, 1, 16);
        let p = pixel(&scene(&point), m, 1, 16);
        assert!(
            (a - p).abs() / p < 0.01,
            "{}: rect {a} vs point {p}",
            m.name
        );
    }
}

#[test]
fn a_shrinking_sphere_light_converges_to_the_point_light_of_equal_power() {
    // Equal power: Φ = 4π² r² L = 4π I, so I = π r² L, in every direction.
    let (r, l) = (1e-3f32, 1e6f32);
    let i = std::f32::consts::PI * r * r * l;
    for target in [
        Vec3::ZERO,
        Vec3::new(1.5, 0.0, -0.5),
        Vec3::new(-3.0, 0.0, 1.0),
    ] {
        let body = "[materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n[[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\nmaterial = \"white\"\n";
        let cam = spot(Vec3::new(0.0, 3.0, 3.0), target);
        let sphere = format!(
            "{cam}{body}[[lights]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = {r}\nradiance = [{l}, {l}, {l}]\n"
        );
        let point = format!("{cam}{body}[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [{i}, {i}, {i}]\n");
        // Area sampling wastes the hidden half of the sphere, so it needs more samples.
        for (m, spp) in [(STRATIFIED_IS, 16), (STRATIFIED_IS_AREA, 4096)] {
            let a = pixel(&scene(&sphere), m, 1, spp);
            let p = pixel(&scene(&point), m, 1, spp);
            assert!(
                (a - p).abs() / p < 0.01,
                "{} at {target}: sphere {a} vs point {p}",
                m.name
            );
        }
    }
}

#[test]
fn infinite_glossiness_converges_to_the_mirror_and_zero_aperture_to_the_pinhole() {
    let mirror = glossy_highlight(0.0);
    let sharp = glossy_highlight(1e7);
    let m = pixel(&mirror, STRATIFIED_IS, 3, 16);
    let g = pixel(&sharp, STRATIFIED_IS, 3, 16);
    assert!(
        (m - g).abs() <= 0.01 * m.max(0.01),
        "mirror {m} vs glossiness 1e7 {g}"
    );

    let body = "[render]\nwidth = 24\nheight = 16\nspp = 4\n[materials.glow]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\n\
        [[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"glow\"\n";
    let cam = |aperture: f32| {
        format!(
            "{body}[camera]\ntype = \"thin_lens\"\nposition = [0.5, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 30.0\naperture = {aperture}\nfocus_distance = 3.0\n"
        )
    };
    let pinhole = crate::common::render_rgb(&scene(&cam(0.0)), 1);
    let tiny = crate::common::render_rgb(&scene(&cam(1e-6)), 1);
    let diff: f32 = pinhole
        .iter()
        .zip(&tiny)
        .map(|(a, b)| (*a - *b).abs().x)
        .sum::<f32>()
        / pinhole.len() as f32;
    assert!(
        diff < 1e-3,
        "aperture 1e-6 vs pinhole: mean difference {diff}"
    );
}

/// Stability where methods fail: each case renders without NaN or
/// infinity (the `pixel` helper asserts it) and stays near its analytic value.
#[test]
fn stability_where_methods_fail() {
    // Glossiness 1 and 1e5, and grazing incidence with half the lobe below the surface.
    for exponent in [1.0f32, 1e5] {
        let s = glossy_highlight(exponent);
        let v = pixel(&s, STRATIFIED_IS, 1, 16);
        assert!(v.is_finite() && v >= 0.0);
    }
    let grazing = scene(&format!(
        "{}[materials.gloss]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 1.0\nglossiness = 5.0\n\
         [materials.sky]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"gloss\"\n\
         [[objects]]\nsphere = {{ radius = 100.0 }}\nmaterial = \"sky\"\n",
        spot(Vec3::new(0.0, 0.01, 10.0), Vec3::new(0.0, 0.0, 0.0))
    ));
    let mut s = grazing.clone();
    s.settings.spp = 256;
    let mut integrator = Integrator::new(&s);
    let mut acc = PixelSum::default();
    render_pixel(&mut integrator, &s, 0, 0..256, &mut acc);
    let rejected = integrator.counts.glossy_rejected;
    let v = acc.sum[0] as f64 / strata::render::film::FIXED_SCALE / acc.count as f64;
    eprintln!("grazing glossy: {rejected} of 256 lobe samples rejected, value {v:.3}");
    assert!(
        rejected > 64 && rejected < 230,
        "about half the lobe is below the surface: {rejected}"
    );
    assert!(v > 0.2 && v < 0.8, "the kept half sees the sky: {v}");
    assert_eq!(acc.invalid, 0);

    // A square light almost touching the floor: solid-angle sampling stays
    // exact where area sampling's 1/r² blows up. Exact irradiance under the
    // centre of a 2a × 2a square at height h: E = π L · 4 F(a/h, a/h), with F
    // the differential form factor to a rectangle seen from under its corner.
    let (h, a, l) = (1e-3f64, 0.5f64, 1.0f64);
    let f = |x: f64, y: f64| {
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    };
    let exact = std::f64::consts::PI * l * 4.0 * f(a / h, a / h);
    let light = strata::light::Light::Rect {
        rect: strata::shape::rect::Rect::new(
            Vec3::new(-a as f32, h as f32, -a as f32),
            Vec3::X * (2.0 * a as f32),
            Vec3::Z * (2.0 * a as f32),
        )
        .unwrap(),
        radiance: Vec3::splat(l as f32),
        prim: 0,
    };
    let estimate = |method: LightSampling, n: usize| {
        let mut e = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let u = glam::Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                if let Some(s) = light.sample(Vec3::ZERO, u, method) {
                    e += (s.weight.x * s.wi.y) as f64;
                }
            }
        }
        e / (n * n) as f64
    };
    for n in [4, 8, 16, 32, 64] {
        eprintln!(
            "n² = {}: solid {:.5} area {:.5}",
            n * n,
            estimate(LightSampling::SolidAngle, n),
            estimate(LightSampling::Area, n)
        );
    }
    let solid = estimate(LightSampling::SolidAngle, 16);
    let area = estimate(LightSampling::Area, 16);
    eprintln!("square light at height 1e-3, 256 samples: solid angle {solid:.4}, area {area:.4}, exact {exact:.4}");
    assert!(
        (solid - exact).abs() / exact < 0.01,
        "solid angle {solid} vs {exact}"
    );
    assert!(area.is_finite());

    // A tiny, very bright sphere light equals its point light (tested above at r = 1e-3);
    // here r = 1e-5 with radiance 1e10 must still give finite, matching values.
    let (r, l) = (1e-5f32, 1e10f32);
    let i = std::f32::consts::PI * r * r * l;
    let body = "[materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n[[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\nmaterial = \"white\"\n";
    let cam = spot(Vec3::new(0.0, 3.0, 3.0), Vec3::new(0.3, 0.0, 0.0));
    let a = pixel(
        &scene(&format!(
            "{cam}{body}[[lights]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = {r}\nradiance = [{l}, {l}, {l}]\n"
        )),
        STRATIFIED_IS,
        1,
        7,
    );
    let p = pixel(
        &scene(&format!("{cam}{body}[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [{i}, {i}, {i}]\n")),
        STRATIFIED_IS,
        1,
        7,
    );
    assert!(
        (a - p).abs() / p < 0.01,
        "tiny bright sphere {a} vs point {p}"
    );

    // A light seen only through a mirror: the pixel shows k_r · L_e.
    let through_mirror = scene(&format!(
        "{}[materials.mirror]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 0.75\n\
         [[lights]]\ntype = \"rect\"\ncorner = [-1.0, 2.0, -1.0]\nedge_u = [2.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 2.0]\nradiance = [3.0, 3.0, 3.0]\n\
         [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"mirror\"\n",
        // From below the light's level, looking down at the mirror floor under the light.
        // The view ray reflects off (0, 0, 0.3) into the light's interior, around z = −0.1.
        spot(Vec3::new(0.0, 1.0, 0.5), Vec3::new(0.0, 0.0, 0.3))
    ));
    let v = pixel(&through_mirror, STRATIFIED_IS, 1, 3);
    assert!((v - 2.25).abs() < 1e-4, "k_r · L_e = 2.25, got {v}");
}

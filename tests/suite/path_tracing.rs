//! The path integrator (`integrator = "path"`): analytic answers (white
//! furnaces, the bounce series inside a glowing sphere), glowing surfaces
//! against the lights they equal, `auto` light sampling against either
//! method it mixes, indirect light that the distribution integrator lacks
//! and that converges as 1/N, and images bit-identical across threads,
//! slices and noise targets.

use crate::common::films::{film_of, part, pixel_means};
use crate::common::scene;
use glam::Vec3;
use strata::partial::merge::{merge_partials, MergeRules};
use strata::render::SliceSpec;
use strata::scene::settings::IntegratorKind;
use strata::scene::Scene;

/// Each pixel's mean of `spp` samples of `scene` (one seed), linear RGB,
/// pixel by pixel, with no sample dropped as NaN.
fn pixels(scene: &Scene, seed: u32, spp: u32) -> Vec<Vec3> {
    pixel_means(scene, seed, spp)
}

fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A sphere of `material` filling a narrow camera's view under a constant
/// environment of radiance 0.5.
fn furnace(material: &str) -> Scene {
    scene(&format!(
        "[render]\nwidth = 6\nheight = 6\nintegrator = \"path\"\nmax_depth = 6\n\
         [camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 4.0\n\
         [materials.m]\n{material}\n\
         [[lights]]\ntype = \"environment\"\nradiance = [0.5, 0.5, 0.5]\n\
         [[objects]]\nsphere = {{ radius = 1.0 }}\nmaterial = \"m\"\n"
    ))
}

/// A convex Lambertian sphere of albedo a sees only the environment, so it
/// shows a·L: exactly, in every sample, since the light's cosine sampling
/// and the BSDF's share one density and MIS weights sum to 1. White, it
/// vanishes.
#[test]
fn a_lambertian_sphere_in_a_white_furnace_shows_its_albedo_times_the_light() {
    for albedo in [1.0f32, 0.5] {
        let s = furnace(&format!("diffuse = [{albedo}, {albedo}, {albedo}]"));
        for p in pixels(&s, 3, 4) {
            let want = 0.5 * albedo;
            assert!(
                (p - Vec3::splat(want)).abs().max_element() < 1e-4,
                "albedo {albedo}: {p}"
            );
        }
    }
}

/// Metallic-roughness spheres in the furnace: never brighter than the
/// light, and a smooth white metal (F0 = 1) all of it.
#[test]
fn metallic_roughness_spheres_in_a_white_furnace_reflect_at_most_the_light() {
    for (material, floor) in [
        (
            "base_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 0.05",
            0.98,
        ),
        (
            "base_color = [1.0, 1.0, 1.0]\nmetallic = 0.0\nroughness = 0.5",
            0.8,
        ),
        (
            "base_color = [1.0, 0.77, 0.34]\nmetallic = 1.0\nroughness = 0.4",
            0.3,
        ),
    ] {
        let s = furnace(material);
        let values: Vec<f64> = pixels(&s, 5, 64).iter().map(|p| p.x as f64 / 0.5).collect();
        let (mean, se) = mean_and_se(&values);
        assert!(
            mean <= 1.0 + 3.0 * se + 1e-3,
            "{material}: albedo {mean} ± {se}"
        );
        assert!(mean >= floor, "{material}: albedo {mean} ± {se}");
    }
}

/// Inside a closed sphere that glows with Le and reflects a, light that
/// reflects at most D + 1 times sums to Le (1 + a + … + a^(D+1)), the
/// series of `max_depth` D, Russian roulette or not.
#[test]
fn inside_a_glowing_sphere_the_bounces_sum_the_series() {
    let a = 0.6f64;
    for depth in [0u32, 1, 4] {
        let s = scene(&format!(
            "[render]\nwidth = 4\nheight = 4\nintegrator = \"path\"\nmax_depth = {depth}\n\
             [camera]\nposition = [0.0, 0.0, 0.5]\nlook_at = [0.0, 0.0, 0.0]\nfov = 60.0\n\
             [materials.glow]\ndiffuse = [{a}, {a}, {a}]\nemission = [1.0, 1.0, 1.0]\n\
             [[objects]]\nsphere = {{ radius = 2.0 }}\nmaterial = \"glow\"\n"
        ));
        assert_eq!(s.emitters.len(), 1, "the sphere is a light");
        let values: Vec<f64> = (0..8)
            .flat_map(|seed| pixels(&s, seed, 64))
            .map(|p| p.x as f64)
            .collect();
        let (mean, se) = mean_and_se(&values);
        let want: f64 = (0..=depth + 1).map(|k| a.powi(k as i32)).sum();
        assert!(
            (mean - want).abs() < 4.0 * se + 1e-3,
            "max_depth {depth}: {mean} ± {se}, want {want}"
        );
    }
}

/// A floor under an overhead square, once a rect light and once two
/// glowing triangles (or a sphere light and a glowing sphere): the same
/// light, so the same mean on the floor, which the camera sees from below
/// the square.
#[test]
fn glowing_surfaces_light_the_room_as_the_lights_they_equal() {
    let base = "[render]\nwidth = 8\nheight = 8\nintegrator = \"path\"\nmax_depth = 2\n\
        [camera]\nposition = [0.0, 0.8, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 30.0\n\
        [materials.glow]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [4.0, 4.0, 4.0]\n\
        [[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\n";
    let pairs = [
        (
            "[[lights]]\ntype = \"rect\"\ncorner = [-0.5, 1.5, -0.5]\nedge_u = [1.0, 0.0, 0.0]\n\
             edge_v = [0.0, 0.0, 1.0]\nradiance = [4.0, 4.0, 4.0]\n",
            // The square's two triangles, facing down (the light is one-sided).
            "[[objects]]\ntriangle = { v = [[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5]] }\n\
             material = \"glow\"\n\
             [[objects]]\ntriangle = { v = [[-0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]] }\n\
             material = \"glow\"\n",
        ),
        (
            "[[lights]]\ntype = \"sphere\"\ncenter = [0.3, 1.0, 0.0]\nradius = 0.3\nradiance = [4.0, 4.0, 4.0]\n",
            "[[objects]]\nsphere = { center = [0.3, 1.0, 0.0], radius = 0.3 }\nmaterial = \"glow\"\n",
        ),
    ];
    for (light, glowing) in pairs {
        let lit = scene(&format!("{base}{light}"));
        let glows = scene(&format!("{base}{glowing}"));
        assert!(!glows.emitters.is_empty());
        let floor = |s: &Scene| {
            let values: Vec<f64> = (0..6)
                .map(|seed| pixels(s, seed, 32).iter().map(|p| p.x as f64).sum::<f64>() / 64.0)
                .collect();
            mean_and_se(&values)
        };
        let (a, sa) = floor(&lit);
        let (b, sb) = floor(&glows);
        let se = (sa * sa + sb * sb).sqrt();
        assert!(a > 0.05, "the floor is lit: {a}");
        assert!(
            (a - b).abs() < 4.0 * se + 2e-3 * a,
            "light {a} ± {sa} vs glowing {b} ± {sb}"
        );
    }
}

/// `light_sampling = "auto"` (the path integrator's default) samples a
/// rect light by its spherical rectangle where it looks large and by its
/// area where it looks small, and weighs BSDF rays that hit the light by
/// the density of the method chosen at their origin: a floor under a low
/// square light, seen from the light's foot (large) to far off (small),
/// comes out as under either method alone, in the near and the far half
/// of the image alike. The renders share their random numbers, so each
/// seed's difference is compared with the spread of those differences.
/// (A glossy sphere under the light made the differences heavy-tailed:
/// with area sampling its highlight is found rarely and brightly.)
#[test]
fn auto_light_sampling_gives_the_image_of_either_method() {
    const SEEDS: u32 = 32;
    let text = |method: &str| {
        format!(
            "[render]\nwidth = 12\nheight = 8\nintegrator = \"path\"\nmax_depth = 2\n\
             light_sampling = \"{method}\"\n\
             [camera]\nposition = [0.0, 2.5, 1.5]\nlook_at = [0.0, 0.0, -1.0]\nfov = 40.0\n\
             [[lights]]\ntype = \"rect\"\ncorner = [-0.4, 0.8, -0.4]\nedge_u = [0.8, 0.0, 0.0]\n\
             edge_v = [0.0, 0.0, 0.8]\nradiance = [50.0, 50.0, 50.0]\n\
             [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\n"
        )
    };
    // Per seed, the mean of the top half of the image (the floor far off)
    // and of the bottom half (near the light's foot).
    let halves = |method: &str| -> Vec<[f64; 2]> {
        let s = scene(&text(method));
        (0..SEEDS)
            .map(|seed| {
                let p = pixels(&s, seed, 32);
                let mean = |rows: std::ops::Range<usize>| {
                    rows.flat_map(|y| (0..12).map(move |x| y * 12 + x))
                        .map(|i| p[i].x as f64)
                        .sum::<f64>()
                        / 48.0
                };
                [mean(0..4), mean(4..8)]
            })
            .collect()
    };
    let auto = halves("auto");
    for method in ["solid_angle", "area"] {
        let other = halves(method);
        for (h, half) in ["far", "near"].into_iter().enumerate() {
            let a = auto.iter().map(|m| m[h]).sum::<f64>() / SEEDS as f64;
            let differences: Vec<f64> = auto.iter().zip(&other).map(|(a, b)| a[h] - b[h]).collect();
            let (d, se) = mean_and_se(&differences);
            assert!(a > 0.01, "{half}: lit {a}");
            assert!(
                d.abs() < 4.0 * se + 1e-4 * a,
                "{half}: auto {a}, {method} differs by {d} ± {se}"
            );
        }
    }
}

/// A white box lit by a small square in its ceiling: the ceiling beside
/// the light sees no light directly.
const BOX: &str = "[render]\nwidth = 1\nheight = 1\nmax_depth = 6\n\
    [camera]\nposition = [0.6, 0.2, 0.6]\nlook_at = [0.6, 2.0, 0.6]\nup = [0.0, 0.0, -1.0]\nfov = 2.0\n\
    [materials.white]\ndiffuse = [0.75, 0.75, 0.75]\n\
    [materials.red]\ndiffuse = [0.7, 0.05, 0.05]\n\
    [[lights]]\ntype = \"rect\"\ncorner = [-0.25, 1.99, -0.25]\nedge_u = [0.5, 0.0, 0.0]\n\
    edge_v = [0.0, 0.0, 0.5]\nradiance = [15.0, 15.0, 15.0]\n\
    [[objects]]\nplane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [0.0, 2.0, 0.0], normal = [0.0, -1.0, 0.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [-1.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }\nmaterial = \"red\"\n\
    [[objects]]\nplane = { point = [1.0, 0.0, 0.0], normal = [-1.0, 0.0, 0.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [0.0, 0.0, -1.0], normal = [0.0, 0.0, 1.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [0.0, 0.0, 1.0], normal = [0.0, 0.0, -1.0] }\nmaterial = \"white\"\n";

fn ceiling(integrator: IntegratorKind, seed: u32, spp: u32) -> f64 {
    let mut s = scene(BOX);
    s.settings.integrator = integrator;
    pixels(&s, seed, spp)[0].x as f64
}

/// The distribution integrator leaves the ceiling black; the path
/// integrator lights it, and its error across seeds falls as 1/N.
#[test]
fn indirect_light_reaches_the_ceiling_and_converges_as_one_over_n() {
    assert_eq!(ceiling(IntegratorKind::Distribution, 1, 16), 0.0);
    let variance = |spp: u32| {
        let values: Vec<f64> = (0..40)
            .map(|seed| ceiling(IntegratorKind::Path, seed, spp))
            .collect();
        let (mean, se) = mean_and_se(&values);
        (mean, se * se * values.len() as f64)
    };
    let (m4, v4) = variance(4);
    let (m32, v32) = variance(32);
    assert!(m32 > 0.05, "the ceiling is lit: {m32}");
    assert!(
        (m4 - m32).abs() < 4.0 * (v4 / 40.0).sqrt(),
        "unbiased: {m4} vs {m32}"
    );
    // 8× the samples: the variance falls 8× for independent samples
    // (faster is stratification's gain); 4× allows for the noise of 40
    // estimates of each variance.
    assert!(v4 / v32 > 4.0, "variance {v4} at 4 spp, {v32} at 32 spp");
}

/// A glowing triangle, a gold sphere, glass and an environment, traced
/// by paths: every kind of vertex.
const BUSY: &str = "[render]\nwidth = 24\nheight = 18\nspp = 6\nintegrator = \"path\"\n\
    [camera]\nposition = [0.0, 1.0, 6.0]\nlook_at = [0.0, 0.5, 0.0]\n\
    [materials.glass]\ndiffuse = [0.0, 0.0, 0.0]\ntransparency = 1.0\nfresnel = true\n\
    [materials.gold]\nbase_color = [1.0, 0.77, 0.34]\nmetallic = 1.0\nroughness = 0.3\n\
    [materials.glow]\nemission = [3.0, 2.0, 1.0]\n\
    [[lights]]\ntype = \"point\"\nposition = [2.0, 5.0, 4.0]\nintensity = [20.0, 20.0, 20.0]\n\
    [[lights]]\ntype = \"environment\"\nradiance = [0.2, 0.3, 0.4]\n\
    [[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\n\
    [[objects]]\ntriangle = { v = [[-2.0, 0.1, -1.0], [-1.0, 2.0, -1.5], [-2.5, 2.0, -1.0]] }\nmaterial = \"glow\"\n\
    [[objects]]\nsphere = { center = [-0.8, 0.6, 0.0], radius = 0.6 }\nmaterial = \"glass\"\n\
    [[objects]]\nsphere = { center = [0.8, 0.6, -0.5], radius = 0.6 }\nmaterial = \"gold\"\n";

#[test]
fn paths_are_bit_identical_across_threads_slices_and_noise_targets() {
    let s = scene(BUSY);
    let whole = film_of(&s, SliceSpec::WHOLE, 1);
    assert!(whole.to_rgb().iter().any(|p| p.max_element() > 0.0));
    assert_eq!(whole, film_of(&s, SliceSpec::WHOLE, 3), "3 threads");
    for p in [2u32, 3] {
        let parts: Vec<_> = (0..p)
            .map(|k| part(&s, SliceSpec { index: k, count: p }, 1 + k as usize % 2))
            .collect();
        let rules = MergeRules {
            require_all: true,
            preview: false,
            force: false,
        };
        assert_eq!(
            merge_partials(parts, rules).unwrap().film,
            whole,
            "{p} slices"
        );
    }
    let mut noisy = s.clone();
    noisy.settings.noise = Some(0.1);
    noisy.settings.spp = 64;
    assert_eq!(
        film_of(&noisy, SliceSpec::WHOLE, 1),
        film_of(&noisy, SliceSpec::WHOLE, 3)
    );
}

/// A glowing mesh placed twice is stored once, as two instances, and is a
/// light like the same mesh read from two files (each baked into world
/// space): both put each placement's triangles in the glowing table, and
/// the floor under them is lit alike, within noise.
#[test]
fn an_instanced_glowing_mesh_lights_the_floor_as_the_same_mesh_baked() {
    let dir = crate::common::temp_dir("instanced-emitter");
    // A small glowing panel facing down (two-sided emission anyway).
    let panel = "mtllib panel.mtl\nv -0.3 -0.3 0\nv 0.3 -0.3 0\nv 0.3 0.3 0\nv -0.3 0.3 0\n\
                 usemtl glow\nf 1 4 3 2\n";
    for name in ["panel.obj", "panel-a.obj", "panel-b.obj"] {
        std::fs::write(dir.join(name), panel).unwrap();
    }
    std::fs::write(dir.join("panel.mtl"), "newmtl glow\nKd 0 0 0\nKe 6 5 4\n").unwrap();
    let scene_with = |a: &str, b: &str| {
        let toml = format!(
            r#"
[render]
width = 8
height = 6
spp = 64
integrator = "path"
max_depth = 2
[camera]
position = [0.0, -3.0, 2.5]
look_at = [0.0, 0.0, 0.0]
fov = 50.0
[materials.white]
diffuse = [0.8, 0.8, 0.8]
[[objects]]
plane = {{ normal = [0.0, 0.0, 1.0] }}
material = "white"
[[objects]]
mesh = "{a}"
transform = {{ translate = [-0.6, 0.0, 1.5], rotate = [0.0, 1.0, 0.0, 20.0] }}
[[objects]]
mesh = "{b}"
transform = {{ translate = [0.7, 0.2, 1.2] }}
"#
        );
        crate::common::scene_at(&toml, &dir.join("scene.toml"))
    };
    let instanced = scene_with("panel.obj", "panel.obj");
    let baked = scene_with("panel-a.obj", "panel-b.obj");
    assert_eq!(
        instanced.geometry.instances().len(),
        2,
        "placed twice: instances"
    );
    assert_eq!(baked.geometry.instances().len(), 0);
    assert_eq!(
        instanced.emitters.len(),
        4,
        "each placement's two triangles"
    );
    assert_eq!(baked.emitters.len(), 4);
    let mean = |s: &Scene, seed| {
        let p = pixels(s, seed, 64);
        p.iter().map(|c| c.x as f64).sum::<f64>() / p.len() as f64
    };
    let runs = |s: &Scene, first: u32| -> Vec<f64> {
        (first..first + 6).map(|seed| mean(s, seed)).collect()
    };
    let (a, sa) = mean_and_se(&runs(&instanced, 1));
    let (b, sb) = mean_and_se(&runs(&baked, 11));
    assert!(b > 0.05, "{b}");
    assert!(
        (a - b).abs() < 4.0 * (sa * sa + sb * sb).sqrt(),
        "instanced {a} ± {sa} vs baked {b} ± {sb}"
    );
}

/// A rect light sampled 3 times a vertex (its spherical rectangles built
/// in SIMD lanes, and skipped where a vertex is behind it), a glowing
/// sphere (the glowing surfaces as a source, each shadow ray skipping its
/// own primitive), a spot and a mirror, traced by paths deep enough for
/// Russian roulette.
const LIT: &str = "[render]\nwidth = 10\nheight = 8\nspp = 8\nshadow_samples = 3\n\
    integrator = \"path\"\nmax_depth = 7\n\
    [camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.8, 0.0]\n\
    [materials.white]\ndiffuse = [0.8, 0.8, 0.8]\n\
    [materials.mirror]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 1.0\n\
    [materials.glow]\nemission = [2.0, 3.0, 4.0]\n\
    [[lights]]\ntype = \"rect\"\ncorner = [-0.3, 2.0, -0.3]\nedge_u = [0.6, 0.0, 0.0]\n\
    edge_v = [0.0, 0.0, 0.6]\nradiance = [9.0, 8.0, 7.0]\n\
    [[lights]]\ntype = \"spot\"\nposition = [1.0, 1.5, 1.0]\ndirection = [-1.0, -1.0, -1.0]\n\
    intensity = [3.0, 3.0, 3.0]\ninner_angle = 20.0\nouter_angle = 40.0\n\
    [[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [0.0, 2.5, 0.0], normal = [0.0, -1.0, 0.0] }\nmaterial = \"white\"\n\
    [[objects]]\nplane = { point = [0.0, 0.0, -1.5], normal = [0.0, 0.0, 1.0] }\nmaterial = \"white\"\n\
    [[objects]]\nsphere = { center = [-0.6, 0.4, -0.3], radius = 0.4 }\nmaterial = \"mirror\"\n\
    [[objects]]\nsphere = { center = [0.7, 0.3, 0.2], radius = 0.15 }\nmaterial = \"glow\"\n";

/// A batch of paths (up to eight, bounce by bounce together: their rays
/// traced together, their light samples in SIMD lanes) brings back, bit
/// for bit, what each path traced alone brings, whichever samples share a
/// batch: one pixel's, or several pixels' (the batches of a pass of one
/// sample a pixel), with the AOVs of its first hits.
#[test]
fn a_batch_of_paths_brings_back_what_each_path_alone_does() {
    use strata::sampling::{Dim, PixelSampler};
    use strata::shade::{CameraSample, FirstHit, Integrator, SampleContext};
    for text in [BUSY, LIT] {
        let s = scene(text);
        let st = &s.settings;
        let mut samples = Vec::new();
        for pixel in 0..st.width * st.height {
            let sampler = PixelSampler::new(st.sampler, 11, pixel);
            let corner = glam::Vec2::new((pixel % st.width) as f32, (pixel / st.width) as f32);
            for i in 0..st.spp {
                let ctx = SampleContext::new(sampler, i, st.spp);
                let film = corner + sampler.get_2d(Dim::PIXEL, i, st.spp);
                samples.push(CameraSample { ctx, film });
            }
        }
        let mut alone = Integrator::new(&s);
        let one: Vec<(Vec3, FirstHit)> = samples
            .iter()
            .map(|c| {
                let (mut out, mut first) = ([Vec3::ZERO], [FirstHit::MISS]);
                alone.camera_batch(std::slice::from_ref(c), &mut out, Some(&mut first));
                (out[0], first[0])
            })
            .collect();
        assert!(one.iter().any(|(l, _)| l.max_element() > 0.0));
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        // Batches of one pixel's samples (8 and 8), then of samples across
        // pixels: every seventh sample (a permutation: no count here is a
        // multiple of 7), in batches of seven.
        let across: Vec<usize> = (0..samples.len()).map(|k| k * 7 % samples.len()).collect();
        for (order, size) in [((0..samples.len()).collect::<Vec<_>>(), 8), (across, 7)] {
            let mut batched = Integrator::new(&s);
            for chunk in order.chunks(size) {
                let batch: Vec<CameraSample> = chunk.iter().map(|&k| samples[k]).collect();
                let mut out = vec![Vec3::ZERO; batch.len()];
                let mut first = vec![FirstHit::MISS; batch.len()];
                batched.camera_batch(&batch, &mut out, Some(&mut first));
                for (j, &k) in chunk.iter().enumerate() {
                    assert_eq!(
                        bits(out[j]),
                        bits(one[k].0),
                        "sample {k} in a batch of {size}"
                    );
                    assert_eq!(first[j], one[k].1, "sample {k}'s first hit");
                }
            }
            assert_eq!(batched.counts, alone.counts, "the same rays");
        }
    }
}

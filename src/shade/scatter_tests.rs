//! The path integrator's BSDFs held to what a BSDF must be: reciprocal,
//! never reflecting more than arrives (a white furnace per material, and
//! exactly all of it where nothing is absorbed), and drawn with the
//! density they report.

use super::scatter::Bsdf;
use crate::material::Material;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Materials that cover every lobe: Lambert, the Phong highlight, fuzzy
/// and mirror reflection, glass, weights summing past 1, and the
/// metallic-roughness model from a mirror-like metal to a rough dielectric.
fn materials() -> Vec<(&'static str, Material)> {
    let phong = |diffuse: f32, specular: f32, shininess: f32, kr: f32, gloss: f32| Material {
        diffuse: Vec3::splat(diffuse),
        specular: Vec3::splat(specular),
        shininess,
        reflectivity: kr,
        glossiness: gloss,
        ..Material::default()
    };
    vec![
        ("white lambert", phong(1.0, 0.0, 0.0, 0.0, 0.0)),
        ("grey lambert", Material::default()),
        ("plastic", phong(0.6, 0.3, 40.0, 0.0, 0.0)),
        ("glossy", phong(0.2, 0.0, 0.0, 0.7, 200.0)),
        ("overcommitted", phong(0.9, 0.5, 10.0, 0.5, 0.0)),
        (
            "glass",
            Material {
                diffuse: Vec3::ZERO,
                transparency: 1.0,
                fresnel: true,
                ..Material::default()
            },
        ),
        (
            "smooth gold",
            Material::metallic_roughness(Vec3::new(1.0, 0.77, 0.34), 1.0, 0.05, Vec3::ZERO),
        ),
        (
            "white metal",
            Material::metallic_roughness(Vec3::ONE, 1.0, 0.02, Vec3::ZERO),
        ),
        (
            "rough metal",
            Material::metallic_roughness(Vec3::ONE, 1.0, 0.8, Vec3::ZERO),
        ),
        (
            "rough plastic",
            Material::metallic_roughness(Vec3::ONE, 0.0, 0.6, Vec3::ZERO),
        ),
        (
            "half metal",
            Material::metallic_roughness(Vec3::splat(0.9), 0.5, 0.3, Vec3::ZERO),
        ),
    ]
}

fn bsdf(m: &Material, wo: Vec3) -> Bsdf {
    Bsdf::new(m, Vec3::ONE, wo, Vec3::Z, Vec3::Z, true)
}

/// A view at `theta` degrees from the normal.
fn view(theta: f32) -> Vec3 {
    let t = theta.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

/// xorshift: the tests' own reproducible numbers.
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// ∫ f(wo, wi) cos θ_i dωi, estimated from `n²` of the BSDF's own samples.
fn albedo(b: &Bsdf, n: u32, rng: &mut Numbers) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new(
                (i as f32 + rng.next()) / n as f32,
                (j as f32 + rng.next()) / n as f32,
            );
            if let Some(s) = b.sample(rng.next(), u) {
                sum += s.weight;
            }
        }
    }
    sum / (n * n) as f32
}

#[test]
fn every_material_reflects_at_most_what_arrives_and_lossless_ones_all_of_it() {
    let mut rng = Numbers(0x9e37_79b9_7f4a_7c15);
    for (name, m) in materials() {
        for theta in [0.0f32, 30.0, 60.0, 80.0] {
            let a = albedo(&bsdf(&m, view(theta)), 128, &mut rng);
            assert!(
                a.max_element() <= 1.0 + 1e-2,
                "{name} at {theta}°: albedo {a}"
            );
            // The Phong highlight (n+2)/(2π) cosⁿα loses what falls below
            // the horizon, so it is lossless only at normal incidence.
            let lossless = matches!(name, "white lambert" | "glass")
                || (name == "overcommitted" && theta == 0.0);
            if lossless || (name == "white metal" && theta <= 60.0) {
                // Weights summing past 1 are scaled to exactly 1; a smooth
                // white metal loses only what Smith's masking hides.
                let floor = if lossless { 0.99 } else { 0.97 };
                assert!(a.min_element() >= floor, "{name} at {theta}°: albedo {a}");
            }
        }
    }
}

#[test]
fn every_smooth_lobe_is_reciprocal() {
    let mut rng = Numbers(12345);
    for (name, m) in materials() {
        for _ in 0..500 {
            let dir = |rng: &mut Numbers| {
                let z: f32 = rng.next().max(0.02);
                let phi = 2.0 * PI * rng.next();
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            };
            let (a, b) = (dir(&mut rng), dir(&mut rng));
            let (fab, _) = bsdf(&m, a).eval(b);
            let (fba, _) = bsdf(&m, b).eval(a);
            let scale = fab.max_element().max(1.0);
            assert!(
                (fab - fba).abs().max_element() <= 1e-4 * scale,
                "{name}: f({a}, {b}) = {fab} but f({b}, {a}) = {fba}"
            );
        }
    }
}

/// The directions drawn fall into bins of (cos θ, φ) as often as the
/// reported density integrates to over each bin (a chi-square test), and
/// the density integrates to at most 1.
#[test]
fn samples_follow_the_density_they_report() {
    const ROWS: usize = 10;
    const COLS: usize = 16;
    let mut rng = Numbers(777);
    for (name, m) in materials() {
        if matches!(
            name,
            "glass" | "white lambert" | "grey lambert" | "smooth gold" | "white metal"
        ) {
            // A delta lobe, the cosine that `albedo` already checks, or a
            // lobe too sharp for bins this size to integrate.
            continue;
        }
        for theta in [10.0f32, 50.0, 75.0] {
            let b = bsdf(&m, view(theta));
            // The density integrated over each bin by the midpoint rule.
            let sub = 12;
            let mut expected = [[0.0f64; COLS]; ROWS];
            let mut total = 0.0;
            for (r, row) in expected.iter_mut().enumerate() {
                for (c, cell) in row.iter_mut().enumerate() {
                    for i in 0..sub {
                        for j in 0..sub {
                            let z = (r as f32 + (i as f32 + 0.5) / sub as f32) / ROWS as f32;
                            let phi =
                                2.0 * PI * (c as f32 + (j as f32 + 0.5) / sub as f32) / COLS as f32;
                            let s = (1.0 - z * z).max(0.0).sqrt();
                            let (_, pdf) = b.eval(Vec3::new(s * phi.cos(), s * phi.sin(), z));
                            let d_omega = 2.0 * PI as f64 / (ROWS * COLS * sub * sub) as f64;
                            *cell += pdf as f64 * d_omega;
                        }
                    }
                    total += *cell;
                }
            }
            assert!(total <= 1.0 + 2e-2, "{name} at {theta}°: ∫pdf = {total}");
            let n = 200_000;
            let mut observed = [[0u32; COLS]; ROWS];
            for _ in 0..n {
                let u = Vec2::new(rng.next(), rng.next());
                // Delta lobes' directions are not in the density.
                if let Some(s) = b.sample(rng.next(), u).filter(|s| !s.delta) {
                    let z = s.wi.z.clamp(0.0, 0.999_999);
                    let phi = s.wi.y.atan2(s.wi.x).rem_euclid(2.0 * PI);
                    let c = ((phi / (2.0 * PI) * COLS as f32) as usize).min(COLS - 1);
                    observed[(z * ROWS as f32) as usize][c] += 1;
                }
            }
            let (mut chi2, mut dof) = (0.0, 0);
            for r in 0..ROWS {
                for c in 0..COLS {
                    let e = expected[r][c] * n as f64;
                    let o = observed[r][c] as f64;
                    if e >= 5.0 {
                        chi2 += (o - e) * (o - e) / e;
                        dof += 1;
                    } else {
                        assert!(
                            o < 5.0 * (e + 4.0),
                            "{name} at {theta}°: bin {r},{c}: {o} vs {e}"
                        );
                    }
                }
            }
            // Far above the 99.9th percentile (≈ dof + 4.5 √(2 dof)) only
            // if the samples and the density disagree; the midpoint rule
            // adds a little of its own error on sharp lobes.
            let limit = dof as f64 + 6.0 * (2.0 * dof as f64).sqrt() + 0.002 * n as f64;
            assert!(
                chi2 < limit,
                "{name} at {theta}°: χ² = {chi2:.0} over {dof} bins"
            );
        }
    }
}

/// A unit vector from three of the tests' numbers.
fn unit(rng: &mut Numbers) -> Vec3 {
    let z = 2.0 * rng.next() - 1.0;
    let phi = 2.0 * PI * rng.next();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn same(a: Vec3, b: Vec3) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}

/// Within a few units in the last place (relative 1e-6), each channel.
fn close(a: Vec3, b: Vec3) -> bool {
    (0..3).all(|k| close_f(a[k], b[k]))
}

/// Within a few units in the last place, or within the rounding of a
/// unit vector's component (2e-7) where a density is a cosine over π:
/// the two compute the cosine in different frames.
fn close_f(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 2e-7
}

/// The Lambertian BSDF a diffuse-only Phong material is held as gives
/// what the general Phong mix gives, to rounding: the same sampled
/// direction bit for bit, its weight (ρ itself, where the mix divides
/// f·cos by the density) and density within a few units in the last
/// place, the same value and a density as close for any direction
/// (above and below the surface), over random materials (ρ past 1 too,
/// scaled; a highlight with a negative exponent, which switches it off),
/// textures, views and normals. Only a direction within rounding of the
/// surface may be drawn by one and refused by the other.
#[test]
fn a_lambertian_phong_material_is_sampled_and_evaluated_as_the_phong_mix() {
    let mut rng = Numbers(0x5eed_61f0);
    let mut lambert_draws = 0;
    for case in 0..4000 {
        // ρ up to 1.4 (past 1 the weights are scaled), a little below 0 now and then.
        let below = 0.1 * (case % 7 == 0) as u32 as f32;
        let mut rho = || 1.4 * rng.next() - below;
        let diffuse = Vec3::new(rho(), rho(), rho());
        let m = Material {
            diffuse,
            specular: if case % 3 == 0 {
                Vec3::splat(rng.next())
            } else {
                Vec3::ZERO
            },
            shininess: if case % 3 == 0 {
                -1.0
            } else {
                30.0 * rng.next()
            },
            glossiness: 100.0 * rng.next(),
            ..Material::default()
        };
        let texel = if case % 2 == 0 {
            Vec3::ONE
        } else {
            Vec3::new(rng.next(), rng.next(), rng.next())
        };
        let wo = unit(&mut rng);
        let mut ng = unit(&mut rng);
        let entering = ng.dot(wo) >= 0.0;
        if !entering {
            ng = -ng;
        }
        // A shading normal tilted off the geometric one, as interpolated
        // normals and normal maps tilt it (wo may fall below it).
        let ns = (ng + 0.4 * unit(&mut rng)).normalize();
        let fast = Bsdf::new(&m, texel, wo, ng, ns, entering);
        // The same material held as the general Phong mix.
        let general = Bsdf::build(&m, texel, wo, ng, ns, entering, false);
        assert!(fast.is_lambert() && !general.is_lambert(), "case {case}");
        assert_eq!(fast.has_smooth_lobe(), general.has_smooth_lobe());
        for k in 0..8 {
            // The lobe choice at its extremes too: one that rounds up to
            // the total finds no lobe.
            let choice = match k {
                0 => 0.0,
                1 => 1.0 - f32::EPSILON / 2.0,
                _ => rng.next(),
            };
            let u = Vec2::new(rng.next(), rng.next());
            let (a, b) = (fast.sample(choice, u), general.sample(choice, u));
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    lambert_draws += 1;
                    assert!(
                        same(a.wi, b.wi)
                            && close(a.weight, b.weight)
                            && close_f(a.pdf, b.pdf)
                            && a.delta == b.delta,
                        "case {case}: {a:?} against {b:?}"
                    );
                }
                (Some(s), None) | (None, Some(s)) => {
                    // Refused by one: only at the surface's rounding.
                    let grazing = fast
                        .cos(s.wi)
                        .abs()
                        .min(ng.dot(s.wi).abs())
                        .min(wo.dot(ns).abs());
                    assert!(
                        grazing < 1e-5,
                        "case {case}, choice {choice}: {a:?} against {b:?}"
                    );
                }
            }
            let wi = unit(&mut rng);
            let ((fa, pa), (fb, pb)) = (fast.eval(wi), general.eval(wi));
            assert!(
                same(fa, fb) && close_f(pa, pb),
                "case {case}: eval({wi}) {fa} {pa} against {fb} {pb}"
            );
        }
    }
    assert!(lambert_draws > 10_000, "{lambert_draws} directions drawn");
}

/// Only a material with no lobe but ρ's is held as Lambert's.
#[test]
fn materials_with_other_lobes_keep_the_phong_mix() {
    for (name, m) in materials() {
        let lambert = bsdf(&m, view(30.0)).is_lambert();
        assert_eq!(lambert, name.ends_with("lambert"), "{name}");
    }
}

//! strata's CSG against the f64 reference (`super::reference`): the first
//! boundary along random rays from inside and around each solid, and along
//! rays spawned from CSG hits as the integrator spawns them, within a
//! rounding band; every disagreement is tallied and real ones fail.

use super::reference::{op, sphere, Node, Op, Reference};
use super::{csg_scene, die, drilled, nested, two_spheres};
use crate::common::{seeded, Draw, StreamRng};
use glam::Vec3;
use strata::math::offset::spawn_origin;
use strata::math::Ray;
use strata::scene::Scene;
use strata::shade::bsdf::refract;

/// Disagreements with the reference closer than this (in t, along unit
/// directions, for solids of size ~1) are rounding, not errors.
const DELTA: f64 = 1e-4;

/// Agreement of strata's CSG with the reference over many rays.
#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    hits: usize,
    /// Disagreements where surfaces of two different leaves cross the ray
    /// within 2δ of each other there: which one is first is up to rounding.
    coincident: usize,
    /// Other disagreements where strata and the reference differ only on a
    /// stretch of ray that lies wholly within δ of the solid's boundary (a
    /// ray grazing a surface, where t is ill-conditioned).
    in_band: usize,
    /// Everything else: real errors, described.
    real: Vec<String>,
}

/// Whether `p` lies within about `DELTA` of the reference solid's boundary:
/// membership is not the same at all 26 points around it at that distance.
fn near_boundary(reference: &Reference, p: glam::DVec3) -> bool {
    let inside = reference.contains(p);
    (0..27).filter(|&i| i != 13).any(|i| {
        let u = glam::DVec3::new(
            (i % 3) as f64 - 1.0,
            ((i / 3) % 3) as f64 - 1.0,
            (i / 9) as f64 - 1.0,
        );
        reference.contains(p + DELTA * u.normalize()) != inside
    })
}

impl Tally {
    /// Judge strata's answer `got` for the ray `o + t d`, t > `tmin`: it
    /// must be the reference's first boundary (within δ), and membership
    /// must change across it (the point-membership test). `next(t)` is
    /// strata's first boundary after t, to find where the answers differ.
    fn judge(
        &mut self,
        reference: &Reference,
        o: Vec3,
        d: Vec3,
        tmin: f64,
        got: Option<f32>,
        next: impl Fn(f64) -> Option<f64>,
    ) {
        let (o, d) = (o.as_dvec3(), d.as_dvec3().normalize());
        let got = got.map(f64::from);
        self.rays += 1;
        self.hits += got.is_some() as usize;
        let expected = reference.first_boundary(o, d, tmin);
        let ok = match (got, expected) {
            (None, None) => true,
            (Some(t), Some(e)) => {
                (t - e).abs() <= DELTA
                    && reference.contains(o + (t - DELTA) * d)
                        != reference.contains(o + (t + DELTA) * d)
            }
            _ => false,
        };
        if ok {
            return;
        }
        // Two leaves crossing the ray within 2δ near a disputed point?
        let disputed: Vec<f64> = got.into_iter().chain(expected).collect();
        let near: Vec<(f64, usize)> = reference
            .crossings(o, d)
            .into_iter()
            .filter(|c| disputed.iter().any(|t| (c.0 - t).abs() <= 2.0 * DELTA))
            .collect();
        let coincident = near.iter().enumerate().any(|(i, a)| {
            near[i + 1..]
                .iter()
                .any(|b| a.1 != b.1 && (a.0 - b.0).abs() <= 2.0 * DELTA)
        });
        if coincident {
            self.coincident += 1;
            return;
        }
        // The stretch where the two answers disagree about membership: between
        // the two boundaries, or, where one side sees none, up to the other
        // side's next boundary.
        let (from, to) = match (got, expected) {
            (Some(t), Some(e)) => (t.min(e), t.max(e)),
            (None, Some(e)) => (e, reference.first_boundary(o, d, e).unwrap_or(e + 1.0)),
            (Some(t), None) => (t, next(t).unwrap_or(t + 1.0)),
            (None, None) => unreachable!(),
        };
        let in_band = (0..=8)
            .all(|k| near_boundary(reference, o + (from + (to - from) * k as f64 / 8.0) * d));
        if in_band {
            self.in_band += 1;
            return;
        }
        let at = |t: Option<f64>| t.map(|t| (o + t * d).to_array());
        self.real.push(format!(
            "ray o={:?} d={:?} tmin={tmin}: strata t={got:?} at {:?}, reference t={expected:?} at {:?}",
            o.to_array(),
            d.to_array(),
            at(got),
            at(expected)
        ));
    }

    fn summary(&self, name: &str) -> String {
        format!(
            "{name}: {} rays, {} hits; disagreements: {} real, {} at coincident surfaces (two leaves within 2e-4 along the ray), {} elsewhere within the 1e-4 band (grazing)",
            self.rays,
            self.hits,
            self.real.len(),
            self.coincident,
            self.in_band
        )
    }
}

/// strata's first boundary along `o + t d` after `t`.
fn next_boundary(s: &Scene, o: Vec3, d: Vec3) -> impl Fn(f64) -> Option<f64> + '_ {
    move |t| {
        let ray = Ray {
            tmin: t as f32,
            ..Ray::new(o, d)
        };
        s.geometry.intersect(&ray).map(|h| h.t as f64)
    }
}

/// Random rays from inside and around the solid (half of them aimed at a
/// point inside its neighbourhood), judged against the reference.
fn random_rays(node: &Node, rays: usize, seed: u32) -> Tally {
    let s = csg_scene(node, "");
    let reference = Reference::new(node);
    let mut rng = seeded(seed.into());
    let mut tally = Tally::default();
    let point = |rng: &mut StreamRng, r: f32| {
        Vec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
    };
    for i in 0..rays {
        let o = point(&mut rng, 3.0);
        let d = if i % 2 == 0 {
            rng.unit_vector()
        } else {
            (point(&mut rng, 1.5) - o).normalize()
        };
        let ray = Ray::new(o, d);
        tally.judge(
            &reference,
            o,
            d,
            0.0,
            s.geometry.intersect(&ray).map(|h| h.t),
            next_boundary(&s, o, d),
        );
    }
    tally
}

fn configurations() -> Vec<(&'static str, Node)> {
    vec![
        ("union of two spheres", two_spheres(Op::Union)),
        ("intersection of two spheres", two_spheres(Op::Intersection)),
        ("difference of two spheres", two_spheres(Op::Difference)),
        ("die: (cube mesh ∩ sphere) − (sphere ∪ sphere)", die()),
        ("cylinder drilled by a cylinder", drilled()),
        ("three levels nested, transforms at each", nested()),
    ]
}

#[test]
fn every_operator_and_operand_agrees_with_point_membership_on_20k_rays() {
    for (i, (name, node)) in configurations().into_iter().enumerate() {
        let tally = random_rays(&node, 20_000, 1000 + i as u32);
        println!("{}", tally.summary(name));
        assert!(
            tally.hits > 1000,
            "{name}: the rays exercise the solid ({} hits)",
            tally.hits
        );
        assert!(
            tally.real.is_empty(),
            "{}\n{}",
            tally.summary(name),
            tally.real[..tally.real.len().min(10)].join("\n")
        );
    }
}

/// The stability count: 1M random rays per configuration.
/// Run with `cargo test --release --test suite csg:: -- --ignored --nocapture`.
#[test]
#[ignore]
fn stability_over_a_million_rays_per_configuration() {
    let mut total_real = 0;
    for (i, (name, node)) in configurations().into_iter().enumerate() {
        let tally = random_rays(&node, 1_000_000, 7000 + i as u32);
        println!("{}", tally.summary(name));
        for r in tally.real.iter().take(10) {
            println!("    {r}");
        }
        total_real += tally.real.len();
    }
    assert_eq!(total_real, 0);
}

/// Rays spawned from CSG hits, as the integrator spawns them (refracted
/// through the surface, and random directions on either side), must see
/// the reference's first boundary: never their own surface again at t ≈ 0.
fn spawned_rays(node: &Node, seed: u32, paths: usize) -> Tally {
    let s = csg_scene(node, "");
    let reference = Reference::new(node);
    let mut rng = seeded(seed.into());
    let mut tally = Tally::default();
    for _ in 0..paths {
        let target = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let mut ray = Ray::new(target + 4.0 * rng.unit_vector(), Vec3::ZERO);
        ray.direction = (target - ray.origin).normalize();
        let Some(mut hit) = s.geometry.intersect(&ray) else {
            continue;
        };
        for bounce in 0..6 {
            let surf = s.geometry.surface(&ray, &hit);
            let n = surf.geometric_normal;
            let wo = -ray.direction;
            let dir = match bounce % 3 {
                // Refraction, entering or leaving (glass of index 1.5).
                0 => {
                    let (nf, eta) = if n.dot(wo) > 0.0 {
                        (n, 1.0 / 1.5)
                    } else {
                        (-n, 1.5)
                    };
                    refract(wo, nf, eta).unwrap_or(2.0 * nf.dot(wo) * nf - wo)
                }
                // Onwards through the surface, or back the way it came.
                k => {
                    let d = rng.unit_vector();
                    let through = (k == 1) == (d.dot(n) * ray.direction.dot(n) > 0.0);
                    if through {
                        d
                    } else {
                        -d
                    }
                }
            };
            let next = Ray::new(spawn_origin(surf.p, surf.p_error, n, dir), dir);
            let got = s.geometry.intersect(&next);
            tally.judge(
                &reference,
                next.origin,
                next.direction,
                0.0,
                got.map(|h| h.t),
                next_boundary(&s, next.origin, next.direction),
            );
            match got {
                Some(h) => (ray, hit) = (next, h),
                None => break,
            }
        }
    }
    tally
}

#[test]
fn rays_spawned_from_csg_hits_never_rehit_their_own_surface() {
    let lens = op(
        Op::Intersection,
        sphere([0.0, 0.0, -0.9], 1.2),
        sphere([0.0, 0.0, 0.9], 1.2),
    );
    for (name, node) in [
        ("lens", lens),
        ("die", die()),
        ("drilled cylinder", drilled()),
        ("nested", nested()),
    ] {
        let tally = spawned_rays(&node, 17, 3000);
        println!("spawned, {}", tally.summary(name));
        assert!(tally.rays > 1500, "{name}: {} spawned rays", tally.rays);
        assert!(
            tally.real.is_empty(),
            "{}\n{}",
            tally.summary(name),
            tally.real[..tally.real.len().min(10)].join("\n")
        );
    }
}

//! Surfaces that glow, as one light for the path integrator: every
//! triangle of the scene's own meshes and every untransformed sphere whose
//! material has `emission`, sampled by power (area × luminance of the
//! radiance; pbrt-v4's `PowerLightSampler`), then a point on the chosen
//! one: uniform by area on a triangle, uniform in the cone of directions
//! that see a sphere from outside it (Shirley, Wang and Zimmerman 1996).
//!
//! Emitted radiance is two-sided, as the camera sees it. A mesh placed
//! more than once (an instance of a prototype) is here too, each
//! placement's triangles in world space, named by the instance and the
//! prototype's triangle ([`EmitterId`]). Emissive surfaces this table
//! leaves out (CSG solids, cylinders, transformed spheres, planes) still
//! light the scene, found by the BSDF's own rays alone; the scene's
//! `[[lights]]` surfaces are sampled as those lights and are not here.
//!
//! The distribution integrator never reads this table: there, emission is
//! seen and lights nothing, as it always has.

use crate::math::Frame;
use crate::sampling::warp::uniform_cone;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Which surface an emitter is: a primitive of the scene and, for an
/// instance, the prototype's triangle ([`NO_PART`] otherwise).
pub type EmitterId = (u32, u32);

/// The part of an [`EmitterId`] that is a primitive of the scene itself.
pub const NO_PART: u32 = u32::MAX;

/// One glowing surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Emitter {
    Triangle {
        v: [Vec3; 3],
        /// The material's emission; times the texture where there is one.
        radiance: Vec3,
        texture: Option<EmissionTexture>,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        radiance: Vec3,
    },
}

impl Emitter {
    pub fn area(&self) -> f32 {
        match *self {
            Emitter::Triangle { v, .. } => 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length(),
            Emitter::Sphere { radius, .. } => 4.0 * PI * radius * radius,
        }
    }

    /// The mean radiance the surface is weighed by: its emission, times
    /// its texture's mean where it has one.
    pub fn radiance(&self) -> Vec3 {
        match *self {
            Emitter::Triangle {
                radiance,
                texture: Some(t),
                ..
            } => radiance * t.mean,
            Emitter::Triangle { radiance, .. } | Emitter::Sphere { radiance, .. } => radiance,
        }
    }
}

/// An emissive texture over a triangle: the radiance at a point is the
/// factor times the texture there, and the triangle's power is weighed by
/// the factor times the texture's mean over its image (a guess at its mean
/// over the triangle that costs nothing per sample; any positive weight
/// keeps the estimate unbiased, as the chance drawn with is the chance
/// the density reports).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmissionTexture {
    /// Index into the scene's textures.
    pub texture: u32,
    /// The texture coordinates of the corners.
    pub uv: [Vec2; 3],
    /// The texture's mean.
    pub mean: Vec3,
}

/// A point drawn on a glowing surface as seen from a shading point.
#[derive(Debug, Clone, Copy)]
pub struct EmitterSample {
    /// Unit direction from the shading point towards the surface.
    pub wi: Vec3,
    pub distance: f32,
    /// The emission there, to be multiplied by `texture` where given.
    pub radiance: Vec3,
    /// The emissive texture and the point's coordinates in it.
    pub texture: Option<(u32, Vec2)>,
    /// Density per steradian, the choice of the surface included.
    pub pdf: f32,
    /// The primitive drawn on, which its shadow ray skips; `u32::MAX` on
    /// an instance, whose primitive is the whole placed mesh (which may
    /// shadow itself): its shadow ray skips nothing and ends short
    /// instead (`distance` is shortened by [`INSTANCE_SHADOW_GAP`]).
    pub prim: u32,
}

/// The fraction of the distance by which a shadow ray towards a point on
/// an instanced emitter stops short of it, so that it does not find the
/// emitter itself (no primitive id names one triangle of an instance).
pub const INSTANCE_SHADOW_GAP: f32 = 1e-4;

/// Every glowing surface the path integrator samples, and the primitive
/// each one is.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Emitters {
    emitters: Vec<Emitter>,
    /// `prims[i]` is the surface `emitters[i]` is.
    prims: Vec<EmitterId>,
    /// Cumulative power, normalised: `cdf[i]` is the chance of `0..=i`.
    cdf: Vec<f32>,
    /// (surface, index), sorted by surface: a BSDF ray's hit to its
    /// emitter.
    by_prim: Vec<(EmitterId, u32)>,
}

impl Emitters {
    /// The table of `(surface, emitter)` pairs; surfaces that emit
    /// nothing or have no area are left out.
    pub fn new(list: Vec<(EmitterId, Emitter)>) -> Self {
        let list: Vec<(EmitterId, Emitter)> = list
            .into_iter()
            .filter(|(_, e)| {
                let power = e.area() * luminance(e.radiance());
                power > 0.0 && power.is_finite()
            })
            .collect();
        let mut running = 0.0f64;
        let mut cdf = Vec::with_capacity(list.len());
        for (_, e) in &list {
            running += (e.area() * luminance(e.radiance())) as f64;
            cdf.push(running);
        }
        let cdf: Vec<f32> = cdf.iter().map(|c| (c / running) as f32).collect();
        let mut by_prim: Vec<(EmitterId, u32)> = list
            .iter()
            .enumerate()
            .map(|(i, (p, _))| (*p, i as u32))
            .collect();
        by_prim.sort_unstable();
        let (prims, emitters) = list.into_iter().unzip();
        let mut out = Self {
            emitters,
            prims,
            cdf,
            by_prim,
        };
        if let Some(last) = out.cdf.last_mut() {
            *last = 1.0;
        }
        out
    }

    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    pub fn len(&self) -> usize {
        self.emitters.len()
    }

    /// The chance that a draw picks emitter `i`.
    fn chance(&self, i: usize) -> f32 {
        self.cdf[i] - if i == 0 { 0.0 } else { self.cdf[i - 1] }
    }

    /// A point on a glowing surface seen from `p`, with `u` uniform in
    /// [0,1)²: `u.x` picks the surface by power and is stretched back to
    /// [0,1) to place the point, so one stratified pair serves both.
    pub fn sample(&self, p: Vec3, u: Vec2) -> Option<EmitterSample> {
        if self.emitters.is_empty() {
            return None;
        }
        let i = self
            .cdf
            .partition_point(|&c| c <= u.x)
            .min(self.cdf.len() - 1);
        let chance = self.chance(i);
        if !(chance > 0.0) {
            return None;
        }
        let below = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let ux = ((u.x - below) / chance).clamp(0.0, 1.0 - f32::EPSILON);
        let u = Vec2::new(ux, u.y);
        let s = match self.emitters[i] {
            Emitter::Triangle {
                v,
                radiance,
                texture,
            } => {
                // Uniform by area: the square-root warp of barycentrics.
                let r = u.x.sqrt();
                let (b1, b2) = (r * (1.0 - u.y), r * u.y);
                let q = v[0] + b1 * (v[1] - v[0]) + b2 * (v[2] - v[0]);
                let n = (v[1] - v[0]).cross(v[2] - v[0]);
                let area = 0.5 * n.length();
                let to = q - p;
                let d2 = to.length_squared();
                let distance = d2.sqrt();
                let wi = to / distance;
                let cos_l = (n.normalize().dot(wi)).abs();
                EmitterSample {
                    wi,
                    distance,
                    radiance,
                    texture: texture.map(|t| {
                        let uv = t.uv[0] + b1 * (t.uv[1] - t.uv[0]) + b2 * (t.uv[2] - t.uv[0]);
                        (t.texture, uv)
                    }),
                    pdf: d2 / (cos_l * area),
                    prim: 0,
                }
            }
            Emitter::Sphere {
                center,
                radius,
                radiance,
            } => sphere_sample(p, center, radius, radiance, u)?,
        };
        let pdf = s.pdf * chance;
        let (prim, distance) = match self.prims[i] {
            (prim, NO_PART) => (prim, s.distance),
            _ => (u32::MAX, s.distance * (1.0 - INSTANCE_SHADOW_GAP)),
        };
        (pdf > 0.0 && pdf.is_finite() && s.distance > 0.0).then_some(EmitterSample {
            pdf,
            prim,
            distance,
            ..s
        })
    }

    /// The density with which [`Emitters::sample`] draws the direction
    /// from `p` to `q` on surface `prim` (normal `n` there), or 0 where
    /// `prim` is no emitter of this table.
    pub fn pdf(&self, prim: EmitterId, p: Vec3, q: Vec3, n: Vec3) -> f32 {
        let Ok(k) = self.by_prim.binary_search_by_key(&prim, |&(p, _)| p) else {
            return 0.0;
        };
        let i = self.by_prim[k].1 as usize;
        let to = q - p;
        let d2 = to.length_squared();
        if !(d2 > 0.0) {
            return 0.0;
        }
        let wi = to / d2.sqrt();
        let pdf = match self.emitters[i] {
            Emitter::Triangle { .. } => {
                let cos_l = n.dot(wi).abs();
                d2 / (cos_l * self.emitters[i].area())
            }
            Emitter::Sphere { center, radius, .. } => match super::sphere_cone(p, center, radius) {
                Some((_, solid_angle)) => 1.0 / solid_angle,
                None => d2 / (n.dot(wi).abs() * self.emitters[i].area()),
            },
        };
        let pdf = pdf * self.chance(i);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// The surface emitter `i` is (for tests and reports).
    pub fn prim(&self, i: usize) -> EmitterId {
        self.prims[i]
    }
}

/// A sphere's point seen from `p`: in its cone from outside, uniform by
/// area from inside.
fn sphere_sample(
    p: Vec3,
    center: Vec3,
    radius: f32,
    radiance: Vec3,
    u: Vec2,
) -> Option<EmitterSample> {
    let to_center = center - p;
    if let Some((cos_max, solid_angle)) = super::sphere_cone(p, center, radius) {
        let dc = to_center.length();
        let wi = Frame::from_z(to_center / dc).to_world(uniform_cone(u, cos_max));
        let b = wi.dot(to_center);
        let disc = (radius * radius - (to_center - b * wi).length_squared()).max(0.0);
        return Some(EmitterSample {
            wi,
            distance: b - disc.sqrt(),
            radiance,
            texture: None,
            pdf: 1.0 / solid_angle,
            prim: 0,
        });
    }
    let n = crate::sampling::warp::uniform_sphere(u);
    let q = center + radius * n;
    let to = q - p;
    let d2 = to.length_squared();
    let distance = d2.sqrt();
    let wi = to / distance;
    let cos_l = n.dot(wi).abs();
    Some(EmitterSample {
        wi,
        distance,
        radiance,
        texture: None,
        pdf: d2 / (cos_l * 4.0 * PI * radius * radius),
        prim: 0,
    })
}

/// Rec. 709 luminance: what a surface's power is weighed by.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The density `sample` reports is the density `pdf` gives for the
    /// same direction, and its integral over the directions that see the
    /// emitters (estimated by the samples' own 1/pdf, i.e. their solid
    /// angle) matches the solid angle they subtend.
    #[test]
    fn sampled_densities_match_the_density_function() {
        let tri = Emitter::Triangle {
            v: [
                Vec3::new(-1.0, 2.0, -1.0),
                Vec3::new(1.0, 2.0, -1.0),
                Vec3::new(0.0, 2.0, 1.0),
            ],
            radiance: Vec3::splat(2.0),
            texture: None,
        };
        let sphere = Emitter::Sphere {
            center: Vec3::new(3.0, 1.0, 0.0),
            radius: 0.5,
            radiance: Vec3::new(1.0, 0.5, 0.25),
        };
        let e = Emitters::new(vec![((7, NO_PART), tri), ((3, NO_PART), sphere)]);
        assert_eq!(e.len(), 2);
        let p = Vec3::ZERO;
        for i in 0..64 {
            for j in 0..64 {
                let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                let s = e.sample(p, u).unwrap();
                let q = p + s.wi * s.distance;
                let (prim, n) = if (q.y - 2.0).abs() < 1e-4 {
                    (7, Vec3::Y)
                } else {
                    (3, (q - Vec3::new(3.0, 1.0, 0.0)).normalize())
                };
                let pdf = e.pdf((prim, NO_PART), p, q, n);
                assert!((pdf - s.pdf).abs() <= 2e-3 * s.pdf, "{pdf} vs {}", s.pdf);
            }
        }
        assert_eq!(e.pdf((99, NO_PART), p, Vec3::Y, Vec3::Y), 0.0);
    }
}

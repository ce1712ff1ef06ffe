//! Lights: a closed enum. Point and directional lights are deltas (one
//! shadow ray each). Area lights are also visible emitting surfaces, and are
//! sampled `shadow_samples` times per hit.
//!
//! ```toml
//! [[lights]]
//! type = "point"
//! position = [0.0, 4.0, 0.0]
//! intensity = [10.0, 10.0, 10.0]   # W/sr: irradiance I cosθ / r²
//!
//! [[lights]]
//! type = "directional"
//! direction = [0.0, -1.0, 0.0]     # the way the light travels
//! irradiance = [1.0, 1.0, 1.0]     # W/m² on a surface facing the light
//!
//! [[lights]]
//! type = "spot"                    # a point light limited to a cone
//! position = [0.0, 4.0, 0.0]
//! direction = [0.0, -1.0, 0.0]     # the cone's axis (or look_at = a point)
//! intensity = [10.0, 10.0, 10.0]   # W/sr on the axis
//! inner_angle = 20.0               # degrees from the axis: full intensity
//! outer_angle = 30.0               # beyond it: none; between: glTF's falloff
//!
//! [[lights]]
//! type = "rect"                    # one-sided, emits towards edge_u × edge_v
//! corner = [-0.5, 3.0, -0.5]
//! edge_u = [1.0, 0.0, 0.0]
//! edge_v = [0.0, 0.0, 1.0]
//! radiance = [5.0, 5.0, 5.0]
//!
//! [[lights]]
//! type = "disk"                    # one-sided, emits towards normal
//! center = [0.0, 3.0, 0.0]
//! normal = [0.0, -1.0, 0.0]
//! radius = 0.5
//! radiance = [5.0, 5.0, 5.0]
//!
//! [[lights]]
//! type = "sphere"                  # emits outwards everywhere
//! center = [0.0, 3.0, 0.0]
//! radius = 0.25
//! radiance = [5.0, 5.0, 5.0]
//!
//! [[lights]]
//! type = "environment"             # from every direction at infinity
//! radiance = [0.5, 0.6, 0.8]       # or map = "sky.exr" (lat-long), scale, rotate
//! ```
//!
//! Sampling by solid angle (`light_sampling = "solid_angle"`, the default)
//! uses spherical rectangles for rectangular `rect` lights (Ureña, Fajardo
//! and King 2013) and the cone of directions for spheres (Shirley, Wang and
//! Zimmerman 1996, "Monte Carlo Techniques for Direct Lighting
//! Calculations"); disks, parallelograms and points inside a sphere light
//! fall back to sampling by area, which `light_sampling = "area"` forces.
//! `light_sampling = "auto"` (the path integrator's default) samples a rect
//! light by area from the points where it looks small
//! ([`SMALL_SOLID_ANGLE`]), by solid angle elsewhere.
//! The environment light ([`environment`]) has its own sampling. Glowing
//! surfaces are one more light for the path integrator ([`emitters`]).

pub mod emitters;
pub mod environment;
mod lanes;
mod pdf;
mod sample;
mod spot;

pub use emitters::{EmissionTexture, Emitter, EmitterId, Emitters, NO_PART};
pub use environment::Environment;
pub use lanes::LightLanes;
pub use sample::{LightFrom, LightSample, LightSampling, SMALL_SOLID_ANGLE};
pub use spot::{spot_falloff, spot_power};

use crate::shape::disk::Disk;
use crate::shape::rect::Rect;
use glam::Vec3;
use std::f32::consts::PI;

// Not `Copy`: an environment map's texels are shared, not copied.
#[derive(Debug, Clone, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    /// A point light limited to a cone around the unit `direction` it
    /// shines along: `intensity` (W/sr) on the axis, scaled by
    /// [`spot_falloff`] between the cosines of its inner and outer
    /// half-angles (`cos_inner ≥ cos_outer`).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// `direction` is the unit direction the light travels.
    Directional {
        direction: Vec3,
        irradiance: Vec3,
    },
    /// `prim` is the light's visible surface, skipped by its own shadow rays.
    Rect {
        rect: Rect,
        radiance: Vec3,
        prim: u32,
    },
    Disk {
        disk: Disk,
        radiance: Vec3,
        prim: u32,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        radiance: Vec3,
        prim: u32,
    },
    /// Radiance from every direction at infinity: sampled `shadow_samples`
    /// times per hit, and seen by rays that hit nothing.
    Environment(Environment),
}

impl Light {
    /// A constant environment light of `radiance` (W/(m² sr)) from every
    /// direction: a neutral default light for a scene that has none.
    pub fn constant_environment(radiance: Vec3) -> Light {
        Light::Environment(Environment::constant(radiance))
    }

    /// The environment, if this light is one.
    pub fn environment(&self) -> Option<&Environment> {
        match self {
            Light::Environment(e) => Some(e),
            _ => None,
        }
    }

    /// True for lights with a surface (or the environment), which take
    /// `shadow_samples` samples.
    pub fn is_area(&self) -> bool {
        !matches!(
            self,
            Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. }
        )
    }

    /// The primitive that is this light's visible surface, if any.
    pub fn prim(&self) -> Option<u32> {
        match *self {
            Light::Rect { prim, .. } | Light::Disk { prim, .. } | Light::Sphere { prim, .. } => {
                Some(prim)
            }
            _ => None,
        }
    }

    /// Total emitted power in watts (∞ for directional light).
    pub fn power(&self) -> Vec3 {
        match *self {
            Light::Point { intensity, .. } => 4.0 * PI * intensity,
            Light::Spot {
                intensity,
                cos_inner,
                cos_outer,
                ..
            } => spot_power(intensity, cos_inner, cos_outer),
            Light::Directional { .. } | Light::Environment(_) => Vec3::splat(f32::INFINITY),
            Light::Rect { rect, radiance, .. } => PI * rect.area() * radiance,
            Light::Disk { disk, radiance, .. } => PI * disk.area() * radiance,
            Light::Sphere {
                radius, radiance, ..
            } => 4.0 * PI * PI * radius * radius * radiance,
        }
    }
}

/// The cone of directions from `p` that see the sphere, as (cos of its
/// half-angle, solid angle), where `p` is outside it (by a margin, so
/// that the cone is not degenerate): what solid-angle sampling of a sphere
/// draws from, and the density it reports.
pub(crate) fn sphere_cone(p: Vec3, center: Vec3, radius: f32) -> Option<(f32, f32)> {
    let dc2 = (center - p).length_squared();
    if !(dc2 > radius * radius * 1.0001) {
        return None;
    }
    let sin2_max = radius * radius / dc2;
    let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
    // 1 − cos θ ≈ sin²θ/2 avoids cancellation for tiny or far spheres.
    let solid_angle = if sin2_max < 1e-4 {
        2.0 * PI * (0.5 * sin2_max + 0.125 * sin2_max * sin2_max)
    } else {
        2.0 * PI * (1.0 - cos_max)
    };
    Some((cos_max, solid_angle))
}

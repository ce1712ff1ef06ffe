//! Lights: a closed enum. Point and directional lights are deltas (one
//! shadow ray each); area lights are sampled (see `shade::area`).
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
//! ```

use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    /// `direction` is the unit direction the light travels.
    Directional {
        direction: Vec3,
        irradiance: Vec3,
    },
}

/// One light sample seen from a shading point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub wi: Vec3,
    /// Distance to the light sample (∞ for directional light).
    pub distance: f32,
    /// Irradiance on a surface facing `wi` (before the cosine).
    pub irradiance: Vec3,
}

impl Light {
    /// Sample the light from point `p`. Delta lights ignore the sample.
    pub fn sample(&self, p: Vec3) -> Option<LightSample> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                let to = position - p;
                let d2 = to.length_squared();
                if d2.is_nan() || d2 <= 0.0 {
                    return None;
                }
                let distance = d2.sqrt();
                Some(LightSample {
                    wi: to / distance,
                    distance,
                    irradiance: intensity / d2,
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(LightSample {
                wi: -direction,
                distance: f32::INFINITY,
                irradiance,
            }),
        }
    }

    /// Total emitted power (W), for reporting and equal-power tests.
    pub fn power(&self) -> Vec3 {
        match *self {
            Light::Point { intensity, .. } => 4.0 * std::f32::consts::PI * intensity,
            Light::Directional { .. } => Vec3::splat(f32::INFINITY),
        }
    }
}

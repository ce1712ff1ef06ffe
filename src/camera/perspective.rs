//! Pinhole perspective camera.
//!
//! ```toml
//! [camera]
//! type = "perspective"
//! position = [0.0, 1.0, 6.0]
//! look_at = [0.0, 0.5, 0.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 40.0   # vertical field of view in degrees
//! ```

use super::View;
use crate::math::Ray;
use glam::{Vec2, Vec3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perspective {
    pub view: View,
    /// tan(fov/2): half the image plane height at distance 1.
    pub tan_half_fov: f32,
}

impl Perspective {
    pub fn new(view: View, fov_degrees: f32) -> Self {
        Self {
            view,
            tan_half_fov: (0.5 * fov_degrees.to_radians()).tan(),
        }
    }

    /// Unit direction through a film position.
    #[inline]
    pub fn direction(&self, film: Vec2) -> Vec3 {
        let s = self.view.screen(film) * self.tan_half_fov;
        (self.view.forward + s.x * self.view.right + s.y * self.view.up).normalize()
    }

    #[inline]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        Ray::new(self.view.position, self.direction(film))
    }
}

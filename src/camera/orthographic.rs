//! Orthographic camera: parallel rays, no perspective shrink.
//!
//! ```toml
//! [camera]
//! type = "orthographic"
//! position = [0.0, 1.0, 6.0]
//! look_at = [0.0, 0.5, 0.0]
//! height = 4.0   # world-space height of the view
//! ```

use super::View;
use crate::math::Ray;
use glam::Vec2;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orthographic {
    pub view: View,
    pub half_height: f32,
}

impl Orthographic {
    pub fn new(view: View, height: f32) -> Self {
        Self {
            view,
            half_height: 0.5 * height,
        }
    }

    #[inline]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let s = self.view.screen(film) * self.half_height;
        let origin = self.view.position + s.x * self.view.right + s.y * self.view.up;
        Ray::new(origin, self.view.forward)
    }
}

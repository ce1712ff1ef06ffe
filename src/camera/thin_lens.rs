//! Thin-lens camera for depth of field (Cook, Porter and Carpenter 1984,
//! "Distributed Ray Tracing"; the lens model of Potmesil and Chakravarty 1981).
//!
//! ```toml
//! [camera]
//! type = "thin_lens"
//! position = [0.0, 1.0, 6.0]
//! look_at = [0.0, 0.5, 0.0]
//! fov = 40.0
//! aperture = 0.1         # lens radius in world units; 0 = pinhole
//! focus_distance = 6.0   # distance of the sharp plane; default: |look_at - position|
//! ```
//!
//! Lens samples are mapped to the disk with the concentric map (Shirley and
//! Chiu 1997) so that a stratified square stays stratified on the lens. With
//! `aperture = 0` the camera *is* the pinhole: it returns the perspective
//! ray bit for bit.

use super::perspective::Perspective;
use crate::math::Ray;
use crate::sampling::warp::concentric_disk;
use glam::Vec2;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinLens {
    pub pinhole: Perspective,
    pub aperture: f32,
    pub focus_distance: f32,
}

impl ThinLens {
    #[inline]
    pub fn generate_ray(&self, film: Vec2, lens: Vec2) -> Ray {
        let pinhole = self.pinhole.generate_ray(film);
        if self.aperture <= 0.0 {
            return pinhole;
        }
        let view = &self.pinhole.view;
        // The pinhole ray meets the plane of focus (perpendicular to the view axis) here.
        let t_focus = self.focus_distance / pinhole.direction.dot(view.forward);
        let focus = pinhole.at(t_focus);
        let d = concentric_disk(lens) * self.aperture;
        let origin = view.position + d.x * view.right + d.y * view.up;
        Ray::new(origin, (focus - origin).normalize())
    }
}

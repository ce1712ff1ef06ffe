//! Cameras: a closed enum, one implementation per file.
//!
//! Film coordinates are continuous pixels: x in [0, width) to the right,
//! y in [0, height) downwards. `lens` is a point in [0,1)² that only the
//! thin lens uses.

pub mod lanes;
pub mod orthographic;
pub mod perspective;
pub mod projection;
pub mod thin_lens;

use crate::math::Ray;
use glam::{Vec2, Vec3};

pub use orthographic::Orthographic;
pub use perspective::Perspective;
pub use thin_lens::ThinLens;

/// Position and orientation shared by every camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    pub position: Vec3,
    /// Unit vectors: `forward` looks into the scene, `right` × `up` = −`forward`.
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub width: u32,
    pub height: u32,
}

impl View {
    /// `None` if `up` is parallel to the view direction or the camera
    /// looks at its own position.
    pub fn look_at(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        Self::looking(position, look_at - position, up, width, height)
    }

    pub fn looking(
        position: Vec3,
        direction: Vec3,
        up: Vec3,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = direction.try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        if forward.cross(up).length() < 1e-6 * up.length() {
            return None;
        }
        let up = right.cross(forward);
        Some(Self {
            position,
            forward,
            right,
            up,
            width,
            height,
        })
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Film position to screen coordinates in [-aspect, aspect] × [-1, 1], y up.
    pub fn screen(&self, film: Vec2) -> Vec2 {
        Vec2::new(
            (2.0 * film.x / self.width as f32 - 1.0) * self.aspect(),
            1.0 - 2.0 * film.y / self.height as f32,
        )
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Camera {
    Orthographic(Orthographic),
    Perspective(Perspective),
    ThinLens(ThinLens),
}

impl Camera {
    #[inline]
    pub fn generate_ray(&self, film: Vec2, lens: Vec2) -> Ray {
        match self {
            Camera::Orthographic(c) => c.generate_ray(film),
            Camera::Perspective(c) => c.generate_ray(film),
            Camera::ThinLens(c) => c.generate_ray(film, lens),
        }
    }

    pub fn view(&self) -> &View {
        match self {
            Camera::Orthographic(c) => &c.view,
            Camera::Perspective(c) => &c.view,
            Camera::ThinLens(c) => &c.pinhole.view,
        }
    }

    /// True if rays depend on the lens sample.
    pub fn uses_lens(&self) -> bool {
        matches!(self, Camera::ThinLens(c) if c.aperture > 0.0)
    }
}

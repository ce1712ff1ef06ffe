//! `camera`: the primary rays of a pinhole camera that sees the whole mesh,
//! one jittered ray per pixel of a square-ish image of `n` pixels, in
//! scanline order. The eye sits 2.5 bounding radii from the centre, in a
//! direction drawn from the seed.

use super::{Generator, MeshInfo, RayKind, Stream};
use crate::math::Ray;
use glam::{DVec3, Vec3};

pub struct Pinhole {
    eye: Vec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    width: u32,
    height: u32,
}

impl Pinhole {
    pub fn new(mesh: &MeshInfo, n: usize, seed: u32) -> Self {
        // The view is one draw for the whole set, from a stream no ray uses.
        let mut rng = Stream::new(seed, RayKind::Camera, u32::MAX);
        let back = rng.unit_vector();
        let distance = 2.5 * mesh.radius;
        let eye = mesh.center + distance * back;
        let forward = -back;
        let helper = if forward.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let right = forward.cross(helper).normalize();
        let up = right.cross(forward);
        // Half the field of view: the bounding sphere's angular radius, plus 10%.
        let half = ((mesh.radius / distance).asin() * 1.1).tan();
        let width = (n as f64).sqrt().ceil().max(1.0) as u32;
        let height = (n as u32).div_ceil(width).max(1);
        Self {
            eye: eye.as_vec3(),
            forward,
            right: right * half,
            up: up * half,
            width,
            height,
        }
    }
}

impl Generator for Pinhole {
    fn ray(&self, index: u32, rng: &mut Stream) -> Option<Ray> {
        let (px, py) = (index % self.width, index / self.width);
        let sx = 2.0 * (px as f64 + rng.next_f64()) / self.width as f64 - 1.0;
        let sy = 1.0 - 2.0 * (py as f64 + rng.next_f64()) / self.height as f64;
        let direction = self.forward + sx * self.right + sy * self.up;
        Some(Ray::new(self.eye, direction.as_vec3()))
    }
}

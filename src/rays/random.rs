//! `random`: chords of the mesh's bounding sphere. Both ends are uniform on
//! a sphere slightly larger than the one around the bounding box, so the
//! rays cross the whole mesh in every direction and many of them miss.

use super::{Generator, MeshInfo, Stream};
use crate::math::Ray;
use glam::DVec3;

pub struct Chords {
    center: DVec3,
    radius: f64,
}

impl Chords {
    pub fn new(mesh: &MeshInfo) -> Self {
        Self {
            center: mesh.center,
            radius: 1.01 * mesh.radius,
        }
    }
}

impl Generator for Chords {
    fn ray(&self, _index: u32, rng: &mut Stream) -> Option<Ray> {
        let a = (self.center + self.radius * rng.unit_vector()).as_vec3();
        let b = (self.center + self.radius * rng.unit_vector()).as_vec3();
        let direction = b - a;
        // The ray runs on past b; nothing is out there.
        (direction.length_squared() > 0.0).then(|| Ray::new(a, direction))
    }
}

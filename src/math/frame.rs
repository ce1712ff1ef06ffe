//! Orthonormal bases around a normal, for sampling lobes in local space.

use glam::Vec3;

/// An orthonormal frame whose `z` axis is a given unit vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// Duff, Burgess, Christensen, Hery, Kensler, Liani and Villemin 2017,
    /// "Building an Orthonormal Basis, Revisited": branchless and free of the
    /// singularity of the cross-product constructions.
    pub fn from_z(z: Vec3) -> Self {
        let sign = 1.0f32.copysign(z.z);
        let a = -1.0 / (sign + z.z);
        let b = z.x * z.y * a;
        let x = Vec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x);
        let y = Vec3::new(b, sign + z.y * z.y * a, -z.y);
        Self { x, y, z }
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.x + v.y * self.y + v.z * self.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_even_near_the_poles() {
        for z in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1e-8, 0.0, -1.0).normalize(),
            Vec3::new(0.3, -0.4, 0.5).normalize(),
        ] {
            let f = Frame::from_z(z);
            for (a, b) in [(f.x, f.y), (f.y, f.z), (f.x, f.z)] {
                assert!(a.dot(b).abs() < 1e-6);
            }
            for v in [f.x, f.y, f.z] {
                assert!((v.length() - 1.0).abs() < 1e-6);
            }
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5, "right-handed");
        }
    }
}

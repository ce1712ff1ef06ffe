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

/// The power of two that brings `m` = 1.x·2^e into [1, 2): 2^-e, clamped
/// to float32's normal powers (so finite and not zero for any `m`).
/// Multiplying by it is exact (short of subnormals), which lets a
/// scale-free quantity made from lengths (a direction, an angle) be
/// computed from lengths brought near 1, where their squares and fourth
/// powers stay inside float32's range, with the bits it would have had
/// unscaled wherever those stayed inside anyway.
pub fn unit_scale(m: f32) -> f32 {
    let field = ((m.to_bits() >> 23) & 0xff) as i32;
    f32::from_bits(((254 - field).clamp(1, 254) as u32) << 23)
}

/// The unit vector along `a × b`, or `None` where they are parallel or one
/// is zero (or not finite). Normalising squares the cross product, whose
/// length² (the inputs' fourth power) overflows float32 for vectors past
/// about 4e9 and falls into subnormals below about 1e-10, so both are
/// first brought near 1 by [`unit_scale`]: the same bits as `normalize`
/// of the unscaled product wherever that works, and the right direction
/// at any scale.
pub fn unit_cross(a: Vec3, b: Vec3) -> Option<Vec3> {
    let s = unit_scale(a.abs().max(b.abs()).max_element());
    (a * s).cross(b * s).try_normalize()
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

    /// The scale brings every positive normal float32 below 2^127 into
    /// [1, 2), is a power of two, and stays finite and non-zero for any
    /// input.
    #[test]
    fn unit_scale_brings_a_number_into_one_to_two() {
        for bits in (0x0080_0000u32..0x7f00_0000).step_by(9_973) {
            let m = f32::from_bits(bits);
            let s = unit_scale(m);
            assert!((1.0..2.0).contains(&(m * s)), "{m:e} scaled by {s:e}");
            assert_eq!(s.to_bits() & 0x007f_ffff, 0, "a power of two");
        }
        for m in [
            0.0,
            f32::MIN_POSITIVE / 8.0,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
        ] {
            let s = unit_scale(m);
            assert!(s.is_finite() && s > 0.0, "{m:e}");
        }
    }
}

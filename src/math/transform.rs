//! Affine transforms with their inverse, for moving rays into object space.

use glam::{Affine3A, DAffine3, DMat3, Mat3, Vec3};

/// An object-to-world affine map with its inverse and normal matrix cached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    pub to_world: Affine3A,
    pub to_object: Affine3A,
    /// Inverse transpose of the linear part: maps object normals to world.
    pub normal_to_world: Mat3,
}

impl Transform {
    pub const IDENTITY: Transform = Transform {
        to_world: Affine3A::IDENTITY,
        to_object: Affine3A::IDENTITY,
        normal_to_world: Mat3::IDENTITY,
    };

    /// `None` if the map is singular (a zero scale) or it or its inverse is
    /// not finite. A tiny but invertible map (scale 1e-15) is accepted: its
    /// determinant may underflow, so finiteness of the inverse decides.
    pub fn new(to_world: Affine3A) -> Option<Self> {
        if !to_world.is_finite() {
            return None;
        }
        // Invert in f64: glam's f32 inverse divides by the determinant, which
        // underflows for tiny scales (1e-13³) although the inverse is finite.
        let m = DAffine3::from_mat3_translation(
            DMat3::from_cols(
                to_world.matrix3.x_axis.as_dvec3(),
                to_world.matrix3.y_axis.as_dvec3(),
                to_world.matrix3.z_axis.as_dvec3(),
            ),
            to_world.translation.as_dvec3(),
        );
        let det = m.matrix3.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = m.inverse();
        let to_object = Affine3A::from_mat3_translation(
            Mat3::from_cols(
                inv.matrix3.x_axis.as_vec3(),
                inv.matrix3.y_axis.as_vec3(),
                inv.matrix3.z_axis.as_vec3(),
            ),
            inv.translation.as_vec3(),
        );
        if !to_object.is_finite() {
            return None;
        }
        let normal_to_world = Mat3::from(to_object.matrix3).transpose();
        Some(Self {
            to_world,
            to_object,
            normal_to_world,
        })
    }

    pub fn point(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p)
    }

    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.to_world.transform_vector3(v)
    }

    /// World normal of an object-space normal, renormalised.
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_to_world * n).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn tiny_scales_are_invertible_and_zero_or_infinite_ones_are_not() {
        let tiny =
            Transform::new(Affine3A::from_scale(Vec3::splat(1e-13))).expect("1e-13 is invertible");
        let p = Vec3::new(1.0, -2.0, 3.0);
        assert!((tiny.to_object.transform_point3(tiny.point(p)) - p).length() < 1e-5);
        assert!(Transform::new(Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))).is_none());
        assert!(Transform::new(Affine3A::from_scale(Vec3::splat(f32::INFINITY))).is_none());
        assert!(Transform::new(Affine3A::from_translation(Vec3::splat(f32::NAN))).is_none());
    }
}

//! Affine transforms with their inverse, for moving rays into object space.

use glam::{Affine3A, Mat3, Vec3};

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

    /// `None` if the map is singular (a zero scale) or not finite.
    pub fn new(to_world: Affine3A) -> Option<Self> {
        let det = to_world.matrix3.determinant();
        if !det.is_finite() || det.abs() < f32::MIN_POSITIVE || !to_world.translation.is_finite() {
            return None;
        }
        let to_object = to_world.inverse();
        let normal_to_world = Mat3::from(to_object.matrix3).transpose();
        Some(Self {
            to_world,
            to_object,
            normal_to_world,
        })
    }

    pub fn is_identity(&self) -> bool {
        self.to_world == Affine3A::IDENTITY
    }

    pub fn then(&self, outer: &Transform) -> Transform {
        Transform::new(outer.to_world * self.to_world).expect("product of invertible maps")
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

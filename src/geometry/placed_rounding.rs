//! How far rounding may move things between an instance's world space and
//! its prototype's object space: what the mesh queries through instances
//! (`crossings`, `nearest`) add to the bounds of their object-space walks,
//! whose answers are measured on the triangles moved to world space, so
//! that no walk culls a triangle the world-space test would find.

use super::{Geometry, Instance};
use glam::{Affine3A, DMat3, DVec3, Mat3, Vec3};

/// The rounding of one instance, in object-space lengths.
pub(crate) struct PlacedRounding {
    /// ‖M⁻¹‖₂ rounded up, M⁻¹ the world-to-object map: a world length ℓ
    /// is at most `stretch`·ℓ in object space.
    pub stretch: f32,
    /// How far a prototype's triangle may lie, in object space, from the
    /// world triangle a copy holds moved back exactly: the rounding of
    /// moving its vertices to world space (pbrt-v4 section 6.8.6) and the
    /// f32 object-to-world map not being exactly the inverse of the
    /// world-to-object one (the condition number times ε), with the
    /// rounding of box distances in object space, 16 ε of each magnitude.
    pub vertex: f32,
    /// How far, per axis in world space, a copy's triangle or the world
    /// box of a prototype's box may lie from the exact image under the
    /// object-to-world map: 16 ε of the largest world coordinate's terms.
    pub world: f32,
}

/// 16 ε: each bound here takes a few ε (γ(3) and the like) four times over.
const WIDE: f32 = 16.0 * f32::EPSILON;

fn abs(m: Mat3) -> Mat3 {
    Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

impl PlacedRounding {
    /// `map` is `instance.affine()`, which the caller has at hand.
    pub fn new(instance: &Instance, map: &Affine3A, prototype: &Geometry) -> Self {
        let to_world = Mat3::from(map.matrix3);
        let b = &prototype.bvh.bounds;
        let extent = b.min.abs().max(b.max.abs());
        let object = extent.length();
        let world = (abs(to_world) * extent + Vec3::from(map.translation).abs()).length();
        let stretch = spectral_norm(instance.to_object);
        // The condition number only sizes the slack: the Frobenius norm
        // (≥ the spectral one) spares a second closed form per instance.
        let frobenius = (to_world.x_axis.length_squared()
            + to_world.y_axis.length_squared()
            + to_world.z_axis.length_squared())
        .sqrt();
        let cond = stretch * frobenius * (1.0 + 4.0 * f32::EPSILON);
        Self {
            stretch,
            vertex: WIDE * (stretch * world + cond * object + object),
            world: 2.0 * WIDE * world,
        }
    }

    /// What moving world point `p` (or, with no translation, vector) to
    /// object space may round it by, with the magnitude of the result.
    pub fn moved(instance: &Instance, p: Vec3, translate: bool) -> f32 {
        let shift = if translate {
            instance.to_object_translation.abs()
        } else {
            Vec3::ZERO
        };
        let terms = abs(instance.to_object) * p.abs() + shift;
        WIDE * 2.0 * terms.length()
    }
}

/// ‖m‖₂, the largest singular value, rounded up: the square root of the
/// largest eigenvalue of mᵀm by the closed form of a symmetric 3×3
/// (Smith 1961, "Eigenvalues of a symmetric 3 × 3 matrix"), in f64, so
/// that its error (a few f64 ulps of the trace) is far below f32's.
pub(crate) fn spectral_norm(m: Mat3) -> f32 {
    let a = m.as_dmat3();
    let s = a.transpose() * a;
    let diagonal = DVec3::new(s.x_axis.x, s.y_axis.y, s.z_axis.z);
    let off = DVec3::new(s.y_axis.x, s.z_axis.x, s.z_axis.y);
    let trace = diagonal.element_sum();
    let q = trace / 3.0;
    let p = (((diagonal - q).length_squared() + 2.0 * off.length_squared()) / 6.0).sqrt();
    let largest = if p > 0.0 {
        let b = (s - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
        let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
        q + 2.0 * p * (r.acos() / 3.0).cos()
    } else {
        q
    };
    // The trace bounds the largest eigenvalue of a positive semidefinite
    // matrix: the fallback where the closed form is not a number.
    let largest = if largest.is_finite() { largest } else { trace };
    let norm = (largest.max(0.0) * (1.0 + 1e-12) + 1e-300).sqrt();
    (norm as f32) * (1.0 + 2.0 * f32::EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// The norm bounds |m·u| for every unit u and is reached by some:
    /// against many random directions and a power iteration's best.
    #[test]
    fn the_spectral_norm_bounds_every_stretch_and_is_reached() {
        let mut rng = seeded(45);
        for i in 0..500 {
            let m = Mat3::from_cols(rng.cube(4.0), rng.cube(4.0), rng.cube(4.0));
            let m = if i % 5 == 0 {
                // Nearly singular.
                Mat3::from_cols(m.x_axis, m.y_axis, m.x_axis * 2.0 + m.y_axis * 1e-4)
            } else {
                m
            };
            let norm = spectral_norm(m);
            let md = m.as_dmat3();
            for _ in 0..200 {
                let u = rng.cube(2.0).as_dvec3().normalize_or_zero();
                assert!((md * u).length() <= f64::from(norm), "{m}: {norm}");
            }
            let mut u = DVec3::new(1.0, 0.3, -0.2);
            for _ in 0..200 {
                u = (md.transpose() * (md * u)).normalize_or(DVec3::X);
            }
            let reached = (md * u).length();
            assert!(f64::from(norm) <= reached * (1.0 + 1e-5) + 1e-30, "{m}");
        }
        assert_eq!(spectral_norm(Mat3::IDENTITY), 1.0 + 2.0 * f32::EPSILON);
    }
}

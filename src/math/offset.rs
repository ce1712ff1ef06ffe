//! Spawning secondary rays without self-intersection, with no global epsilon.
//!
//! Each hit carries a conservative bound on the floating-point error of its
//! position (Pharr, Jakob and Humphreys, *Physically Based Rendering*, 4th ed.,
//! section 6.8 "Managing Rounding Error"). The spawned origin is pushed along
//! the geometric normal just past that error box and then rounded away from
//! the surface. Because the bound scales with the magnitude of the
//! coordinates, the same code works at 1e-6 and at 1e5.
//!
//! We prefer this to Wächter and Binder's fixed integer offset (Ray Tracing
//! Gems 2019, chapter 6), whose 256-ulp step is 2 world units at 1e5 and whose
//! absolute floor of 1.5e-5 near the origin swamps a scene at scale 1e-6.

use glam::Vec3;

/// γ(n) = nε/(1 - nε), the bound on the relative error of n floating-point
/// operations (Higham 2002), with ε = 2⁻²⁴.
pub const fn gamma(n: i32) -> f32 {
    let e = n as f32 * (f32::EPSILON * 0.5);
    e / (1.0 - e)
}

/// The next float towards +∞ or −∞.
fn next_float(x: f32, up: bool) -> f32 {
    if x.is_infinite() {
        return x;
    }
    if up {
        if x == -0.0 || x == 0.0 {
            return f32::from_bits(1);
        }
        let bits = x.to_bits();
        f32::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
    } else {
        if x == -0.0 || x == 0.0 {
            return -f32::from_bits(1);
        }
        let bits = x.to_bits();
        f32::from_bits(if x > 0.0 { bits - 1 } else { bits + 1 })
    }
}

/// Offset `p` (with per-axis error bound `p_error`) off the surface with unit
/// geometric normal `n`, towards the side that `direction` points to.
pub fn spawn_origin(p: Vec3, p_error: Vec3, n: Vec3, direction: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = d * n;
    if direction.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut q = p + offset;
    // Round each coordinate away from p so the offset survives rounding.
    for axis in 0..3 {
        if offset[axis] > 0.0 {
            q[axis] = next_float(q[axis], true);
        } else if offset[axis] < 0.0 {
            q[axis] = next_float(q[axis], false);
        }
    }
    q
}

/// Error bound of a point computed as `Σ bᵢ pᵢ` from triangle vertices
/// (barycentric interpolation), pbrt-v4 section 6.8.5.
pub fn barycentric_error(b: [f32; 3], v: [Vec3; 3]) -> Vec3 {
    gamma(7) * ((b[0] * v[0]).abs() + (b[1] * v[1]).abs() + (b[2] * v[2]).abs())
}

/// Error bound after applying an affine map to a point with error `e`
/// (pbrt-v4 section 6.8.6, transforming points with error).
pub fn transformed_error(m: &glam::Affine3A, p: Vec3, e: Vec3) -> Vec3 {
    let abs = glam::Mat3::from_cols(
        m.matrix3.x_axis.abs().into(),
        m.matrix3.y_axis.abs().into(),
        m.matrix3.z_axis.abs().into(),
    );
    let t = Vec3::from(m.translation).abs();
    (gamma(3) + 1.0) * (abs * e) + gamma(3) * (abs * p.abs() + t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_leaves_the_error_box_on_the_right_side_at_every_scale() {
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        for scale in [1e-6f32, 1e-3, 1.0, 1e3, 1e5, 1e7] {
            let p = Vec3::new(0.7, -1.3, 2.1) * scale;
            let err = gamma(5) * p.abs();
            for dir in [n, -n] {
                let q = spawn_origin(p, err, n, dir);
                let moved = (q - p).dot(dir.dot(n).signum() * n);
                assert!(moved >= n.abs().dot(err), "scale {scale}");
                assert!(
                    (q - p).length() < 1e-5 * scale,
                    "offset too large at scale {scale}"
                );
            }
        }
    }

    #[test]
    fn next_float_steps_one_ulp() {
        assert!(next_float(1.0, true) > 1.0 && next_float(1.0, false) < 1.0);
        assert!(next_float(-1.0, true) > -1.0 && next_float(0.0, false) < 0.0);
    }
}

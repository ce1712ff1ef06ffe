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

/// The next float towards +∞ or −∞ (the plain formulation of
/// [`step_along`], which the tests compare it with).
#[cfg(test)]
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

/// `x` moved one float towards the sign of `step` (+∞ for a positive
/// step, −∞ for a negative one); unchanged for a zero or NaN step and for
/// infinite `x`. Written with selects: the sign of an offset along a
/// surface normal is data, and as branches it mispredicted often.
#[inline(always)]
fn step_along(x: f32, step: f32) -> f32 {
    let up = step > 0.0;
    let bits = x.to_bits();
    // Away from zero when x's sign is the step's, else towards it; from
    // ±0 to the smallest subnormal of the step's sign.
    let away = (x > 0.0) == up;
    let stepped = if x == 0.0 {
        if up {
            1
        } else {
            0x8000_0001
        }
    } else if away {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    };
    let moves = (up || step < 0.0) && !x.is_infinite();
    f32::from_bits(if moves { stepped } else { bits })
}

/// Offset `p` (with per-axis error bound `p_error`) off the surface with unit
/// geometric normal `n`, towards the side that `direction` points to.
#[inline]
pub fn spawn_origin(p: Vec3, p_error: Vec3, n: Vec3, direction: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = d * n;
    if direction.dot(n) < 0.0 {
        offset = -offset;
    }
    let q = p + offset;
    // Round each coordinate away from p so the offset survives rounding.
    Vec3::new(
        step_along(q.x, offset.x),
        step_along(q.y, offset.y),
        step_along(q.z, offset.z),
    )
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

    /// The select form steps exactly as the plain one, for every kind of
    /// float and step: zeros of both signs, subnormals, the largest finite
    /// values, infinities, and zero and NaN steps (which move nothing).
    #[test]
    fn step_along_is_next_float_in_the_step_direction() {
        let mut xs = vec![
            0.0f32,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1.0,
            -1.0,
        ];
        let mut state = 0x1234_5678u32;
        for _ in 0..20_000 {
            // xorshift32 (Marsaglia 2003): every bit pattern but zero.
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let x = f32::from_bits(state);
            if !x.is_nan() {
                xs.push(x);
            }
        }
        for &x in &xs {
            for step in [1e-3f32, -1e-3, 0.0, -0.0, f32::NAN] {
                let want = if step > 0.0 {
                    next_float(x, true)
                } else if step < 0.0 {
                    next_float(x, false)
                } else {
                    x
                };
                let got = step_along(x, step);
                assert_eq!(got.to_bits(), want.to_bits(), "{x:e} step {step}");
            }
        }
    }

    #[test]
    fn next_float_steps_one_ulp() {
        assert!(next_float(1.0, true) > 1.0 && next_float(1.0, false) < 1.0);
        assert!(next_float(-1.0, true) > -1.0 && next_float(0.0, false) < 0.0);
    }
}

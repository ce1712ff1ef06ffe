//! A ray with an explicit parametric interval `[tmin, tmax]`.

use glam::Vec3;
use wide::f32x8;

/// `origin + t * direction` for `t` in `[tmin, tmax]`. The direction need not
/// be unit length: rays moved into object space keep world-space `t`.
/// `repr(C)`: the fields lie in [`Ray::components`]'s order, so a ray is
/// one 32-byte load into an `f32x8`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

/// Up to eight rays transposed into lanes for 8-wide SIMD:
/// `[ox, oy, oz, dx, dy, dz, tmin, tmax][lane]`. Lanes past the last ray
/// repeat the first one (callers mask them off). One 8×8 transpose in
/// registers: a ray's eight components are exactly one `f32x8`.
#[inline(always)]
pub fn ray_lanes(rays: &[Ray]) -> [f32x8; 8] {
    // A full packet (the common case) indexes with no per-lane choice or
    // bounds check.
    let rows = match <&[Ray; 8]>::try_from(rays) {
        Ok(full) => full.each_ref().map(|r| f32x8::from(r.components())),
        Err(_) => std::array::from_fn(|lane| {
            f32x8::from(rays[if lane < rays.len() { lane } else { 0 }].components())
        }),
    };
    f32x8::transpose(rows)
}

/// The closest-hit order of two hits on one ray, (t, primitive id):
/// true if the hit at `t` on primitive `id` comes before the one at
/// `than_t` on `than_id`, by smaller t and on equal t (a ray through an
/// edge two triangles share) by the smaller id. A total order, so a
/// closest hit does not depend on the order its candidates are met in:
/// the one rule of the triangle lanes and of traversal (`accel::hit`).
#[inline(always)]
pub fn hit_before(t: f32, id: u32, than_t: f32, than_id: u32) -> bool {
    t < than_t || (t == than_t && id < than_id)
}

impl Ray {
    /// `[ox, oy, oz, dx, dy, dz, tmin, tmax]`: the order of ray files'
    /// records and of [`ray_lanes`].
    #[inline]
    pub fn components(&self) -> [f32; 8] {
        [
            self.origin.x,
            self.origin.y,
            self.origin.z,
            self.direction.x,
            self.direction.y,
            self.direction.z,
            self.tmin,
            self.tmax,
        ]
    }

    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    pub fn segment(origin: Vec3, direction: Vec3, tmax: f32) -> Self {
        Self {
            origin,
            direction,
            tmin: 0.0,
            tmax,
        }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }

    /// True if every component is finite and the direction is not zero.
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite() && self.direction.is_finite() && self.direction != Vec3::ZERO
    }
}

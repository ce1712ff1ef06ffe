//! SIMD lanes: the one lane width, the lanes a mask selects, and three
//! coordinates in `wide::f32x8` lanes with glam's `Vec3` arithmetic in its
//! order (no fused multiply-adds), so each lane is bit for bit what glam
//! computes for that lane's vector: for code that does eight points' or
//! rays' scalar work at once.

use glam::Vec3;
use wide::f32x8;

/// Values per SIMD register (one per `f32x8` lane): the rays of a packet,
/// the samples of a batch, the triangles of a leaf block.
pub const LANES: usize = 8;

/// The lanes of `mask` that are set (bit `i` for lane `i`), in order.
#[inline(always)]
pub fn mask_lanes(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

/// Three coordinates in lanes, with glam's `Vec3` arithmetic in its order.
#[derive(Debug, Clone, Copy)]
pub struct Lanes3 {
    pub x: f32x8,
    pub y: f32x8,
    pub z: f32x8,
}

impl Lanes3 {
    #[inline]
    pub fn splat(v: Vec3) -> Self {
        Self {
            x: f32x8::splat(v.x),
            y: f32x8::splat(v.y),
            z: f32x8::splat(v.z),
        }
    }

    #[inline]
    pub fn dot(self, o: Self) -> f32x8 {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }

    #[inline]
    pub fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// `Vec3::try_normalize`: the unit vector, and whether it exists.
    #[inline]
    pub fn try_normalize(self) -> (Self, f32x8) {
        let rcp = f32x8::ONE / self.dot(self).sqrt();
        let ok = rcp.is_finite() & rcp.simd_gt(f32x8::ZERO);
        let unit = Self {
            x: self.x * rcp,
            y: self.y * rcp,
            z: self.z * rcp,
        };
        (unit, ok)
    }

    /// The eight vectors, lane by lane.
    #[inline]
    pub fn to_vecs(self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|i| Vec3::new(x[i], y[i], z[i]))
    }

    /// `Vec3::normalize`: the vector times the reciprocal of its length.
    #[inline]
    pub fn normalize(self) -> Self {
        self.try_normalize().0
    }

    /// `self + t * v`, as glam computes `a + t * v` for a `Vec3` and an `f32`.
    #[inline]
    pub fn add_scaled(self, t: f32x8, v: Self) -> Self {
        Self {
            x: self.x + t * v.x,
            y: self.y + t * v.y,
            z: self.z + t * v.z,
        }
    }
}

impl std::ops::Sub for Lanes3 {
    type Output = Self;

    /// `self - o`, lane by lane.
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

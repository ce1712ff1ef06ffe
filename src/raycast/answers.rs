//! What the queries of [`super::Mesh`] answer, in the shapes a binding
//! copies into arrays: a ray's first hit ([`FirstHit`], or written
//! straight into columns, [`FirstHitColumns`]), every crossing of a run of
//! rays ([`Crossings`]), a point's nearest surface point
//! ([`ClosestPoint`]).

use glam::{DVec3, Vec3};

/// One ray's first hit, or [`FirstHit::MISS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstHit {
    /// Along the ray, in its direction's lengths; infinite on a miss.
    pub t: f32,
    /// The face hit (in the copies' numbering for a placed mesh); -1 on a miss.
    pub face: i64,
    /// Barycentric coordinates of the face's second and third vertices.
    pub u: f32,
    pub v: f32,
    /// The unit geometric normal of the face in world space, by the
    /// right-hand rule over its vertex order (trimesh's face normal).
    pub normal: Vec3,
    /// Where the ray meets the plane of the face, in world space and
    /// float64 ([`exact::plane_hit`](super::exact::plane_hit)): on the face's plane to float64's
    /// precision, wherever the mesh lies.
    pub point: DVec3,
}

impl FirstHit {
    /// What a ray that hits nothing answers: t infinite, face -1, NaN else.
    pub const MISS: FirstHit = FirstHit {
        t: f32::INFINITY,
        face: -1,
        u: f32::NAN,
        v: f32::NAN,
        normal: Vec3::NAN,
        point: DVec3::NAN,
    };

    /// A miss as Open3D answers one: t infinite, face -1, 0 else.
    pub const ZEROED_MISS: FirstHit = FirstHit {
        u: 0.0,
        v: 0.0,
        normal: Vec3::ZERO,
        point: DVec3::ZERO,
        ..FirstHit::MISS
    };
}

/// Where [`Mesh::first_hits_into`](super::Mesh::first_hits_into) writes its rays' first hits: a column
/// a quantity, row i for ray i (three values a row for `normal` and
/// `point`); an empty column is not asked for.
pub struct FirstHitColumns<'a> {
    /// [`FirstHit::t`], a value a ray.
    pub t: &'a mut [f32],
    /// [`FirstHit::face`], a value a ray.
    pub face: &'a mut [i64],
    /// [`FirstHit::u`], a value a ray.
    pub u: &'a mut [f32],
    /// [`FirstHit::v`], a value a ray.
    pub v: &'a mut [f32],
    /// [`FirstHit::normal`], x, y and z a ray.
    pub normal: &'a mut [f32],
    /// [`FirstHit::point`], x, y and z a ray.
    pub point: &'a mut [f64],
    /// What a miss writes: [`FirstHit::MISS`], or a binding's own
    /// ([`FirstHit::ZEROED_MISS`], Open3D's).
    pub miss: FirstHit,
}

impl FirstHitColumns<'_> {
    /// Each column's length and values a row.
    pub(super) fn lens(&self) -> [(usize, usize); 6] {
        [
            (self.t.len(), 1),
            (self.face.len(), 1),
            (self.u.len(), 1),
            (self.v.len(), 1),
            (self.normal.len(), 3),
            (self.point.len(), 3),
        ]
    }

    /// Writes a hit's t, face and barycentrics into row `i` of each of
    /// their columns asked for, where the normal and the point are not.
    #[inline(always)]
    pub(super) fn put_plain(&mut self, i: usize, t: f32, face: i64, u: f32, v: f32) {
        debug_assert!(self.normal.is_empty() && self.point.is_empty());
        if let Some(o) = self.t.get_mut(i) {
            *o = t;
        }
        if let Some(o) = self.face.get_mut(i) {
            *o = face;
        }
        if let Some(o) = self.u.get_mut(i) {
            *o = u;
        }
        if let Some(o) = self.v.get_mut(i) {
            *o = v;
        }
    }

    /// Writes `hit` into row `i` of each column asked for.
    #[inline(always)]
    pub(super) fn put(&mut self, i: usize, hit: &FirstHit) {
        if let Some(o) = self.t.get_mut(i) {
            *o = hit.t;
        }
        if let Some(o) = self.face.get_mut(i) {
            *o = hit.face;
        }
        if let Some(o) = self.u.get_mut(i) {
            *o = hit.u;
        }
        if let Some(o) = self.v.get_mut(i) {
            *o = hit.v;
        }
        if let Some(o) = self.normal.get_mut(3 * i..3 * i + 3) {
            hit.normal.write_to_slice(o);
        }
        if let Some(o) = self.point.get_mut(3 * i..3 * i + 3) {
            hit.point.write_to_slice(o);
        }
    }
}

/// Every crossing of the surface along a run of rays, column by column,
/// ray after ray and each ray's nearest first ([`Mesh::all_hits`](super::Mesh::all_hits)): the
/// arrays a binding hands out, with no record per crossing in between.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Crossings {
    /// How many crossings each ray has.
    pub counts: Vec<u32>,
    pub t: Vec<f32>,
    /// The face crossed.
    pub face: Vec<i64>,
    /// Barycentric weights of the face's second and third vertices where
    /// the ray meets the face's plane, in float64 ([`exact::plane_hit`](super::exact::plane_hit));
    /// empty unless asked for.
    pub u: Vec<f64>,
    pub v: Vec<f64>,
}

/// The nearest surface point to a query point, or [`ClosestPoint::MISS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// In world space and float64, on the face as given
    /// ([`exact::closest_on_triangle`](super::exact::closest_on_triangle)).
    pub point: DVec3,
    /// Its distance (float64); negative inside where a signed distance
    /// was asked.
    pub distance: f64,
    /// Barycentric weights of the face's second and third vertices at it.
    pub u: f64,
    pub v: f64,
    /// The face it lies on; -1 where none lies within reach.
    pub face: i64,
}

impl ClosestPoint {
    /// Nothing within reach: point NaN, distance infinite, face -1.
    pub const MISS: ClosestPoint = ClosestPoint {
        point: DVec3::NAN,
        distance: f64::INFINITY,
        u: f64::NAN,
        v: f64::NAN,
        face: -1,
    };
}

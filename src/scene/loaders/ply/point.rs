//! A vertex position as the body readers keep it: float32 for a scene,
//! float64 where the load asks for the file's own coordinates
//! ([`Coordinates::Float64`](crate::scene::loaders::Coordinates)). Each
//! coordinate is read as f64 (exact for every PLY scalar type, a `float`
//! widened) and rounded once to the point's type, so a float32 point is
//! the same bits either way.

use glam::{DVec3, Vec3};

pub(super) trait Point: Copy + Default + Send + Sync {
    fn from_f64s(p: [f64; 3]) -> Self;

    /// The mesh's float32 positions, and its float64 ones where read.
    fn split(points: Vec<Self>) -> (Vec<Vec3>, Option<Vec<DVec3>>);
}

impl Point for Vec3 {
    #[inline]
    fn from_f64s(p: [f64; 3]) -> Self {
        DVec3::from(p).as_vec3()
    }

    fn split(points: Vec<Self>) -> (Vec<Vec3>, Option<Vec<DVec3>>) {
        (points, None)
    }
}

impl Point for DVec3 {
    #[inline]
    fn from_f64s(p: [f64; 3]) -> Self {
        DVec3::from(p)
    }

    fn split(points: Vec<Self>) -> (Vec<Vec3>, Option<Vec<DVec3>>) {
        (points.iter().map(|p| p.as_vec3()).collect(), Some(points))
    }
}

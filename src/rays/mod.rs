//! Ray sets for testing intersection against a mesh (`strata rays`), one
//! file per kind (the `camera` set in [`view`]), and the binary ray and
//! hit files they travel in ([`file`]):
//!
//! | kind      | rays                                                                   |
//! |-----------|------------------------------------------------------------------------|
//! | `random`  | chords of the mesh's bounding sphere: two uniform points on it          |
//! | `camera`  | primary rays of a pinhole view of the whole mesh, one per pixel         |
//! | `grazing` | aimed at a random point of a random triangle, 0.01° to 1° off its plane |
//! | `edges`   | aimed exactly (as f32 allows) at a point of a shared edge or vertex     |
//! | `inside`  | from random points inside the mesh, in random directions                |
//!
//! `grazing` and `edges` rays reach their target at `t = 1`: the direction
//! is `target − origin`, computed from the exact target in f64 (see
//! [`aimed_ray`]). All rays have `tmin = 0` and `tmax = +inf`.
//!
//! Each ray draws from its own seeded `rand` stream, a function of (seed,
//! kind, ray index), so a set is reproducible on any machine and thread
//! count, and (except for `camera`, whose image size follows the ray count)
//! ray `i` does not depend on how many rays are asked for.

pub mod edges;
pub mod file;
pub mod grazing;
pub mod inside;
pub mod random;
pub mod topology;
pub mod view;

use crate::math::{Aabb, Ray};
use crate::sampling::stream::{item_stream, StreamRng};
use glam::{DVec3, Vec3};
use rand::RngExt;
use rayon::prelude::*;

crate::mode::mode_enum! {
    /// The kinds of ray set. Closed set: [`generate`] matches on it.
    pub enum RayKind("ray kind") {
        Random = "random",
        Camera = "camera",
        Grazing = "grazing",
        Edges = "edges",
        Inside = "inside",
    }
}

impl RayKind {
    /// The parameter `t` at which every ray of this kind reaches the point
    /// it was aimed at, for kinds that aim at one.
    pub fn target_t(self) -> Option<f32> {
        matches!(self, RayKind::Grazing | RayKind::Edges).then_some(1.0)
    }
}

/// Random numbers for one ray: its own seeded `rand` stream
/// ([`crate::sampling::stream::item_stream`] of (seed, kind, ray)), so ray
/// `i` does not depend on how many rays are made or on which thread.
pub struct Stream(StreamRng);

impl Stream {
    pub fn new(seed: u32, kind: RayKind, index: u32) -> Self {
        Self(item_stream(seed, kind as u32, index))
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        self.0.random()
    }

    /// Uniform in [0, 1) with 53 random bits, for f64 geometry.
    pub fn next_f64(&mut self) -> f64 {
        self.0.random()
    }

    /// Uniform below `n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        self.0.random_range(0..n)
    }

    /// A uniform direction (Marsaglia's rejection: a point in the unit ball).
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
            );
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

/// What every kind needs to know about the mesh.
pub struct MeshInfo<'a> {
    pub triangles: &'a [[Vec3; 3]],
    pub bounds: Aabb,
    /// Centre and radius of a sphere around the mesh (of its bounding box).
    pub center: DVec3,
    pub radius: f64,
}

impl<'a> MeshInfo<'a> {
    pub fn new(triangles: &'a [[Vec3; 3]]) -> Result<Self, String> {
        if triangles.is_empty() {
            return Err("the mesh has no triangles".to_string());
        }
        let bounds = triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(Aabb::from_points(t)));
        let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
        let radius = 0.5 * (hi - lo).length();
        if !(radius > 0.0 && radius.is_finite()) {
            return Err("the mesh has no extent (all vertices coincide)".to_string());
        }
        Ok(Self {
            triangles,
            bounds,
            center: 0.5 * (lo + hi),
            radius,
        })
    }
}

/// A generator of one kind, set up once per mesh.
pub trait Generator: Sync {
    /// One attempt at a ray; `None` asks for another attempt with more draws
    /// from the same stream.
    fn ray(&self, index: u32, rng: &mut Stream) -> Option<Ray>;
}

/// Attempts per ray before [`generate`] gives up.
const MAX_ATTEMPTS: u32 = 1000;

/// `n` rays of `kind` against `triangles` (in scene order), from `seed`.
/// Errors say why the mesh cannot give this kind (no triangles, no shared
/// edges, no inside).
pub fn generate(
    kind: RayKind,
    triangles: &[[Vec3; 3]],
    n: usize,
    seed: u32,
) -> Result<Vec<Ray>, String> {
    let info = MeshInfo::new(triangles)?;
    match kind {
        RayKind::Random => run(kind, &random::Chords::new(&info), n, seed),
        RayKind::Camera => run(kind, &view::Pinhole::new(&info, n, seed), n, seed),
        RayKind::Grazing => run(kind, &grazing::Grazing::new(&info)?, n, seed),
        RayKind::Edges => run(kind, &edges::Edges::new(&info)?, n, seed),
        RayKind::Inside => run(kind, &inside::Inside::new(&info)?, n, seed),
    }
}

fn run<G: Generator>(kind: RayKind, g: &G, n: usize, seed: u32) -> Result<Vec<Ray>, String> {
    let n = u32::try_from(n).map_err(|_| format!("at most {} rays per set", u32::MAX))?;
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Stream::new(seed, kind, i);
            (0..MAX_ATTEMPTS)
                .find_map(|_| g.ray(i, &mut rng).filter(Ray::is_valid))
                .ok_or_else(|| format!("could not make {kind} ray {i} in {MAX_ATTEMPTS} attempts"))
        })
        .collect()
}

/// A ray from `origin` (rounded to f32) towards `target`, an exact point
/// in f64: the direction is `target − origin` computed in f64 and rounded
/// once, so the ray's line passes within about 2⁻²⁴ |direction| of the
/// target however far from the origin of coordinates the mesh is, and it
/// reaches the target at `t = 1`. (Rounding the target itself to f32 would
/// move it by half an f32 spacing: 0.004 at 1e5, more than a small
/// triangle there.) `None` if the direction rounds to zero.
pub fn aimed_ray(origin: DVec3, target: DVec3) -> Option<Ray> {
    let origin = origin.as_vec3();
    let direction = (target - origin.as_dvec3()).as_vec3();
    (direction != Vec3::ZERO).then(|| Ray::new(origin, direction))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed octahedron, consistently wound (normals outward).
    pub(crate) fn octahedron(scale: f32, offset: Vec3) -> Vec<[Vec3; 3]> {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * scale + offset;
        let (px, nx, py, ny, pz, nz) = (
            p(1.0, 0.0, 0.0),
            p(-1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(0.0, -1.0, 0.0),
            p(0.0, 0.0, 1.0),
            p(0.0, 0.0, -1.0),
        );
        vec![
            [px, py, pz],
            [py, nx, pz],
            [nx, ny, pz],
            [ny, px, pz],
            [py, px, nz],
            [nx, py, nz],
            [ny, nx, nz],
            [px, ny, nz],
        ]
    }

    #[test]
    fn every_kind_is_deterministic_and_valid() {
        let tris = octahedron(1.0, Vec3::ZERO);
        for kind in RayKind::ALL {
            let a = generate(kind, &tris, 200, 7).unwrap();
            let b = generate(kind, &tris, 200, 7).unwrap();
            let c = generate(kind, &tris, 200, 8).unwrap();
            assert_eq!(a.len(), 200);
            assert_eq!(a, b, "{kind}: same seed, same rays");
            assert_ne!(a, c, "{kind}: another seed, other rays");
            assert!(a.iter().all(|r| r.is_valid() && r.tmin == 0.0), "{kind}");
            // Ray i does not depend on how many were asked for.
            if kind != RayKind::Camera {
                let fewer = generate(kind, &tris, 50, 7).unwrap();
                assert_eq!(&fewer[..], &a[..50], "{kind}");
            }
        }
    }

    #[test]
    fn kinds_parse_and_print() {
        for kind in RayKind::ALL {
            assert_eq!(kind.name().parse::<RayKind>().unwrap(), kind);
        }
        assert!("edge".parse::<RayKind>().unwrap_err().contains("edges"));
    }

    #[test]
    fn empty_and_pointlike_meshes_are_refused() {
        assert!(generate(RayKind::Random, &[], 10, 0).is_err());
        assert!(generate(RayKind::Random, &[[Vec3::ONE; 3]], 10, 0).is_err());
    }
}

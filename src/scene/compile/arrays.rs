//! A mesh given as arrays (a vertex array and a face array, as numpy and
//! the Python package hand them over) compiled into [`Geometry`] the way a
//! mesh file is: indexed until the BVH is built, then written once in leaf
//! order. Face `i` is primitive `i`.

use super::mesh::{triangle_geometry, TriangleSource};
use crate::accel::BuildQuality;
use crate::geometry::{Geometry, MeshRange};
use crate::scene::loaders::{first_face_using, used_vertices};
use glam::Vec3;

/// What is wrong with a mesh's arrays, in the names of the arguments
/// (`vertices`, `faces`) that carried them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshArraysError {
    /// A NaN or infinite coordinate of a vertex that face `face` uses,
    /// quoted as given.
    #[error("vertices[{vertex}] is not finite: {value:?} (faces[{face}] uses it)")]
    NotFinite {
        vertex: usize,
        value: [f64; 3],
        face: usize,
    },
    /// A float64 vertex that face `face` uses too far from the mesh's
    /// centre for float32 (its coordinates relative to the centre
    /// overflow), quoted as given.
    #[error(
        "vertices[{vertex}] is not finite as float32 relative to the mesh's centre: {value:?} (faces[{face}] uses it)"
    )]
    BeyondFloat32 {
        vertex: usize,
        value: [f64; 3],
        face: usize,
    },
    #[error("faces[{face}][{corner}] = {index} is out of range for {vertices} vertices")]
    IndexOutOfRange {
        face: usize,
        corner: usize,
        index: u32,
        vertices: usize,
    },
    #[error("faces has {faces} rows; at most {max} triangles fit in one mesh")]
    TooManyFaces { faces: usize, max: usize },
    /// A mesh too large or too small for float32's ray tests (see
    /// [`EXTENT`]).
    #[error(
        "the vertices lie up to {extent:.3e} from the mesh's centre, where strata's float32 ray tests are exact from {:e} to {:e}: scale them (t, points and distances scale with them)",
        EXTENT.start(),
        EXTENT.end()
    )]
    Extent { extent: f64 },
}

/// The distances of a mesh's farthest vertex from its centre (in any
/// coordinate) at which its ray tests answer as they do at size 1, 0
/// aside. The watertight test multiplies three coordinates to find t,
/// which overflows float32 past about 1e12 and loses bits to subnormals
/// below about 1e-11: the unit icosphere scaled by 1e14 and 1e-14 counted
/// 16 and 33 of 2,000 random rays' crossings wrongly, and intersect
/// missed nearly every hit; scaled by powers of two from 2⁻³⁷ (7e-12) to
/// 2³⁹ (5e11) every t was the unit sphere's scaled, bit for bit, and at
/// 2⁻³⁹ 86 of them were a float32 step off.
pub const EXTENT: std::ops::RangeInclusive<f64> = 1e-11..=1e12;

/// `Err` where a mesh whose vertices lie up to `extent` from its centre
/// is outside [`EXTENT`] (an empty mesh, or one of a single point, spans 0).
pub fn check_extent(extent: f64) -> Result<(), MeshArraysError> {
    match extent == 0.0 || EXTENT.contains(&extent) {
        true => Ok(()),
        false => Err(MeshArraysError::Extent { extent }),
    }
}

/// Compile one triangle mesh from its vertices and faces (indices into
/// `vertices`), with no transform, material or attributes: what ray
/// queries need. Every index must be in range and every vertex a face
/// uses finite; a vertex no face uses is never read, so it may be
/// anything (a depth image's mesh keeps its missing pixels as NaN
/// vertices, which Open3D and Embree take). Degenerate faces are kept (no
/// ray hits them) so that face ids stay the caller's.
pub fn mesh_geometry(
    vertices: Vec<Vec3>,
    faces: Vec<[u32; 3]>,
    quality: BuildQuality,
) -> Result<Geometry, MeshArraysError> {
    // Planes take ids counting down from u32::MAX; keep well clear of them.
    let max = (u32::MAX / 2) as usize;
    if faces.len() > max {
        return Err(MeshArraysError::TooManyFaces {
            faces: faces.len(),
            max,
        });
    }
    for (face, f) in faces.iter().enumerate() {
        if let Some(corner) = f.iter().position(|&k| k as usize >= vertices.len()) {
            return Err(MeshArraysError::IndexOutOfRange {
                face,
                corner,
                index: f[corner],
                vertices: vertices.len(),
            });
        }
    }
    // The common case, every vertex finite and within reach, needs no pass
    // over the faces; otherwise only the vertices faces use count.
    let all_within =
        vertices.iter().all(|v| v.is_finite()) && check_extent(extent_of(vertices.iter())).is_ok();
    if !all_within {
        let used = used_vertices(&faces, vertices.len());
        let first_bad = (0..vertices.len()).find(|&i| used[i] && !vertices[i].is_finite());
        if let Some(vertex) = first_bad {
            let value = vertices[vertex].as_dvec3().to_array();
            let face = first_face_using(&faces, vertex);
            return Err(MeshArraysError::NotFinite {
                vertex,
                value,
                face,
            });
        }
        let in_use = vertices
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .map(|(v, _)| v);
        check_extent(extent_of(in_use))?;
    }
    let count = faces.len() as u32;
    let meshes = vec![MeshRange {
        name: "mesh".into(),
        count,
        ..MeshRange::default()
    }];
    let source = TriangleSource::Indexed {
        positions: vertices,
        indices: faces,
    };
    // Queries from arrays come in numbers the build does not know.
    let choice = quality.choose(count as usize, None);
    let geometry = triangle_geometry(meshes, vec![source], choice);
    Ok(geometry.expect("every vertex a face uses was checked finite and within EXTENT above"))
}

/// The largest coordinate of `vertices` by magnitude, what
/// [`check_extent`] takes.
fn extent_of<'a>(vertices: impl Iterator<Item = &'a Vec3>) -> f64 {
    let farthest = vertices.map(|v| v.abs().max_element()).fold(0.0, f32::max);
    f64::from(farthest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::pages::Pages;
    use crate::math::Ray;

    fn quad() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        (v, vec![[0, 1, 2], [0, 2, 3]])
    }

    /// A mesh is refused where float32's ray tests would answer wrongly,
    /// with what to do; the ends of the range, and nothing, are taken.
    #[test]
    fn a_mesh_too_large_or_too_small_for_float32_is_refused() {
        let (v, f) = quad();
        for scale in [1e13f32, 5e-12] {
            let scaled = v.iter().map(|&p| p * scale).collect();
            let e = mesh_geometry(scaled, f.clone(), BuildQuality::Auto).unwrap_err();
            assert!(matches!(e, MeshArraysError::Extent { .. }), "{e}");
            assert!(e.to_string().contains("scale them"), "{e}");
        }
        for scale in [1e12f32, 1.01e-11, 0.0] {
            let scaled = v.iter().map(|&p| p * scale).collect();
            mesh_geometry(scaled, f.clone(), BuildQuality::Auto).unwrap();
        }
        mesh_geometry(Vec::new(), Vec::new(), BuildQuality::Auto).unwrap();
    }

    /// A large mesh from arrays, whose queries come in numbers the build
    /// does not know, has its tree put on huge pages; a small one not.
    #[test]
    fn a_large_mesh_from_arrays_asks_for_huge_pages() {
        let n = 400u32;
        let vertices = (0..n * n)
            .map(|i| Vec3::new((i % n) as f32, (i / n) as f32, 0.0))
            .collect();
        let faces = (0..n * (n - 1)).map(|i| [i, i + 1, i + n]).collect();
        let large = mesh_geometry(vertices, faces, BuildQuality::Auto).unwrap();
        assert_eq!(large.bvh().pages, Pages::Huge);
        let (v, f) = quad();
        let small = mesh_geometry(v, f, BuildQuality::Auto).unwrap();
        assert_eq!(small.bvh().pages, Pages::Small);
    }

    #[test]
    fn face_ids_are_the_callers() {
        let (v, f) = quad();
        let g = mesh_geometry(v, f, BuildQuality::Auto).unwrap();
        assert_eq!(g.triangle_count, 2);
        let down = Vec3::new(0.0, 0.0, -1.0);
        // Below the diagonal x = y lies face 0, above it face 1.
        let hit = g
            .intersect(&Ray::new(Vec3::new(0.5, -0.5, 1.0), down))
            .unwrap();
        assert_eq!((hit.prim, hit.t), (0, 1.0));
        let hit = g
            .intersect(&Ray::new(Vec3::new(-0.5, 0.5, 1.0), down))
            .unwrap();
        assert_eq!((hit.prim, hit.t), (1, 1.0));
    }

    #[test]
    fn bad_arrays_are_named() {
        let (mut v, f) = quad();
        let err = mesh_geometry(v.clone(), vec![[0, 1, 4]], BuildQuality::Auto).unwrap_err();
        assert_eq!(
            err.to_string(),
            "faces[0][2] = 4 is out of range for 4 vertices"
        );
        v[3].y = f32::NAN;
        let err = mesh_geometry(v, f, BuildQuality::Auto).unwrap_err();
        assert_eq!(
            err.to_string(),
            "vertices[3] is not finite: [-1.0, NaN, 0.0] (faces[1] uses it)"
        );
    }

    /// A vertex no face uses is never traced: NaN, infinite or far past
    /// [`EXTENT`], it is taken, and the mesh answers as it does without
    /// it; the same value in a vertex a face uses is refused.
    #[test]
    fn a_vertex_no_face_uses_may_be_anything() {
        let (v, f) = quad();
        let plain = mesh_geometry(v.clone(), f.clone(), BuildQuality::Auto).unwrap();
        for bad in [f32::NAN, f32::INFINITY, 1e30] {
            // Unused, first and last, so that indices past it shift too.
            let mut with = vec![Vec3::new(bad, 0.0, 0.0)];
            with.extend(&v);
            with.push(Vec3::new(0.0, bad, 0.0));
            let shifted: Vec<[u32; 3]> = f.iter().map(|t| t.map(|k| k + 1)).collect();
            let g = mesh_geometry(with.clone(), shifted.clone(), BuildQuality::Auto).unwrap();
            for (x, y) in [(0.5, -0.5), (-0.5, 0.5), (0.9, 0.95), (2.0, 0.0)] {
                let ray = Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
                let (a, b) = (g.intersect(&ray), plain.intersect(&ray));
                assert_eq!(a.map(|h| (h.prim, h.t)), b.map(|h| (h.prim, h.t)), "{bad}");
            }
            let mut used = shifted;
            used[1][2] = 5;
            let e = mesh_geometry(with, used, BuildQuality::Auto).unwrap_err();
            match bad.is_finite() {
                true => assert!(matches!(e, MeshArraysError::Extent { .. }), "{e}"),
                false => assert!(
                    e.to_string().starts_with("vertices[5] is not finite")
                        && e.to_string().ends_with("(faces[1] uses it)"),
                    "{e}"
                ),
            }
        }
    }

    #[test]
    fn an_empty_mesh_hits_nothing() {
        let g = mesh_geometry(Vec::new(), Vec::new(), BuildQuality::Auto).unwrap();
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(g.intersect(&ray).is_none());
    }
}

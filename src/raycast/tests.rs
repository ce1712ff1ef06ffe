//! A placed mesh answers as a mesh of its copies; a hit's normal and
//! point are its world triangle's; every query counts a hit at `t_max`
//! as a binding asks for `(0, t_max]`, with no nudge.

use super::*;
use crate::scene::loaders::test_files::{temp_dir, write};
use glam::{Mat3, Quat};
use rand::{RngExt, SeedableRng};

/// The cube of side 2 around the origin, two triangles a face, wound
/// outwards.
fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v = (0..8)
        .map(|i| {
            let bit = |k: u32| if i >> k & 1 == 1 { 1.0 } else { -1.0 };
            Vec3::new(bit(0), bit(1), bit(2))
        })
        .collect();
    let faces = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (v, faces)
}

fn cube_mesh() -> Mesh {
    let (v, f) = cube();
    Mesh::new(v, f, BuildQuality::Auto).unwrap()
}

/// Maps that stretch, shear, mirror and overlap the copies.
fn maps() -> Vec<Affine3A> {
    vec![
        Affine3A::IDENTITY,
        Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.0),
            Quat::from_rotation_y(0.4),
            Vec3::new(0.7, 0.2, -0.3),
        ),
        Affine3A::from_mat3_translation(
            Mat3::from_cols(
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.3, 1.0, 0.0),
                Vec3::new(0.0, 0.2, 0.8),
            ),
            Vec3::new(3.0, 0.0, 1.0),
        ),
    ]
}

/// A placed cube and a mesh of its copies (its `triangles()`).
fn placed_and_copies() -> (Mesh, Mesh) {
    let placed = cube_mesh().place(&maps(), BuildQuality::Auto).unwrap();
    let tris = placed.triangles();
    let vertices: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let faces = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let copies = Mesh::new(vertices, faces, BuildQuality::Auto).unwrap();
    (placed, copies)
}

/// Rays between random points around the copies, and points among them.
fn rays_and_points(n: usize) -> (Vec<Ray>, Vec<Vec3>) {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(56);
    let mut point = move || Vec3::new(rng.random(), rng.random(), rng.random()) * 8.0 - 3.0;
    let rays = (0..n)
        .map(|_| {
            let (a, b) = (point(), point());
            Ray::new(a, b - a)
        })
        .collect();
    let points = (0..n).map(|_| point()).collect();
    (rays, points)
}

#[test]
fn a_placed_mesh_answers_as_a_mesh_of_its_copies() {
    let (placed, copies) = placed_and_copies();
    assert!(placed.is_placed() && !copies.is_placed());
    assert_eq!(placed.triangle_count(), 36);
    assert_eq!(placed.triangle_count(), copies.triangle_count());
    assert_eq!(placed.bounds(), copies.bounds());
    let (rays, points) = rays_and_points(2000);
    // Crossings, counts, inside and nearest points are the copies' bit for
    // bit (each candidate triangle moved to world space as they hold it).
    let (mut a, mut b) = (Crossings::default(), Crossings::default());
    placed.all_hits(&rays, &mut a, true);
    copies.all_hits(&rays, &mut b, true);
    assert_eq!((&a.t, &a.face, &a.counts), (&b.t, &b.face, &b.counts));
    // Each crossing's barycentrics put it on its face.
    assert_eq!((a.u.len(), a.v.len()), (a.t.len(), a.t.len()));
    assert!(a
        .u
        .iter()
        .zip(&a.v)
        .all(|(&u, &v)| u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9));
    assert!(a.t.len() > 1000, "{} crossings", a.t.len());
    let mut counts = vec![0; rays.len()];
    placed.count_hits(&rays, &mut counts);
    assert_eq!(counts, a.counts);
    let (mut ia, mut ib) = (vec![false; points.len()], vec![false; points.len()]);
    placed.contains(&points, &mut ia);
    copies.contains(&points, &mut ib);
    assert_eq!(ia, ib);
    for &p in &points {
        for signed in [false, true] {
            let (x, y) = (
                placed.closest_point(p.as_dvec3(), p, 1.5, signed),
                copies.closest_point(p.as_dvec3(), p, 1.5, signed),
            );
            assert!(x == y || (x.face == -1 && y.face == -1), "{p}: {x:?} {y:?}");
        }
    }
    // First hits are walked in each copy's own space, so t and the
    // barycentrics may differ by rounding; the face (away from edges) and
    // its world normal, computed from the same vertices, do not.
    let mut x = vec![FirstHit::MISS; rays.len()];
    let mut y = vec![FirstHit::MISS; rays.len()];
    placed.first_hits(&rays, &mut x, true);
    copies.first_hits(&rays, &mut y, true);
    let mut compared = 0;
    for (i, (x, y)) in x.iter().zip(&y).enumerate() {
        assert_eq!(x.face == -1, y.face == -1, "ray {i}");
        if x.face == -1 {
            assert!(x.t == f32::INFINITY && x.u.is_nan() && x.point.is_nan());
            continue;
        }
        assert!((x.t - y.t).abs() <= 1e-5 * y.t, "ray {i}: {x:?} {y:?}");
        let near_edge = [y.u, y.v, 1.0 - y.u - y.v].iter().any(|&b| b < 1e-3);
        if !near_edge {
            assert_eq!((x.face, x.normal), (y.face, y.normal), "ray {i}");
            assert!((x.point - y.point).length() <= 1e-5 * (1.0 + y.point.length()));
            // On the face's plane, in float64.
            let [a, b, c] = copies.triangles()[y.face as usize].map(|p| p.as_dvec3());
            let n = (b - a).cross(c - a).normalize();
            assert!(
                (y.point - a).dot(n).abs() < 1e-12 * (1.0 + a.length()),
                "ray {i}"
            );
            compared += 1;
        }
    }
    assert!(compared > 500, "{compared}");
    // Occlusion is whether a first hit exists.
    let mut blocked = vec![false; rays.len()];
    placed.occluded(&rays, &mut blocked);
    assert!(blocked.iter().zip(&x).all(|(&b, h)| b == (h.face != -1)));
}

#[test]
fn a_first_hit_carries_its_world_triangles_normal_and_point() {
    let (v, f) = (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
    let one = Mesh::new(v, f, BuildQuality::Auto).unwrap();
    let map = Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 1.0, 1.0),
        Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.0, 0.0, 5.0),
    );
    let placed = one.place(&[map], BuildQuality::Auto).unwrap();
    // Stretched twice along x, then its y turned onto z: the triangle
    // (0, 0, 5), (2, 0, 5), (0, 0, 6) in the plane y = 0, facing -y.
    let world = placed.triangles()[0];
    let ray = Ray::new(Vec3::new(0.5, -3.0, 5.2), Vec3::Y);
    let mut hit = [FirstHit::MISS];
    placed.first_hits(&[ray], &mut hit, true);
    let [a, b, c] = world;
    assert_eq!(hit[0].face, 0);
    let normal = (b - a).cross(c - a).normalize();
    assert!((hit[0].normal - normal).length() < 1e-7);
    assert!((hit[0].normal - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    // The point is where the ray meets the face's plane, in float64.
    let [a64, b64, c64] = world.map(|p| p.as_dvec3());
    let n64 = (b64 - a64).cross(c64 - a64).normalize();
    assert!(
        (hit[0].point - a64).dot(n64).abs() < 1e-14,
        "{:?}",
        hit[0].point
    );
    assert_eq!((hit[0].point.x, hit[0].point.z), (0.5, 5.2f32 as f64));
    let on = (1.0 - hit[0].u - hit[0].v) * a + hit[0].u * b + hit[0].v * c;
    assert!((hit[0].point - on.as_dvec3()).length() < 1e-6);
}

#[test]
fn every_query_counts_a_hit_at_t_max_without_a_nudge() {
    for mesh in [cube_mesh(), placed_and_copies().0] {
        let towards = Ray::new(Vec3::new(0.13, 0.21, -5.0), Vec3::new(0.01, -0.02, 1.0));
        let mut first = [FirstHit::MISS];
        mesh.first_hits(&[towards], &mut first, true);
        let mut all = Crossings::default();
        mesh.all_hits(&[towards], &mut all, true);
        for (t, crossing) in [(first[0].t, false), (all.t[0], true)] {
            for (tmax, counts) in [(t, true), (t.next_down(), false)] {
                let ray = Ray::segment(towards.origin, towards.direction, tmax);
                if crossing {
                    let mut found = Crossings::default();
                    mesh.all_hits(&[ray], &mut found, false);
                    assert_eq!(found.t.first() == Some(&t), counts);
                    assert!(found.u.is_empty() && found.v.is_empty());
                    let mut n = [0];
                    mesh.count_hits(&[ray], &mut n);
                    assert_eq!(n[0] > 0, counts);
                } else {
                    let mut hit = [FirstHit::MISS];
                    mesh.first_hits(&[ray], &mut hit, true);
                    assert_eq!(hit[0].t == t, counts, "{tmax} against {t}");
                    let mut blocked = [false];
                    mesh.occluded(&[ray], &mut blocked);
                    assert_eq!(blocked[0], counts);
                }
            }
        }
    }
}

#[test]
fn placing_is_refused_for_a_placed_mesh_and_a_singular_map() {
    let cube = cube_mesh();
    let placed = cube.place(&maps(), BuildQuality::Auto).unwrap();
    assert_eq!(
        placed.place(&maps(), BuildQuality::Auto).unwrap_err(),
        PlaceError::AlreadyPlaced
    );
    let flat = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
    let err = cube.place(&[Affine3A::IDENTITY, flat], BuildQuality::Auto);
    assert_eq!(err.unwrap_err(), PlaceError::Map(1));
}

#[test]
fn a_mesh_without_faces_answers_nothing() {
    let empty = Mesh::new(Vec::new(), Vec::new(), BuildQuality::Auto).unwrap();
    assert_eq!(empty.triangle_count(), 0);
    assert_eq!(empty.bounds(), [Vec3::INFINITY, Vec3::NEG_INFINITY]);
    let mut hit = [FirstHit::MISS];
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    empty.first_hits(&[ray], &mut hit, true);
    assert_eq!(hit[0].face, -1);
    let near = empty.closest_point(glam::DVec3::ZERO, Vec3::ZERO, f32::INFINITY, true);
    assert_eq!((near.face, near.distance), (-1, f64::INFINITY));
    assert!(near.point.is_nan());
    let mut inside = [true];
    empty.contains(&[Vec3::ZERO], &mut inside);
    assert!(!inside[0]);
    let err = Mesh::new(vec![Vec3::ZERO], vec![[0, 0, 1]], BuildQuality::Auto);
    assert!(err.is_err());
}

/// Crossings, counts and inside walk several rays in flight on a tree
/// that prefetches, one at a time on one that does not: the same answers
/// either way, on a placed mesh (instances) and a plain one.
#[test]
fn crossing_queries_answer_the_same_in_flight() {
    let (placed, copies) = placed_and_copies();
    let (rays, points) = rays_and_points(2000);
    type Answers = (Vec<(f32, i64, u64, u64)>, Vec<u32>, Vec<u32>, Vec<bool>);
    let answers = |m: &Mesh| -> Answers {
        let mut all = Crossings::default();
        m.all_hits(&rays, &mut all, true);
        let mut counts = vec![0; rays.len()];
        m.count_hits(&rays, &mut counts);
        let mut inside = vec![false; points.len()];
        m.contains(&points, &mut inside);
        let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let (u, v) = (bits(&all.u), bits(&all.v));
        let rows = (all.t.iter().zip(&all.face).zip(u).zip(v))
            .map(|(((&t, &face), u), v)| (t, face, u, v))
            .collect();
        (rows, all.counts, counts, inside)
    };
    for mut mesh in [placed, copies] {
        let alone = answers(&mesh);
        assert!(alone.0.len() > 1000 && alone.3.contains(&true));
        mesh.geometry.set_prefetch(true);
        assert_eq!(answers(&mesh), alone);
    }
}

/// First hits and occlusion go through the stream walk (in flight where
/// the tree prefetches): each ray's t, face and barycentrics are bit for
/// bit its own single-ray walk's, prefetching on or off, and its point
/// and normal are the same either way.
#[test]
fn first_hits_and_occlusion_equal_each_rays_single_walk() {
    let (placed, copies) = placed_and_copies();
    let (rays, _) = rays_and_points(2000);
    let bits = |h: &FirstHit| {
        let p = h.point.to_array().map(f64::to_bits);
        (h.t.to_bits(), h.face, h.u.to_bits(), h.v.to_bits(), p)
    };
    for mut mesh in [placed, copies] {
        let mut hits = 0;
        for prefetch in [false, true] {
            mesh.geometry.set_prefetch(prefetch);
            let mut first = vec![FirstHit::MISS; rays.len()];
            mesh.first_hits(&rays, &mut first, true);
            let mut blocked = vec![false; rays.len()];
            mesh.occluded(&rays, &mut blocked);
            for (i, ray) in rays.iter().enumerate() {
                let own = mesh.geometry.intersect(ray);
                assert_eq!(
                    own.map(|h| (h.t, h.u, h.v)),
                    first[i]
                        .t
                        .is_finite()
                        .then_some((first[i].t, first[i].u, first[i].v)),
                    "ray {i}"
                );
                let want = own.map_or(FirstHit::MISS, |h| mesh.first_hit(ray, &h, true));
                assert_eq!(bits(&first[i]), bits(&want), "ray {i}");
                assert_eq!(blocked[i], mesh.geometry.occluded(ray), "ray {i}");
                hits += own.is_some() as usize;
            }
        }
        assert!(hits > 500, "{hits} hits");
    }
}

/// A bad vertex is quoted as the caller gave it, not as it lies relative
/// to the mesh's centre (far from the origin the two differ), and a
/// float64 vertex too far out for float32 is named as such.
#[test]
fn a_bad_vertex_is_quoted_as_given() {
    let (v, faces) = cube();
    let far = DVec3::new(500_123.0, 5_000_456.0, 100.0);
    let mut given: Vec<DVec3> = v.iter().map(|p| p.as_dvec3() + far).collect();
    given[3].y = f64::NAN;
    let e = Mesh::new_exact(given.clone(), faces.clone(), BuildQuality::Auto).unwrap_err();
    assert!(
        matches!(e, MeshArraysError::NotFinite { vertex: 3, .. }),
        "{e}"
    );
    let text = e.to_string();
    assert!(text.contains("[500124.0, NaN, 99.0]"), "{text}");
    assert!(text.ends_with("(faces[1] uses it)"), "{text}");
    given[3].y = 1e39;
    let e = Mesh::new_exact(given, faces, BuildQuality::Auto).unwrap_err();
    assert!(
        matches!(e, MeshArraysError::BeyondFloat32 { vertex: 3, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("1e39"), "{e}");
}

/// The columns `first_hits_into` writes hold, row for row and bit for
/// bit, what `first_hits` answers, whichever of them are asked for (the
/// others empty): with the normal and the point left out, the walk's
/// answers are still the same.
#[test]
fn first_hit_columns_hold_what_first_hits_answers() {
    let (placed, copies) = placed_and_copies();
    let (rays, _) = rays_and_points(700);
    let n = rays.len();
    for mesh in [placed, copies] {
        let mut want = vec![FirstHit::MISS; n];
        mesh.first_hits(&rays, &mut want, true);
        assert!(want.iter().filter(|h| h.face >= 0).count() > 100);
        // Each of the 64 subsets of the six columns.
        for asked in 0..64u32 {
            let has = |k: u32| asked >> k & 1 == 1;
            let len = |k: u32, width: usize| if has(k) { width * n } else { 0 };
            let (mut t, mut face) = (vec![-7.0f32; len(0, 1)], vec![-7i64; len(1, 1)]);
            let (mut u, mut v) = (vec![-7.0f32; len(2, 1)], vec![-7.0f32; len(3, 1)]);
            let (mut normal, mut point) = (vec![-7.0f32; len(4, 3)], vec![-7.0f64; len(5, 3)]);
            let columns = FirstHitColumns {
                t: &mut t,
                face: &mut face,
                u: &mut u,
                v: &mut v,
                normal: &mut normal,
                point: &mut point,
                miss: FirstHit::MISS,
            };
            mesh.first_hits_into(&rays, columns);
            for (i, h) in want.iter().enumerate() {
                let same = |a: f32, b: f32| a.to_bits() == b.to_bits();
                assert!(
                    !has(0) || same(t[i], h.t),
                    "t of ray {i}, columns {asked:#b}"
                );
                assert!(!has(1) || face[i] == h.face, "face of ray {i}");
                assert!(!has(2) || same(u[i], h.u), "u of ray {i}");
                assert!(!has(3) || same(v[i], h.v), "v of ray {i}");
                if has(4) {
                    let row = Vec3::from_slice(&normal[3 * i..3 * i + 3]);
                    assert_eq!(
                        row.to_array().map(f32::to_bits),
                        h.normal.to_array().map(f32::to_bits)
                    );
                }
                if has(5) {
                    let row = DVec3::from_slice(&point[3 * i..3 * i + 3]);
                    assert_eq!(
                        row.to_array().map(f64::to_bits),
                        h.point.to_array().map(f64::to_bits)
                    );
                }
            }
        }
    }
}

/// A column whose length is neither 0 nor a row for each ray is refused
/// before any ray is walked.
#[test]
#[should_panic(expected = "a column of 5 for 4 rays")]
fn a_first_hit_column_of_the_wrong_length_is_refused() {
    let mesh = cube_mesh();
    let rays = vec![Ray::new(Vec3::new(0.5, 0.5, -3.0), Vec3::Z); 4];
    let mut t = vec![0.0f32; 5];
    let columns = FirstHitColumns {
        t: &mut t,
        face: &mut [],
        u: &mut [],
        v: &mut [],
        normal: &mut [],
        point: &mut [],
        miss: FirstHit::MISS,
    };
    mesh.first_hits_into(&rays, columns);
}

/// A vertex no face uses, NaN or far out, is taken and changes nothing:
/// not the centre the mesh is traced relative to (at UTM-like
/// coordinates, where a far vertex would move it), nor whether the
/// vertices must be kept in float64, nor any answer.
#[test]
fn a_vertex_no_face_uses_changes_nothing() {
    let (v, faces) = cube();
    let far = DVec3::new(500_123.0, 5_000_456.0, 100.0);
    let given: Vec<DVec3> = v.iter().map(|p| p.as_dvec3() + far).collect();
    let plain = Mesh::new_exact(given.clone(), faces.clone(), BuildQuality::Auto).unwrap();
    let (rays, points) = rays_and_points(500);
    let key = |h: &FirstHit| (h.t.to_bits(), h.face, h.point.to_array().map(f64::to_bits));
    let mut want = vec![FirstHit::MISS; rays.len()];
    plain.first_hits(&rays, &mut want, true);
    let mut inside_want = vec![false; points.len()];
    plain.contains(&points, &mut inside_want);
    for extra in [DVec3::NAN, DVec3::new(1e20, 0.0, 0.0), DVec3::ZERO] {
        let mut with = given.clone();
        with.push(extra);
        let mesh = Mesh::new_exact(with, faces.clone(), BuildQuality::Auto).unwrap();
        assert_eq!(mesh.centre(), plain.centre(), "{extra}");
        assert_eq!(mesh.given().is_some(), plain.given().is_some(), "{extra}");
        let mut got = vec![FirstHit::MISS; rays.len()];
        mesh.first_hits(&rays, &mut got, true);
        let (a, b): (Vec<_>, Vec<_>) = (
            got.iter().map(key).collect(),
            want.iter().map(key).collect(),
        );
        assert_eq!(a, b, "{extra}");
        let mut inside = vec![false; points.len()];
        mesh.contains(&points, &mut inside);
        assert_eq!(inside, inside_want, "{extra}");
    }
    assert!(want.iter().filter(|h| h.face >= 0).count() > 10);
}

/// The files of one mesh, each format that can write float64: an OBJ and
/// an OFF of shortest round-trip decimals, PLYs of `double` properties
/// (ASCII and binary), and a PLY of `float` properties with the same text.
fn mesh_files(dir: &Path, v: &[DVec3], faces: &[[u32; 3]]) -> [std::path::PathBuf; 6] {
    let rows = |prefix: &str| -> String {
        v.iter()
            .map(|p| format!("{prefix}{:?} {:?} {:?}\n", p.x, p.y, p.z))
            .collect()
    };
    let listed = |base: u32, prefix: &str| -> String {
        (faces.iter())
            .map(|t| format!("{prefix}{} {} {}\n", t[0] + base, t[1] + base, t[2] + base))
            .collect()
    };
    let header = |format: &str, scalar: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty {scalar} x\nproperty {scalar} y\n\
             property {scalar} z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            v.len(),
            faces.len()
        )
    };
    let obj = format!("{}{}", rows("v "), listed(1, "f "));
    let off = format!(
        "OFF\n{} {} 0\n{}{}",
        v.len(),
        faces.len(),
        rows(""),
        listed(0, "3 ")
    );
    let ascii = |scalar| format!("{}{}{}", header("ascii", scalar), rows(""), listed(0, "3 "));
    let mut binary = header("binary_little_endian", "double").into_bytes();
    binary.extend(
        v.iter()
            .flat_map(|p| p.to_array())
            .flat_map(f64::to_le_bytes),
    );
    for t in faces {
        binary.push(3);
        binary.extend(t.iter().flat_map(|&k| (k as i32).to_le_bytes()));
    }
    let stl: String = faces
        .iter()
        .map(|t| {
            let corners: String = (t.iter())
                .map(|&k| v[k as usize])
                .map(|p| format!("vertex {:?} {:?} {:?}\n", p.x, p.y, p.z))
                .collect();
            format!("facet normal 0 0 0\nouter loop\n{corners}endloop\nendfacet\n")
        })
        .collect();
    let files = [
        "m.obj",
        "m.off",
        "double.ply",
        "binary.ply",
        "m.stl",
        "float.ply",
    ];
    let files = files.map(|f| dir.join(f));
    let texts = [
        obj.into_bytes(),
        off.into_bytes(),
        ascii("double").into_bytes(),
        binary,
        format!("solid m\n{stl}endsolid m\n").into_bytes(),
    ];
    for (path, bytes) in files.iter().zip(texts) {
        std::fs::write(path, bytes).unwrap();
    }
    std::fs::write(&files[5], ascii("float")).unwrap();
    files
}

/// Each face's corners as the mesh holds them given, in float64.
fn given_corners(mesh: &Mesh) -> Option<Vec<[DVec3; 3]>> {
    let (v, f) = mesh.given()?;
    Some(f.iter().map(|t| t.map(|k| v[k as usize])).collect())
}

/// A file's own float64 coordinates are held as it writes them: a cube
/// at UTM-like coordinates (where float32 is 0.5 m coarse) loaded from an
/// OBJ, an OFF, `double` PLYs and an ASCII STL is the mesh of its float64 arrays, bit
/// for bit (its centre, its vertices as given, every first hit); from a
/// PLY whose header says `float`, it is the mesh of those arrays rounded
/// to float32, as the header says, whatever digits the text writes.
#[test]
fn a_far_file_is_held_as_it_writes_its_coordinates() {
    let (v, faces) = cube();
    let far = DVec3::new(500_123.37, 5_000_456.71, 100.3);
    let given: Vec<DVec3> = v.iter().map(|p| p.as_dvec3() * 1.37 + far).collect();
    let rounded: Vec<DVec3> = given.iter().map(|p| p.as_vec3().as_dvec3()).collect();
    let arrays = Mesh::new_exact(given.clone(), faces.clone(), BuildQuality::Auto).unwrap();
    let float32 = Mesh::new_exact(rounded, faces.clone(), BuildQuality::Auto).unwrap();
    assert!(arrays.given().is_some() && arrays.centre() != DVec3::ZERO);
    let rays: Vec<Ray> = rays_and_points(400)
        .0
        .iter()
        .map(|r| Ray::new(r.origin * 1.37, r.direction))
        .collect();
    let key = |h: &FirstHit| (h.t.to_bits(), h.face, h.point.to_array().map(f64::to_bits));
    let hits = |mesh: &Mesh| {
        let mut got = vec![FirstHit::MISS; rays.len()];
        mesh.first_hits(&rays, &mut got, true);
        got.iter().map(key).collect::<Vec<_>>()
    };
    let dir = temp_dir("far-files");
    for (k, path) in mesh_files(&dir, &given, &faces).iter().enumerate() {
        let want = if k < 5 { &arrays } else { &float32 };
        let (mesh, _) = Mesh::load(path, BuildQuality::Auto).unwrap();
        assert_eq!(mesh.centre(), want.centre(), "{}", path.display());
        // The faces' corners as given (tobj orders an OBJ's vertices by
        // first use).
        assert_eq!(
            given_corners(&mesh),
            given_corners(want),
            "{}",
            path.display()
        );
        assert_eq!(hits(&mesh), hits(want), "{}", path.display());
    }
    assert!(hits(&arrays).iter().filter(|h| h.1 >= 0).count() > 50);
    assert_ne!(hits(&arrays), hits(&float32), "float32 moves the faces");
}

/// An OBJ's meshes are faces one after another in file order, as the scene
/// of the file compiles them: two objects, a quad, a degenerate triangle
/// and a vertex no face uses.
#[test]
fn a_loaded_file_keeps_the_scene_s_face_order() {
    let dir = temp_dir("face-order");
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 7 7 7\nv 0.1 0.2 0.3\n\
                o a\nf 1 2 3 4\nf 1 1 2\no b\nf 6 2 3\nf 4 6 1\n";
    let path = write(&dir, "two.obj", text.as_bytes());
    let (loaded, warnings) = Mesh::load(&path, BuildQuality::Auto).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let (scene, _) = load_mesh_scene(&path, BuildQuality::Auto).unwrap();
    let compiled = Mesh::from_geometry(scene.geometry);
    assert_eq!(loaded.triangle_count(), 5);
    assert_eq!(loaded.triangles(), compiled.triangles());
    let (vertices, _) = loaded.given().expect("0.1 is no float32");
    // Each object's own vertices that its faces use (4 and 5): not the
    // one no face uses.
    assert_eq!(vertices.len(), 9);
    assert!(!vertices.contains(&DVec3::splat(7.0)));
}

/// A mesh no farther from the origin than its size keeps centre 0 on that
/// axis (rounding the box's middle alone took the box [0, 1] to 1, and
/// moved the rays of a mesh at the origin); one farther is held near its
/// middle, a multiple of the power of two at least its size.
#[test]
fn a_mesh_near_the_origin_keeps_centre_zero() {
    let tri = |o: DVec3| vec![o, o + DVec3::X, o + DVec3::Y];
    for (at, want) in [
        (DVec3::ZERO, DVec3::ZERO),
        (DVec3::new(0.2, -1.0, 0.0), DVec3::ZERO),
        (DVec3::new(1e6, 0.5, 3.0), DVec3::new(1e6 + 1.0, 0.0, 3.0)),
    ] {
        let mesh = Mesh::new_exact(tri(at), vec![[0, 1, 2]], BuildQuality::Auto).unwrap();
        assert_eq!(mesh.centre(), want, "{at}");
    }
}

/// A file traced for its faces reads none of its looks: an OBJ whose
/// material library has a mistake and names a texture that is not there,
/// a glTF whose material's image is not there, and one that requires
/// texture extensions strata does not read, load as queries and as
/// `strata trace` loads them (a render of them is an error naming the
/// texture or the extension).
#[test]
fn a_file_traced_for_its_faces_reads_none_of_its_looks() {
    let dir = temp_dir("faces-alone");
    write(&dir, "looks.mtl", b"newmtl a\nKd red\nmap_Kd gone.png\n");
    let obj = write(
        &dir,
        "quad.obj",
        b"mtllib looks.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nusemtl a\n\
          f 1/1 2/1 3/1 4/1\nusemtl none\nf 1 3 4\n",
    );
    let gltf = write(
        &dir,
        "tri.gltf",
        br#"{"asset":{"version":"2.0"},
            "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
            "bufferViews":[{"buffer":0,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
            "images":[{"uri":"gone.png"}],"textures":[{"source":0}],
            "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]}],
            "nodes":[{"mesh":0}]}"#,
    );
    // A glTF that requires texture extensions strata does not read, its
    // texture's image in one of them (no `source`).
    let text = std::fs::read_to_string(&gltf).unwrap();
    let webp = text
        .replace(
            r#""images":[{"uri":"gone.png"}],"textures":[{"source":0}]"#,
            r#""extensionsRequired":["KHR_texture_basisu","EXT_texture_webp"],
               "extensionsUsed":["KHR_texture_basisu","EXT_texture_webp"],
               "images":[{"uri":"gone.webp"}],"textures":[{"extensions":{"EXT_texture_webp":{"source":0}}}]"#,
        )
        .into_bytes();
    let webp = write(&dir, "webp.gltf", &webp);
    for (path, triangles) in [(&obj, 3u32), (&gltf, 1), (&webp, 1)] {
        let render = crate::scene::loaders::load_mesh_file(path).unwrap_err();
        let said = render.to_string();
        assert!(
            ["gone.png", "red", "KHR_texture_basisu"]
                .iter()
                .any(|w| said.contains(w)),
            "{said}"
        );
        let (mesh, warnings) = Mesh::load(path, BuildQuality::Auto).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(mesh.triangle_count(), u64::from(triangles));
        let (scene, _) = load_mesh_scene(path, BuildQuality::Auto).unwrap();
        assert_eq!(scene.geometry.triangle_count(), triangles);
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let ray = Ray::new(Vec3::new(0.25, 0.1, 1.0), Vec3::NEG_Z);
        let mut hit = [FirstHit::MISS];
        mesh.first_hits(&[ray], &mut hit, false);
        assert_eq!(hit[0].t, 1.0, "{}", path.display());
    }
}

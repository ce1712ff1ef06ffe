//! The mesh queries through instances (`Geometry::crossings`,
//! `count_crossings`, `contains`, `nearest` on a scene of placed copies of
//! one mesh, `geometry::instance::placed`), against the same queries on a
//! mesh of the copies (every triangle moved to world space as
//! `Instance::affine` moves it) and against brute force over those
//! triangles: the same crossings (t and the copies' triangle ids, bit for
//! bit), the same counts and containment, the same nearest points and
//! distances, under random affine maps with non-uniform scale, shear and
//! mirroring, copies that overlap, and copies that share faces exactly.

use crate::common::queries::{brute_crossings, check_nearest, Around};
use glam::{Affine3A, Mat3, Quat, Vec3};
use strata::accel::{BuildQuality, PrimHit};
use strata::geometry::instance::placed;
use strata::geometry::Geometry;
use strata::math::Ray;
use strata::sampling::stream::{seeded, Draw, StreamRng};
use strata::scene::mesh_geometry;

/// A closed, indexed, bumpy sphere of `rings` × `segments` quads (poles
/// as fans), wound outwards.
fn bumpy_sphere(rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = vec![Vec3::Z, -Vec3::Z];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let r = 1.0 + 0.15 * (3.0 * theta).sin() * (5.0 * phi).cos();
            v.push(
                r * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ),
            );
        }
    }
    let at = |i: u32, j: u32| 2 + (i - 1) * segments + j % segments;
    let mut f = Vec::new();
    for j in 0..segments {
        f.push([0, at(1, j), at(1, j + 1)]);
        f.push([1, at(rings - 1, j + 1), at(rings - 1, j)]);
        for i in 1..rings - 1 {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    (v, f)
}

/// The unit cube [0, 1]³, twelve triangles wound outwards.
fn unit_cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (v, f) = crate::common::cube(1.0);
    (v.into_iter().map(|p| p + 0.5).collect(), f)
}

/// `n` random invertible maps: rotation · scale (non-uniform, every other
/// one mirrored) · shear · rotation, moved within `spread` of the origin
/// so that copies overlap.
fn random_maps(rng: &mut StreamRng, n: usize, spread: f32) -> Vec<Affine3A> {
    let rotation = |rng: &mut StreamRng| {
        let q = rng.cube(2.0);
        Mat3::from_quat(Quat::from_xyzw(q.x, q.y, q.z, rng.range(-1.0, 1.0)).normalize())
    };
    (0..n)
        .map(|k| {
            let mirror = if k % 2 == 1 { -1.0 } else { 1.0 };
            let scale = Vec3::new(
                rng.range(0.3, 2.5),
                rng.range(0.3, 2.5),
                mirror * rng.range(0.3, 2.5),
            );
            let mut shear = Mat3::IDENTITY;
            shear.y_axis.x = rng.range(-0.8, 0.8);
            shear.z_axis.y = rng.range(-0.8, 0.8);
            let linear = rotation(rng) * Mat3::from_diagonal(scale) * shear * rotation(rng);
            Affine3A::from_mat3_translation(linear, rng.cube(2.0 * spread))
        })
        .collect()
}

fn build((v, f): (Vec<Vec3>, Vec<[u32; 3]>)) -> Geometry {
    mesh_geometry(v, f, BuildQuality::Auto).unwrap()
}

/// The placed scene and a mesh of its copies (copy k's triangle j is
/// triangle k·T + j, each vertex moved as `Instance::affine` moves it).
fn placed_and_copies(prototype: Geometry, maps: &[Affine3A]) -> (Geometry, Geometry) {
    let scene = placed(prototype, maps, BuildQuality::Auto).unwrap();
    let own = scene.prototypes()[0].file_order_triangles();
    let mut vertices = Vec::new();
    for instance in scene.instances() {
        let m = instance.affine();
        vertices.extend(own.iter().flatten().map(|&p| m.transform_point3(p)));
    }
    let faces = (0..vertices.len() as u32 / 3)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    (scene, build((vertices, faces)))
}

/// The id of a placed triangle as the copies number it.
fn flat(scene: &Geometry, prim: u32, part: u32) -> u64 {
    let hit = PrimHit {
        t: 0.0,
        prim,
        u: 0.0,
        v: 0.0,
        part,
    };
    scene.flat_prim(&hit, &scene.flat_offsets())
}

/// Crossings as (t, the copies' triangle id).
fn crossings(scene: &Geometry, ray: &Ray) -> Vec<(f32, u64)> {
    let mut out = Vec::new();
    scene.crossings(ray, &mut out);
    out.iter()
        .map(|c| (c.t, flat(scene, c.prim, c.part)))
        .collect()
}

/// The rays the checks cast: random ones through the scene's box (some
/// clipped), and ones aimed exactly at the copies' vertices and at points
/// of their edges, where ties are broken.
fn rays(copies: &Geometry, n: usize, seed: u64) -> Vec<Ray> {
    let tris = copies.file_order_triangles();
    let (lo, hi) = (copies.bvh().bounds.min, copies.bvh().bounds.max);
    let size = (hi - lo).length();
    let mut rng = seeded(seed);
    (0..n)
        .map(|i| {
            let tri = tris[(rng.unit() * tris.len() as f32) as usize % tris.len()];
            let target = match i % 3 {
                0 => lo + (hi - lo) * Vec3::new(rng.unit(), rng.unit(), rng.unit()),
                1 => tri[i % 9 / 3],
                _ => tri[0] + (tri[1] - tri[0]) * 0.5,
            };
            let origin = target + rng.cube(2.0).normalize_or(Vec3::X) * size;
            let mut ray = Ray::new(origin, target - origin);
            if i % 5 == 0 {
                ray.tmax = rng.range(0.5, 1.5);
            }
            ray
        })
        .collect()
}

/// Crossings, counts and containment of `scene` equal the copies' (and
/// brute force over their triangles for every tenth ray).
fn check_crossings(scene: &Geometry, copies: &Geometry, n: usize, seed: u64) -> usize {
    let tris = copies.file_order_triangles();
    let mut total = 0;
    for (i, ray) in rays(copies, n, seed).iter().enumerate() {
        let want: Vec<(f32, u64)> = {
            let mut out = Vec::new();
            copies.crossings(ray, &mut out);
            out.iter().map(|c| (c.t, u64::from(c.prim))).collect()
        };
        let got = crossings(scene, ray);
        assert_eq!(got, want, "ray {i}: {ray:?}");
        assert_eq!(scene.count_crossings(ray) as usize, want.len(), "ray {i}");
        if i % 10 == 0 {
            let brute: Vec<(f32, u64)> = brute_crossings(&tris, ray)
                .iter()
                .map(|c| (c.t, u64::from(c.prim)))
                .collect();
            assert_eq!(got, brute, "ray {i}: {ray:?}");
        }
        total += want.len();
    }
    total
}

/// `contains` of `points` equals the copies'.
fn check_contains(scene: &Geometry, copies: &Geometry, points: &[Vec3]) -> usize {
    let mut inside = 0;
    for &p in points {
        assert_eq!(scene.contains(p), copies.contains(p), "{p}");
        inside += usize::from(copies.contains(p));
    }
    inside
}

/// The nearest point of `scene` equals brute force over the copies'
/// triangles with no limit, and the copies' own with limits around the
/// answer.
fn nearest_matches_copies(scene: &Geometry, copies: &Geometry, points: usize, seed: u64) {
    let around = Around {
        lo: copies.bvh().bounds.min,
        hi: copies.bvh().bounds.max,
        far: 2.0,
        near: 0.1,
    };
    check_nearest(
        &copies.file_order_triangles(),
        &around,
        (points, seed),
        |p, limit| {
            scene
                .nearest(p, limit)
                .map(|n| (n.point, n.distance, flat(scene, n.prim, n.part)))
        },
        |p, limit| {
            copies
                .nearest(p, limit)
                .map(|n| (n.point, n.distance, u64::from(n.prim)))
        },
    );
}

#[test]
fn crossings_through_instances_are_the_copies() {
    let mut rng = seeded(45);
    let maps = random_maps(&mut rng, 12, 3.0);
    let (scene, copies) = placed_and_copies(build(bumpy_sphere(12, 24)), &maps);
    let total = check_crossings(&scene, &copies, 6000, 1);
    assert!(total > 6000, "{total} crossings: the rays miss");
}

#[test]
fn copies_that_share_faces_cross_like_a_mesh_of_them() {
    // A 3 × 3 × 2 block of unit cubes, each placed by a translation (exact
    // in f32), so neighbours share faces, edges and vertices bit for bit,
    // plus mirrored and scaled ones that meet them at the same vertices.
    let mut maps = Vec::new();
    for k in 0..18 {
        let at = Vec3::new((k % 3) as f32, (k / 3 % 3) as f32, (k / 9) as f32);
        maps.push(Affine3A::from_translation(at));
    }
    maps.push(Affine3A::from_scale(Vec3::new(-1.0, 2.0, 1.0)));
    maps.push(Affine3A::from_scale_rotation_translation(
        Vec3::new(1.0, 1.0, -1.0),
        glam::Quat::IDENTITY,
        Vec3::new(3.0, 0.0, 0.0),
    ));
    let (scene, copies) = placed_and_copies(build(unit_cube()), &maps);
    check_crossings(&scene, &copies, 6000, 2);
    // The centre of each translated cube is inside the block.
    let centres: Vec<Vec3> = maps[..18]
        .iter()
        .map(|m| m.transform_point3(Vec3::splat(0.5)))
        .collect();
    for &c in &centres {
        assert!(scene.contains(c), "{c}");
    }
    check_contains(&scene, &copies, &centres);
}

#[test]
fn contains_through_instances_is_the_copies() {
    let mut rng = seeded(46);
    let maps = random_maps(&mut rng, 10, 4.0);
    let (scene, copies) = placed_and_copies(build(bumpy_sphere(10, 20)), &maps);
    // Each copy's centre (inside it, and maybe inside others), and random
    // points around them all.
    let mut points: Vec<Vec3> = maps
        .iter()
        .map(|m| m.transform_point3(Vec3::ZERO))
        .collect();
    let (lo, hi) = (copies.bvh().bounds.min, copies.bvh().bounds.max);
    points
        .extend((0..4000).map(|_| lo + (hi - lo) * Vec3::new(rng.unit(), rng.unit(), rng.unit())));
    let inside = check_contains(&scene, &copies, &points);
    assert!(inside > 200 && inside < 3800, "{inside} inside");
    // A copy far from the others holds its centre.
    let far = Affine3A::from_translation(Vec3::splat(100.0)) * maps[0];
    let (alone, _) = placed_and_copies(build(bumpy_sphere(10, 20)), &[maps[1], far]);
    assert!(alone.contains(far.transform_point3(Vec3::ZERO)));
    assert!(!alone.contains(Vec3::splat(50.0)));
}

#[test]
fn nearest_through_instances_is_the_copies_in_world_distances() {
    let mut rng = seeded(47);
    let maps = random_maps(&mut rng, 12, 3.0);
    let (scene, copies) = placed_and_copies(build(bumpy_sphere(12, 24)), &maps);
    nearest_matches_copies(&scene, &copies, 1500, 3);
    // Strongly non-uniform: a copy squashed 50:1, so object distances
    // are far from world ones.
    let squash = [
        Affine3A::from_scale(Vec3::new(50.0, 1.0, 0.5)),
        Affine3A::from_mat3_translation(
            Mat3::from_cols(
                Vec3::new(0.02, 3.0, 0.0),
                Vec3::Y,
                Vec3::new(0.0, 0.0, -4.0),
            ),
            Vec3::new(1.0, 2.0, 3.0),
        ),
    ];
    let (scene, copies) = placed_and_copies(build(bumpy_sphere(12, 24)), &squash);
    nearest_matches_copies(&scene, &copies, 1000, 4);
}

#[test]
fn nearest_through_instances_of_shared_faces_breaks_ties_as_the_copies() {
    // Points equally near two copies' shared face must name the copies'
    // smaller id, as a mesh of them would.
    let maps: Vec<Affine3A> = (0..8)
        .map(|k| Affine3A::from_translation(Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0)))
        .collect();
    let (scene, copies) = placed_and_copies(build(unit_cube()), &maps);
    nearest_matches_copies(&scene, &copies, 1500, 5);
}

#[test]
fn an_empty_placement_answers_nothing() {
    let mut rng = seeded(48);
    let maps = random_maps(&mut rng, 3, 1.0);
    let (scene, _) = placed_and_copies(build((Vec::new(), Vec::new())), &maps);
    let ray = Ray::new(Vec3::splat(-5.0), Vec3::ONE);
    assert_eq!(scene.count_crossings(&ray), 0);
    assert!(!scene.contains(Vec3::ZERO));
    assert_eq!(scene.nearest(Vec3::ZERO, f32::INFINITY), None);
}

//! The mesh queries: every crossing along a ray and their count
//! (`Geometry::crossings`, `count_crossings`), inside or outside
//! (`contains`) and the nearest point (`nearest`), against brute force
//! over every triangle and against analytic answers, on generated closed
//! meshes (a cube, an icosphere, a bumpy icosphere) and on the bunny when
//! `tools/fetch-assets` has fetched it. Rays aimed exactly at the shared
//! edges and vertices of closed meshes must cross the surface once per
//! surface crossing: never 0 and never 2.

use crate::common::cube;
use crate::common::queries::{brute_crossings, brute_nearest, check_nearest, Around};
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;
use strata::accel::BuildQuality;
use strata::geometry::{Crossing, Geometry};
use strata::math::Ray;
use strata::sampling::stream::{seeded, Draw, StreamRng};
use strata::scene::{load_mesh_scene, mesh_geometry};

/// An icosahedron subdivided `levels` times onto the unit sphere
/// (level 3: 642 vertices, 1,920 edges, 1,280 triangles), wound outwards.
fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let ab = midpoint(a, b, &mut v);
            let bc = midpoint(b, c, &mut v);
            let ca = midpoint(c, a, &mut v);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// The edges of a mesh, each once.
fn edges(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// The level-3 icosphere with each vertex moved along its radius by a
/// seeded factor in [0.6, 1.4]: closed and far from convex.
fn bumpy() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (v, f) = icosphere(3);
    let mut rng = seeded(17);
    (v.into_iter().map(|p| p * rng.range(0.6, 1.4)).collect(), f)
}

fn build((v, f): (Vec<Vec3>, Vec<[u32; 3]>)) -> Geometry {
    mesh_geometry(v, f, BuildQuality::Auto).unwrap()
}

/// The bunny's geometry, or None (with a note) when it was not fetched.
fn bunny() -> Option<Geometry> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bunny.obj");
    if !path.exists() {
        crate::common::skipped(
            "mesh_queries (the bunny)",
            "assets/bunny.obj is missing (tools/fetch-assets fetches it)",
        );
        return None;
    }
    let (scene, _) = load_mesh_scene(&path, BuildQuality::Auto).unwrap();
    Some(scene.geometry)
}

/// The crossings, their leaf slots left out (brute force has none).
fn crossings(g: &Geometry, ray: &Ray) -> Vec<Crossing> {
    let mut out = Vec::new();
    g.crossings(ray, &mut out);
    out.iter().map(|&c| Crossing { part: 0, ..c }).collect()
}

/// A random unit direction.
fn direction(rng: &mut StreamRng) -> Vec3 {
    loop {
        let d = rng.cube(2.0);
        if d.length_squared() > 0.01 && d.length_squared() <= 1.0 {
            return d.normalize();
        }
    }
}

/// `n` random rays through `g`'s box, a third of them clipped to a
/// random interval.
fn random_rays(g: &Geometry, n: usize, seed: u64) -> Vec<Ray> {
    let (lo, hi) = (g.bvh().bounds.min, g.bvh().bounds.max);
    let size = (hi - lo).length();
    let mut rng = seeded(seed);
    (0..n)
        .map(|i| {
            let target = lo + (hi - lo) * Vec3::new(rng.unit(), rng.unit(), rng.unit());
            let origin = target + direction(&mut rng) * size * rng.range(0.0, 1.0);
            let mut ray = Ray::new(origin, (target - origin) * rng.range(0.1, 2.0));
            if i % 3 == 0 {
                ray.tmin = rng.range(0.0, 1.0);
                ray.tmax = ray.tmin + rng.range(0.0, 2.0);
            }
            ray
        })
        .collect()
}

/// Crossings and counts equal brute force on random rays, some clipped
/// to a random interval.
fn check_random_rays(g: &Geometry, rays: usize, seed: u64) -> usize {
    let tris = g.file_order_triangles();
    let mut total = 0;
    for (i, ray) in random_rays(g, rays, seed).into_iter().enumerate() {
        let got = crossings(g, &ray);
        assert_eq!(got, brute_crossings(&tris, &ray), "ray {i}: {ray:?}");
        assert_eq!(g.count_crossings(&ray) as usize, got.len(), "ray {i}");
        if let (Some(first), Some(hit)) = (got.first(), g.intersect(&ray)) {
            assert_eq!(
                first.t, hit.t,
                "ray {i}: the first crossing is the closest hit"
            );
        }
        total += got.len();
    }
    total
}

#[test]
fn crossings_and_counts_equal_brute_force_on_random_rays() {
    let total = check_random_rays(&build(bumpy()), 3000, 1);
    assert!(total > 3000, "{total} crossings: the rays must hit");
    let (v, mut f) = bumpy();
    // Two shells, one inside the other: rays cross four layers.
    let n = v.len() as u32;
    let mut v2 = v.clone();
    v2.extend(v.iter().map(|&p| p * 0.3));
    f.extend(f.clone().iter().map(|t| t.map(|k| k + n)));
    check_random_rays(&build((v2, f)), 2000, 2);
}

#[test]
fn crossings_equal_brute_force_on_the_bunny() {
    if let Some(g) = bunny() {
        let total = check_random_rays(&g, 300, 3);
        assert!(total > 150, "{total} crossings");
    }
}

#[test]
fn parity_tells_inside_from_outside_on_a_closed_mesh() {
    let g = build(bumpy());
    let mut rng = seeded(4);
    for _ in 0..2000 {
        let d = direction(&mut rng) * rng.range(0.5, 2.0);
        // Inside every face (the radii are at least 0.6, the level-3
        // faces' planes within 0.99 of them) and outside the 1.4 sphere.
        let inside = rng.cube(0.6);
        let outside = direction(&mut rng) * rng.range(1.5, 10.0);
        assert_eq!(
            g.count_crossings(&Ray::new(inside, d)) % 2,
            1,
            "{inside} {d}"
        );
        assert_eq!(
            g.count_crossings(&Ray::new(outside, d)) % 2,
            0,
            "{outside} {d}"
        );
    }
}

/// The number of crossings of rays aimed exactly at each of `targets` on
/// the surface of a convex closed mesh, each through the centre and from
/// random points outside through a random point inside (scaled by `inner`
/// from the centre): every one crosses twice.
fn check_aimed_rays(g: &Geometry, targets: &[Vec3], inner: f32, what: &str) {
    let mut rng = seeded(5);
    for (k, &target) in targets.iter().enumerate() {
        let mut rays = vec![
            Ray::new(target * 3.0, -target),
            Ray::new(target * 1.5, -target * 0.37),
            Ray::new(target * 11.0, -target * 10.0),
        ];
        for _ in 0..8 {
            let p = rng.cube(2.0 * inner);
            let origin = target + (target - p) * rng.range(0.2, 4.0);
            rays.push(Ray::new(origin, (p - origin) * rng.range(0.1, 3.0)));
        }
        for ray in rays {
            let got = crossings(g, &ray);
            assert_eq!(got.len(), 2, "{what} {k} at {target}: {ray:?} {got:?}");
        }
    }
}

#[test]
fn rays_at_the_icospheres_vertices_and_edges_cross_it_twice() {
    let (v, f) = icosphere(3);
    let e = edges(&f);
    assert_eq!((v.len(), e.len()), (642, 1920));
    let g = build((v.clone(), f));
    check_aimed_rays(&g, &v, 0.5, "vertex");
    let mids: Vec<Vec3> = e
        .iter()
        .map(|&(a, b)| (v[a as usize] + v[b as usize]) * 0.5)
        .collect();
    check_aimed_rays(&g, &mids, 0.5, "edge midpoint");
}

#[test]
fn rays_at_the_cubes_vertices_edges_and_diagonals_cross_it_twice() {
    let (v, f) = cube(2.0);
    let e = edges(&f);
    assert_eq!(e.len(), 18, "12 edges and 6 face diagonals");
    let g = build((v.clone(), f));
    check_aimed_rays(&g, &v, 0.9, "vertex");
    let mids: Vec<Vec3> = e
        .iter()
        .map(|&(a, b)| (v[a as usize] + v[b as usize]) * 0.5)
        .collect();
    check_aimed_rays(&g, &mids, 0.9, "edge midpoint");
    // Down each axis, through points of every face diagonal and through
    // its ends: exact zeros in the edge functions.
    for (a, b) in e {
        let (a, b) = (v[a as usize], v[b as usize]);
        let axis = (b - a).abs().min_position();
        if (b - a).abs().cmpeq(Vec3::ZERO).bitmask().count_ones() != 1 {
            continue;
        }
        for i in 0..=64 {
            let p = a + (b - a) * (i as f32 / 64.0);
            let mut n = Vec3::ZERO;
            n[axis] = p[axis].signum();
            for ray in [Ray::new(p + n * 3.0, -n), Ray::new(p - n * 5.0, n * 0.25)] {
                let want = if i == 0 || i == 64 || p.abs().max_element() > 0.99 {
                    // Along a cube edge: it only touches the surface.
                    None
                } else {
                    Some(2)
                };
                let got = g.count_crossings(&ray);
                match want {
                    Some(w) => assert_eq!(got, w, "{p} along {}", ray.direction),
                    None => assert_eq!(got % 2, 0, "{p} along {}", ray.direction),
                }
            }
        }
    }
}

#[test]
fn rays_that_touch_a_silhouette_vertex_or_edge_cross_an_even_number_of_times() {
    // The icosphere's tangent planes at its vertices hold no other point
    // of it: a ray in one through the vertex only touches the surface.
    let (v, f) = icosphere(3);
    let g = build((v.clone(), f));
    let mut rng = seeded(6);
    for &p in &v {
        for _ in 0..4 {
            let w = direction(&mut rng).reject_from(p).normalize();
            let ray = Ray::new(p - w * 2.0, w);
            assert_eq!(g.count_crossings(&ray) % 2, 0, "{p} along {w}");
        }
    }
    // The cube's corners and edges, touched from outside.
    let (v, f) = cube(2.0);
    let g = build((v.clone(), f));
    for &p in &v {
        for _ in 0..16 {
            // A direction leaving the cube both ways: along one axis
            // outwards, along another inwards.
            let mut w = direction(&mut rng);
            w.x = w.x.abs() * p.x.signum();
            w.y = -w.y.abs() * p.y.signum();
            let ray = Ray::new(p - w * 2.0, w);
            assert_eq!(g.count_crossings(&ray) % 2, 0, "{p} along {w}");
            let edge_mid = Vec3::new(p.x, p.y, 0.0);
            let ray = Ray::new(edge_mid - w * 2.0, w);
            assert_eq!(g.count_crossings(&ray) % 2, 0, "{edge_mid} along {w}");
        }
    }
}

#[test]
fn big_boxes_hit_from_inside_cross_once() {
    for side in [1e4f32, 1e6] {
        let g = build(cube(side));
        let mut rng = seeded(7);
        for _ in 0..2000 {
            let p = rng.cube(side * 0.9);
            let ray = Ray::new(p, direction(&mut rng) * rng.range(0.01, 100.0));
            let got = crossings(&g, &ray);
            assert_eq!(got.len(), 1, "side {side}: {ray:?} {got:?}");
            assert!(g.contains(p), "side {side}: {p}");
        }
    }
}

#[test]
fn contains_on_a_cube() {
    let (v, f) = cube(2.0);
    let g = build((v.clone(), f));
    for &p in &v {
        assert!(g.contains(p / 1.5), "{p} / 1.5");
        assert!(!g.contains(p * 1.5), "{p} * 1.5");
        assert!(!g.contains(p * 1e6), "{p} * 1e6");
    }
    let centroid = v.iter().sum::<Vec3>() / v.len() as f32;
    assert!(g.contains(centroid));
    let mut rng = seeded(8);
    for _ in 0..2000 {
        let p = rng.cube(4.0);
        let inside = p.abs().max_element() < 1.0;
        if (p.abs().max_element() - 1.0).abs() > 1e-4 {
            assert_eq!(g.contains(p), inside, "{p}");
        }
    }
}

#[test]
fn contains_agrees_with_brute_force_parity_in_every_direction() {
    for (name, mesh) in [("icosphere", icosphere(3)), ("bumpy", bumpy())] {
        let g = build(mesh);
        let tris = g.file_order_triangles();
        let mut rng = seeded(9);
        let dirs: Vec<Vec3> = (0..6).map(|_| direction(&mut rng)).collect();
        let mut inside = 0;
        for _ in 0..1500 {
            let p = rng.cube(3.2);
            // Within rounding of the surface either answer is right.
            if g.nearest(p, 1e-4).is_some() {
                continue;
            }
            let c = g.contains(p);
            for &d in &dirs {
                let odd = brute_crossings(&tris, &Ray::new(p, d)).len() % 2 == 1;
                assert_eq!(c, odd, "{name}: {p} along {d}");
            }
            inside += c as u32;
        }
        assert!(inside > 50, "{name}: {inside} inside");
    }
}

/// `nearest` equals brute force on random points near and far, with no
/// limit and with limits around the answer.
fn nearest_matches_brute_force(g: &Geometry, points: usize, seed: u64) {
    let tris = g.file_order_triangles();
    let around = Around {
        lo: g.bvh().bounds.min,
        hi: g.bvh().bounds.max,
        far: 3.0,
        near: 0.2,
    };
    check_nearest(
        &tris,
        &around,
        (points, seed),
        |p, limit| {
            g.nearest(p, limit)
                .map(|n| (n.point, n.distance, u64::from(n.prim)))
        },
        |p, limit| brute_nearest(&tris, p, limit),
    );
}

#[test]
fn nearest_equals_brute_force() {
    nearest_matches_brute_force(&build(bumpy()), 3000, 10);
    nearest_matches_brute_force(&build(cube(2.0)), 500, 11);
    if let Some(g) = bunny() {
        nearest_matches_brute_force(&g, 200, 12);
    }
}

#[test]
fn nearest_answers_analytic_points_on_a_cube_and_a_plane() {
    let g = build(cube(2.0));
    let mut rng = seeded(13);
    for _ in 0..5000 {
        let p = rng.cube(8.0);
        let a = p.abs();
        let want = if a.max_element() <= 1.0 {
            1.0 - a.max_element()
        } else {
            (a - Vec3::ONE).max(Vec3::ZERO).length()
        };
        let got = g.nearest(p, f32::INFINITY).unwrap();
        assert!(
            (got.distance - want).abs() < 1e-5,
            "{p}: {got:?}, not {want}"
        );
        assert!((got.point - p).length() - got.distance < 1e-5);
        assert!(
            (got.point.abs().max_element() - 1.0).abs() < 1e-6,
            "{got:?} on the cube"
        );
    }
    // A square of side 200 at z = 0.
    let v = vec![
        Vec3::new(-100.0, -100.0, 0.0),
        Vec3::new(100.0, -100.0, 0.0),
        Vec3::new(100.0, 100.0, 0.0),
        Vec3::new(-100.0, 100.0, 0.0),
    ];
    let g = build((v, vec![[0, 1, 2], [0, 2, 3]]));
    for _ in 0..2000 {
        let p = rng.cube(100.0);
        let got = g.nearest(p, f32::INFINITY).unwrap();
        assert!(
            (got.point - Vec3::new(p.x, p.y, 0.0)).length() < 1e-4,
            "{p}: {got:?}"
        );
        assert!((got.distance - p.z.abs()).abs() < 1e-4, "{p}: {got:?}");
        assert_eq!(got.prim, if p.x >= p.y { 0 } else { 1 }, "{p}");
        assert_eq!(
            g.nearest(p, p.z.abs() * 0.99 - 1e-4),
            None,
            "{p}: beyond the limit"
        );
    }
}

#[test]
fn empty_meshes_and_bad_points_answer_nothing() {
    let g = build((Vec::new(), Vec::new()));
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(g.count_crossings(&ray), 0);
    assert!(crossings(&g, &ray).is_empty());
    assert!(!g.contains(Vec3::ZERO));
    assert_eq!(g.nearest(Vec3::ZERO, f32::INFINITY), None);
    let g = build(cube(2.0));
    assert_eq!(g.count_crossings(&Ray::new(Vec3::ZERO, Vec3::ZERO)), 0);
    assert_eq!(g.nearest(Vec3::NAN, f32::INFINITY), None);
    assert_eq!(g.nearest(Vec3::ZERO, -1.0), None);
    assert_eq!(g.nearest(Vec3::ZERO, f32::NAN), None);
    // Appended after what the vector held, in order.
    let mut out = vec![Crossing {
        t: -1.0,
        prim: 99,
        part: 0,
    }];
    g.crossings(&Ray::new(Vec3::new(0.2, 0.3, -5.0), Vec3::Z), &mut out);
    let t: Vec<f32> = out.iter().map(|c| c.t).collect();
    assert_eq!(t, [-1.0, 4.0, 6.0]);
    // (tmin, tmax]: the end is in, the start is not.
    let clipped = Ray {
        tmin: 4.0,
        tmax: 6.0,
        ..Ray::new(Vec3::new(0.2, 0.3, -5.0), Vec3::Z)
    };
    assert_eq!(g.count_crossings(&clipped), 1);
}

/// A closed pyramid: apex (0, 0, 1) over a regular `sides`-gon of radius 1
/// at z = 0, the base a fan from a centre vertex at the origin.
fn pyramid(sides: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = vec![Vec3::Z];
    for i in 0..sides {
        let a = std::f64::consts::TAU * i as f64 / sides as f64;
        v.push(Vec3::new(a.cos() as f32, a.sin() as f32, 0.0));
    }
    v.push(Vec3::ZERO);
    let (centre, ring) = (sides + 1, |i: u32| 1 + i % sides);
    let mut f: Vec<[u32; 3]> = (0..sides).map(|i| [0, ring(i), ring(i + 1)]).collect();
    f.extend((0..sides).map(|i| [centre, ring(i + 1), ring(i)]));
    (v, f)
}

/// Axis-aligned rays through a vertex of any valence, with +0 and −0 in
/// their directions: the triangle that owns the crossing (by the tie-break's
/// step down every axis) lies in a box whose face plane holds the ray, and
/// the box test must let the ray in on that side.
#[test]
fn axis_aligned_rays_through_a_pyramids_apex_cross_it_twice() {
    for sides in [3, 5, 8, 9, 16, 17, 24, 40, 80] {
        let g = build(pyramid(sides));
        for zero in [0.0f32, -0.0] {
            for (origin, dz) in [(5.0f32, -1.0f32), (-5.0, 1.0)] {
                let ray = Ray::new(Vec3::new(0.0, 0.0, origin), Vec3::new(zero, zero, dz));
                let found = crossings(&g, &ray);
                assert_eq!(found.len(), 2, "{sides} sides, ray {ray:?}: {found:?}");
                assert_eq!(found, brute_crossings(&g.file_order_triangles(), &ray));
            }
        }
    }
}

/// Random rays through `g`'s box and rays aimed at `targets` through the
/// origin, a third of the random ones clipped to a random interval.
fn stream_rays(g: &Geometry, n: usize, targets: &[Vec3], seed: u64) -> Vec<Ray> {
    let mut rays = random_rays(g, n, seed);
    rays.extend(targets.iter().map(|&p| Ray::new(p * 3.0, -p)));
    rays
}

/// The stream forms (`count_crossings_stream`, `crossings_stream`,
/// `contains_stream`, several rays in flight where the tree prefetches,
/// one at a time where not) answer each ray as its own walk does and as
/// brute force does, for any number of rays, and rays aimed at every
/// vertex and edge midpoint of a closed icosphere still cross it twice.
#[test]
fn streams_of_crossings_equal_each_rays_own_walk_and_brute_force() {
    let (v, f) = icosphere(3);
    let mids: Vec<Vec3> = edges(&f)
        .iter()
        .map(|&(a, b)| (v[a as usize] + v[b as usize]) * 0.5)
        .collect();
    let (bv, mut bf) = bumpy();
    // Two shells, one inside the other: rays cross four layers.
    let n = bv.len() as u32;
    let mut shells = bv.clone();
    shells.extend(bv.iter().map(|&p| p * 0.3));
    bf.extend(bf.clone().iter().map(|t| t.map(|k| k + n)));
    let targets: Vec<Vec3> = v.iter().chain(&mids).copied().collect();
    for (mut g, aimed) in [(build((v.clone(), f)), true), (build((shells, bf)), false)] {
        let tris = g.file_order_triangles();
        let all = stream_rays(&g, 1500, if aimed { &targets } else { &[] }, 6);
        let points: Vec<Vec3> = all.iter().map(|r| r.origin * 0.4).collect();
        for prefetch in [false, true] {
            g.set_prefetch(prefetch);
            for count in [0, 1, 5, all.len()] {
                let rays = &all[..count];
                let mut counts = vec![u32::MAX; count];
                g.count_crossings_stream(rays, &mut counts);
                let mut found = Vec::new();
                let mut spans = vec![(usize::MAX, 0); count];
                g.crossings_stream(rays, &mut found, &mut spans);
                for (i, ray) in rays.iter().enumerate() {
                    let mut own = Vec::new();
                    g.crossings(ray, &mut own);
                    let (first, n) = spans[i];
                    let listed = &found[first..first + n as usize];
                    assert_eq!(listed, own.as_slice(), "ray {i} (prefetch {prefetch})");
                    assert_eq!(counts[i] as usize, own.len(), "ray {i}");
                    let parts: Vec<Crossing> =
                        own.iter().map(|&c| Crossing { part: 0, ..c }).collect();
                    assert_eq!(parts, brute_crossings(&tris, ray), "ray {i}: {ray:?}");
                    if aimed && i >= 1500 {
                        assert_eq!(n, 2, "aimed ray {i}: {ray:?}");
                    }
                }
                assert_eq!(
                    spans.iter().map(|s| s.1 as usize).sum::<usize>(),
                    found.len()
                );
                let mut inside = vec![false; count];
                g.contains_stream(&points[..count], &mut inside);
                let own: Vec<bool> = points[..count].iter().map(|&p| g.contains(p)).collect();
                assert_eq!(inside, own, "prefetch {prefetch}");
            }
        }
    }
}

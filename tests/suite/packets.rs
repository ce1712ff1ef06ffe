//! Packets, streams (bundles, narrow rays as packets, the rest as
//! several single rays in flight) and single rays return
//! identical hits: the same primitive, t,
//! u, v bit for bit, and the same occlusion answer, on coherent (lens
//! samples of a pixel, shadow rays from one point to an area light),
//! incoherent (random chords) and tie-heavy (aimed at shared vertices and
//! edges) ray sets, for every BVH quality.

use crate::common::checked::compile;
use crate::common::{bumpy_sphere_obj, scene_at, seeded, temp_dir, Draw};
use glam::Vec3;
use std::time::Instant;
use strata::accel::bundle::{BUNDLE_MAX_BYTES, BUNDLE_SIZE};
use strata::accel::{BuildQuality, PACKET_SIZE};
use strata::geometry::travel::{split_narrow, Travel};
use strata::math::Ray;
use strata::scene::{parse, RenderOverrides, Scene};

/// A bumpy UV sphere (shared edges everywhere) and a flat grid (rays aimed
/// at its vertices hit several triangles at exactly the same t).
fn write_meshes(dir: &std::path::Path) {
    let obj = bumpy_sphere_obj(48, 24, 1.0, 0.05);
    std::fs::write(dir.join("bumpy.obj"), obj).unwrap();
    let mut grid = String::new();
    let n = 16;
    for j in 0..=n {
        for i in 0..=n {
            grid += &format!("v {} -1.5 {}\n", i as f32 / 4.0 - 2.0, j as f32 / 4.0 - 2.0);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            grid += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    std::fs::write(dir.join("grid.obj"), grid).unwrap();
}

fn scenes() -> Vec<(BuildQuality, Scene)> {
    let dir = temp_dir("packets");
    write_meshes(&dir);
    let text = r#"
[[objects]]
mesh = "bumpy.obj"
[[objects]]
mesh = "grid.obj"
[[objects]]
sphere = { center = [1.2, 0.8, 0.5], radius = 0.3 }
[[objects]]
plane = { point = [0.0, -3.0, 0.0], normal = [0.0, 1.0, 0.0] }
"#;
    let path = dir.join("scene.toml");
    let desc = parse::parse_description(&path, text).unwrap();
    let mut out = vec![(BuildQuality::Auto, scene_at(text, &path))];
    for q in [
        BuildQuality::Fastest,
        BuildQuality::Fast,
        BuildQuality::Medium,
        BuildQuality::High,
    ] {
        let (scene, _) =
            compile::compile(&desc, &path, &RenderOverrides::default(), q, Instant::now()).unwrap();
        out.push((q, scene));
    }
    out
}

/// Batches of up to eight rays.
fn ray_sets(scene: &Scene) -> Vec<(&'static str, Vec<Vec<Ray>>)> {
    let mut rng = seeded(7);
    // Lens samples of one pixel: origins on a 0.1 lens, aimed at one focus point.
    let camera: Vec<Vec<Ray>> = (0..400)
        .map(|p| {
            let focus = Vec3::new(
                (p % 20) as f32 / 10.0 - 1.0,
                (p / 20) as f32 / 10.0 - 1.0,
                0.0,
            );
            (0..PACKET_SIZE)
                .map(|_| {
                    let o = Vec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), 3.0);
                    Ray::new(o, focus - o)
                })
                .collect()
        })
        .collect();
    // Shadow rays from points on the mesh to a square light, with tmax short of it.
    let shadow: Vec<Vec<Ray>> = camera
        .iter()
        .filter_map(|b| {
            scene
                .geometry
                .intersect(&b[0])
                .map(|h| b[0].at(h.t * 0.999))
        })
        .map(|p| {
            (0..PACKET_SIZE - (rng.unit() * 4.0) as usize)
                .map(|_| {
                    let l = Vec3::new(rng.range(-0.5, 0.5), 3.0, rng.range(-0.5, 0.5));
                    Ray::segment(p, l - p, 0.999)
                })
                .collect()
        })
        .collect();
    // Random chords of the bounding sphere, all in one octant (so they form
    // packets) and in any direction (so most fall back to single rays).
    let mut chords = |octant: bool| -> Vec<Vec<Ray>> {
        (0..300)
            .map(|_| {
                (0..PACKET_SIZE)
                    .map(|_| {
                        let a = rng.unit_vector() * 3.0;
                        let mut d = rng.unit_vector() * 3.0 - a;
                        if octant {
                            d = d.abs() * Vec3::new(-1.0, 1.0, -1.0);
                        }
                        Ray::new(a, d)
                    })
                    .collect()
            })
            .collect()
    };
    let one_octant = chords(true);
    let any = chords(false);
    // Aimed exactly at the grid's vertices and edge midpoints from one point.
    let mut aimed = Vec::new();
    for j in 0..=16 {
        let o = Vec3::new(0.1, 1.5, 0.05 * j as f32);
        aimed.push(
            (0..=16)
                .step_by(2)
                .take(PACKET_SIZE)
                .map(|i| {
                    let t = Vec3::new(
                        i as f32 / 4.0 - 2.0 + if j % 2 == 1 { 0.125 } else { 0.0 },
                        -1.5,
                        j as f32 / 4.0 - 2.0,
                    );
                    Ray::new(o, t - o)
                })
                .collect(),
        );
    }
    vec![
        ("camera", camera),
        ("shadow", shadow),
        ("chords-one-octant", one_octant),
        ("chords", any),
        ("aimed-at-vertices", aimed),
    ]
}

/// A hit as exact bits (t, prim, u, v), for bit-for-bit comparisons.
fn hit_bits(h: Option<strata::accel::PrimHit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()))
}

/// Asserts that `batch` as a packet gets exactly the single rays' closest
/// hits (t, prim, u, v bit for bit) and occlusion answers (ignoring
/// primitive `except`); returns how many rays hit.
fn assert_packet_matches_single_rays(
    scene: &Scene,
    batch: &[Ray],
    except: u32,
    label: &str,
) -> usize {
    let mut got = [None; PACKET_SIZE];
    scene.geometry.intersect_packet(batch, &mut got);
    let mut blocked = [false; PACKET_SIZE];
    scene.geometry.occluded_packet(batch, except, &mut blocked);
    let mut hits = 0;
    for (i, ray) in batch.iter().enumerate() {
        let want = scene.geometry.intersect(ray);
        assert_eq!(hit_bits(got[i]), hit_bits(want), "{label}: ray {ray:?}");
        assert_eq!(
            blocked[i],
            scene.geometry.occluded_except(ray, except),
            "{label} occlusion: ray {ray:?}"
        );
        hits += want.is_some() as usize;
    }
    hits
}

#[test]
fn packets_and_single_rays_return_identical_hits() {
    for (quality, scene) in scenes() {
        for (name, batches) in ray_sets(&scene) {
            let except = scene.geometry.triangle_count(); // the sphere
            let label = format!("{quality:?} {name}");
            let hits: usize = batches
                .iter()
                .map(|batch| assert_packet_matches_single_rays(&scene, batch, except, &label))
                .sum();
            assert!(hits > 0, "{name}: the set should hit something");
        }
    }
}

/// Rows of eight rays from one eye to points 0.002 apart, narrow enough
/// for a stream to send them as packets: a pinhole camera's pixels, a
/// quarter of the rows sweeping the bumpy sphere and the grid, a quarter
/// passing through the tree's box beyond the grid's edge to the plane
/// below, a quarter heading away from the tree's box to the plane behind
/// the eye, and a quarter through the analytic sphere (the primitive the
/// occlusion queries except) to what lies behind it.
fn pinhole_rows() -> Vec<Ray> {
    let eye = Vec3::new(0.3, 0.4, 3.0);
    (0..400)
        .flat_map(|row| {
            let r = row as f32;
            (0..PACKET_SIZE).map(move |i| {
                let x = i as f32 * 0.002;
                let target = match row % 4 {
                    0 => Vec3::new(-1.8 + r * 0.008 + x, 1.5 - r * 0.009, 0.0),
                    1 => Vec3::new(6.0 + r * 0.0075 + x, -3.0, -6.0),
                    2 => Vec3::new(-2.6 + r * 0.0075 + x, -3.0, 4.5),
                    _ => Vec3::new(1.05 + r * 0.0007 + x, 0.9 - r * 0.0005, 0.5),
                };
                Ray::new(eye, target - eye)
            })
        })
        .collect()
}

/// Rays from one eye to the bumpy sphere, the grid and the plane,
/// left and right of the eye in turn, so that every bundle of them walks
/// at least two octants.
fn alternating_fan() -> Vec<Ray> {
    let eye = Vec3::new(0.1, 0.4, 3.0);
    (0..3 * 256)
        .map(|i| {
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            let k = i as f32 / (3.0 * 256.0);
            let target = Vec3::new(eye.x + side * (0.05 + 2.0 * k), 1.2 - 4.0 * k, 0.0);
            Ray::new(eye, target - eye)
        })
        .collect()
}

/// A stream of rays (spans of alike rays as bundles, narrow rays as
/// packets, the rest several in flight at once where
/// the tree prefetches and one at a time where it does not) gets exactly
/// the single rays' closest hits and occlusion answers, with a plane
/// outside the BVH and a sphere as the excepted primitive; so do the same
/// rays a few at a time (`intersect_few`, `occluded_few`).
#[test]
fn streams_and_single_rays_return_identical_hits() {
    for (quality, mut scene) in scenes() {
        let mut rays: Vec<Ray> = ray_sets(&scene)
            .into_iter()
            .flat_map(|(_, batches)| batches.into_iter().flatten())
            .collect();
        // Eight rays that straddle the two sets are not narrow.
        rays.truncate(rays.len() / PACKET_SIZE * PACKET_SIZE + 3);
        let first_row = rays.len();
        rays.extend(pinhole_rows());
        rays.extend(alternating_fan());
        let (mut packets, mut outside) = (0, 0);
        split_narrow(&rays, &scene.geometry.bvh().bounds, |travel| match travel {
            Travel::Packet(..) => packets += 1,
            Travel::Outside(_) => outside += 1,
            _ => {}
        });
        assert!(
            packets >= 100 && outside >= 100,
            "{quality:?}: {packets} packets, {outside} packets outside the tree's box"
        );
        // Every ray is in one part. The pinhole rows' spans share one
        // origin and walk as bundles in order; spans of alike rays from
        // many origins (the lens samples, for one) walk sorted by octant.
        let mut seen = vec![0; rays.len()];
        let (mut one_origin, mut many_origins, mut scattered) = (0, 0, 0);
        scene.geometry.travel_stream(&rays, |travel| match travel {
            Travel::Packet(range, _)
            | Travel::Outside(range)
            | Travel::Alone(range)
            | Travel::InFlight(range) => range.for_each(|i| seen[i] += 1),
            Travel::Bundle(range) => {
                assert!(!range.is_empty() && range.len() <= BUNDLE_SIZE);
                let o = rays[range.start].origin;
                assert!(rays[range.clone()].iter().all(|r| r.origin == o));
                range.for_each(|i| seen[i] += 1);
                one_origin += 1;
            }
            Travel::Gathered(ids) => {
                assert!(!ids.is_empty() && ids.len() <= BUNDLE_SIZE);
                ids.iter().for_each(|&i| seen[i as usize] += 1);
                scattered += ids.windows(2).any(|w| w[1] != w[0] + 1) as usize;
                many_origins += 1;
            }
        });
        assert!(
            seen.iter().all(|&n| n == 1),
            "{quality:?}: a ray in no part or two"
        );
        assert!(
            one_origin >= 30 && many_origins >= 10 && scattered >= 10,
            "{quality:?}: {one_origin} bundles from one origin, {many_origins} from many, \
             {scattered} of rays apart in the stream"
        );
        assert!(scene.geometry.traversal_bytes() <= BUNDLE_MAX_BYTES);
        let except = scene.geometry.triangle_count(); // the sphere
        for prefetch in [true, false] {
            scene.geometry.set_prefetch(prefetch);
            let mut hits = vec![None; rays.len()];
            scene.geometry.intersect_stream(&rays, &mut hits);
            let mut blocked = vec![true; rays.len()];
            scene.geometry.occluded_stream(&rays, except, &mut blocked);
            for (i, ray) in rays.iter().enumerate() {
                let label = format!("{quality:?} prefetch {prefetch}: ray {i} {ray:?}");
                assert_eq!(
                    hit_bits(hits[i]),
                    hit_bits(scene.geometry.intersect(ray)),
                    "{label}"
                );
                assert_eq!(
                    blocked[i],
                    scene.geometry.occluded_except(ray, except),
                    "{label}"
                );
            }
            // A few at a time, as a path batch traces its bounce and
            // shadow rays: the same answers.
            for (k, few) in rays.chunks(PACKET_SIZE - 1).enumerate() {
                let at = k * (PACKET_SIZE - 1);
                let mut few_hits = [None; PACKET_SIZE];
                let mut few_blocked = [true; PACKET_SIZE];
                let n = few.len();
                scene.geometry.intersect_few(few, &mut few_hits[..n]);
                scene
                    .geometry
                    .occluded_few(few, except, &mut few_blocked[..n]);
                for j in 0..n {
                    let label = format!("{quality:?} prefetch {prefetch}: ray {} of a few", at + j);
                    assert_eq!(hit_bits(few_hits[j]), hit_bits(hits[at + j]), "{label}");
                    assert_eq!(few_blocked[j], blocked[at + j], "{label}");
                }
            }
            let found = hits.iter().filter(|h| h.is_some()).count();
            let open = blocked.iter().filter(|&&b| !b).count();
            let rows = &hits[first_row..];
            let (on_plane, on_bvh) = (
                rows.iter()
                    .flatten()
                    .filter(|h| h.prim > u32::MAX / 2)
                    .count(),
                rows.iter()
                    .flatten()
                    .filter(|h| h.prim < u32::MAX / 2)
                    .count(),
            );
            assert!(
                found > 1000 && open > 100 && on_plane > 100 && on_bvh > 100,
                "{quality:?}: {found} hits ({on_bvh} and {on_plane} on the BVH and plane from the rows), {open} unblocked"
            );
        }
    }
}

/// Software prefetching (the crate's one `unsafe`) is a hint only: rays
/// traced with it and with its safe fallback (prefetching off) get the
/// same closest hits, bit for bit, and the same occlusion answers, single
/// and as packets. The test scenes are small enough that `auto` leaves it
/// off, so both settings are forced.
#[test]
fn prefetching_changes_no_hit() {
    for (quality, mut scene) in scenes() {
        let sets = ray_sets(&scene);
        let trace = |scene: &Scene| {
            let mut answers = Vec::new();
            for batch in sets.iter().flat_map(|(_, batches)| batches) {
                let mut hits = [None; PACKET_SIZE];
                scene.geometry.intersect_packet(batch, &mut hits);
                let mut blocked = [false; PACKET_SIZE];
                scene
                    .geometry
                    .occluded_packet(batch, u32::MAX, &mut blocked);
                for (i, ray) in batch.iter().enumerate() {
                    answers.push((
                        hit_bits(scene.geometry.intersect(ray)),
                        scene.geometry.occluded(ray),
                        hit_bits(hits[i]),
                        blocked[i],
                    ));
                }
            }
            answers
        };
        scene.geometry.set_prefetch(true);
        let with = trace(&scene);
        scene.geometry.set_prefetch(false);
        let without = trace(&scene);
        assert!(with.iter().filter(|a| a.0.is_some()).count() > 1000);
        assert_eq!(with, without, "{quality:?}");
    }
}

/// Every kind of ray `strata rays` makes (on a closed icosphere), batched
/// eight at a time two ways: sorted by direction octant (every axis agrees
/// in sign), and in generation order, where most packets differ in sign on
/// one or two axes. Either way: the same hits and occlusion answers as
/// single rays.
#[test]
fn packets_match_single_rays_on_every_strata_rays_kind() {
    use strata::accel::Packet;
    use strata::rays::{generate, RayKind};
    let dir = temp_dir("packets-kinds");
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/icosphere.obj");
    let scene = scene_at(
        &format!("[[objects]]\nmesh = {mesh:?}\n"),
        &dir.join("scene.toml"),
    );
    let triangles = scene.geometry.file_order_triangles();
    let octant = |r: &Ray| {
        (r.direction.x < 0.0) as u8
            | ((r.direction.y < 0.0) as u8) << 1
            | ((r.direction.z < 0.0) as u8) << 2
    };
    // Packets formed, of those with mixed signs, and rays that hit.
    let check = |kind: RayKind, batches: &mut dyn Iterator<Item = &[Ray]>| {
        let (mut packets, mut mixed, mut hits) = (0, 0, 0);
        for batch in batches {
            if Packet::new(batch).is_some() {
                packets += 1;
                mixed += batch.iter().any(|r| octant(r) != octant(&batch[0])) as usize;
            }
            hits += assert_packet_matches_single_rays(&scene, batch, u32::MAX, &kind.to_string());
        }
        (packets, mixed, hits)
    };
    for kind in RayKind::ALL {
        let mut rays = generate(kind, &triangles, 2000, 5).unwrap();
        let (_, _, hits) = check(kind, &mut rays.chunks(PACKET_SIZE));
        assert!(hits > 100, "{kind}: only {hits} of 2000 rays hit");
        rays.sort_by_key(octant);
        let (packets, mixed, _) = check(
            kind,
            &mut rays
                .chunk_by(|a, b| octant(a) == octant(b))
                .flat_map(|g| g.chunks(PACKET_SIZE)),
        );
        assert!(
            packets >= 2000 / PACKET_SIZE - 8,
            "{kind}: only {packets} packets formed"
        );
        assert_eq!(mixed, 0);
    }
    // Mixed-sign packets really form (only three mixed axes fall back to
    // single rays): narrow fans of rays whose x and y components straddle
    // zero, some exactly ±0, like the lens samples of a pixel at the centre
    // of the image.
    let mut rng = seeded(17);
    let fans: Vec<Ray> = (0..300)
        .flat_map(|_| {
            let eye = Vec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), -4.0);
            let (ax, ay) = (rng.range(-0.05, 0.05), rng.range(-0.05, 0.05));
            let spread = rng.range(0.0, 0.1);
            let jitter: [f32; 2 * PACKET_SIZE] = std::array::from_fn(|_| rng.range(-0.5, 0.5));
            (0..PACKET_SIZE).map(move |lane| {
                let mut d = Vec3::new(
                    ax + spread * jitter[2 * lane],
                    ay + spread * jitter[2 * lane + 1],
                    1.0,
                );
                match lane {
                    0 => d.x = 0.0,
                    1 => d.x = -0.0,
                    _ => {}
                }
                Ray::new(eye, d)
            })
        })
        .collect();
    let (packets, mixed, hits) = check(RayKind::Camera, &mut fans.chunks(PACKET_SIZE));
    assert!(
        packets == 300 && mixed > 200 && hits > 500,
        "{packets} packets, {mixed} of them mixed, {hits} hits"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

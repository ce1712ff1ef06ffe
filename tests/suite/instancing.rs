//! Instances against copies: a mesh placed by `instances = "FILE.csv"`
//! (stored once, walked in object space) and the same mesh copied into
//! world space once per placement give the same hits, surfaces and
//! images within float rounding, under random affine maps with
//! non-uniform scale, shear and mirroring; every way of tracing answers
//! an instanced scene alike; bad placement files name their line; and a
//! thousand instances cost the mesh once plus a fixed record each.

use crate::common::meshes::{placement_row, random_affine};
use crate::common::queries::barycentric;
use crate::common::{
    bumpy_sphere_obj, render_rgb, scene_at, seeded, stderr, strata, temp_dir, Draw,
    StreamRng as Rng,
};
use glam::{Affine3A, Mat3, Vec3};
use strata::accel::PrimHit;
use strata::math::Ray;
use strata::scene::Scene;

/// The same map as a scene file's `transform = { matrix = ... }`.
fn toml_matrix(a: &Affine3A) -> String {
    let m = Mat3::from(a.matrix3).transpose();
    let t = a.translation;
    let r = [m.x_axis, m.y_axis, m.z_axis];
    let rows: Vec<String> = (0..3)
        .map(|i| format!("[{}, {}, {}, {}]", r[i].x, r[i].y, r[i].z, t[i]))
        .collect();
    format!("{}, [0.0, 0.0, 0.0, 1.0]", rows.join(", "))
}

/// An instanced scene and the same placements as world-space copies (one
/// copy of the mesh file per placement, each placed once, so baked).
struct Pair {
    instanced: Scene,
    copied: Scene,
    placements: Vec<Affine3A>,
    /// Triangles of the mesh.
    triangles: u32,
    _dir: crate::common::TempDir,
}

const LIGHTS: &str = "[[lights]]\ntype = \"point\"\nposition = [0.0, 30.0, 20.0]\nintensity = [3000.0, 3000.0, 3000.0]\n\
[camera]\nposition = [0.0, 4.0, 22.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\n\
[render]\nwidth = 48\nheight = 40\nspp = 4\n";

fn pair(seed: u64, count: usize) -> Pair {
    let dir = temp_dir("instancing");
    let mut rng = seeded(seed);
    let obj = bumpy_sphere_obj(18, 12, 1.0, 0.25);
    std::fs::write(dir.join("m.obj"), &obj).unwrap();
    let placements: Vec<Affine3A> = (0..count).map(|_| random_affine(&mut rng, 6.0)).collect();
    let rows: Vec<String> = placements.iter().map(placement_row).collect();
    std::fs::write(dir.join("places.csv"), rows.join("\n") + "\n").unwrap();
    let instanced = scene_at(
        &format!("{LIGHTS}[[objects]]\nmesh = \"m.obj\"\ninstances = \"places.csv\"\n"),
        &dir.join("a.toml"),
    );
    let mut copies = LIGHTS.to_string();
    for (k, a) in placements.iter().enumerate() {
        std::fs::write(dir.join(format!("m{k}.obj")), &obj).unwrap();
        copies += &format!(
            "[[objects]]\nmesh = \"m{k}.obj\"\ntransform = {{ matrix = [{}] }}\n",
            toml_matrix(a)
        );
    }
    let copied = scene_at(&copies, &dir.join("b.toml"));
    Pair {
        instanced,
        copied,
        placements,
        triangles: 2 * 18 * 12,
        _dir: dir,
    }
}

/// A hit as (placement, triangle of the mesh), whichever scene it is from.
fn which(scene: &Scene, hit: &PrimHit, offsets: &[u64], triangles: u32) -> (u64, u64) {
    let flat = if scene.geometry.instances().is_empty() {
        u64::from(hit.prim)
    } else {
        scene.geometry.flat_prim(hit, offsets) - offsets[0]
    };
    (flat / u64::from(triangles), flat % u64::from(triangles))
}

/// Rays at points inside random triangles of random placements (which
/// both scenes must hit), and rays through the placements' region in
/// random directions.
fn rays(p: &Pair, rng: &mut Rng, n: usize) -> Vec<Ray> {
    let tris = p.copied.geometry.file_order_triangles();
    (0..n)
        .map(|i| {
            let target = if i % 2 == 0 {
                let t = tris[(rng.range(0.0, 1.0) * tris.len() as f32) as usize % tris.len()];
                let (u, v) = (rng.range(0.05, 0.45), rng.range(0.05, 0.45));
                (1.0 - u - v) * t[0] + u * t[1] + v * t[2]
            } else {
                rng.unit_vector() * rng.range(0.0, 7.0)
            };
            let origin = target + rng.unit_vector() * 25.0;
            Ray::new(origin, (target - origin).normalize())
        })
        .collect()
}

#[test]
fn instances_hit_what_world_space_copies_hit() {
    let p = pair(45, 12);
    assert_eq!(p.instanced.geometry.triangle_count(), 0, "nothing baked");
    assert_eq!(p.instanced.geometry.prototypes().len(), 1, "stored once");
    assert_eq!(p.instanced.geometry.instances().len(), p.placements.len());
    assert_eq!(
        p.copied.geometry.triangle_count(),
        p.triangles * p.placements.len() as u32
    );
    let offsets = p.instanced.geometry.flat_offsets();
    let mut rng = seeded(7);
    let rays = rays(&p, &mut rng, 6000);
    let (mut hits, mut other_triangle, mut grazing) = (0, 0, 0);
    for (i, ray) in rays.iter().enumerate() {
        let a = p.instanced.geometry.intersect(ray);
        let b = p.copied.geometry.intersect(ray);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                // The rays start 25 away: their rounding there (in object
                // space or in world space) moves a hit along the ray by
                // that much over the cosine of incidence.
                let sb = p.copied.geometry.surface(ray, &b);
                let cos = ray.direction.dot(sb.geometric_normal).abs().max(1e-3);
                let tol = 1e-5 * (25.0 + b.t) / cos;
                if (a.t - b.t).abs() > tol {
                    // Two surfaces: allowed only where the nearer hit grazes
                    // its triangle's edge (exactly, in f64), as at a
                    // silhouette, where rounding in either space decides.
                    let copies = p.copied.geometry.file_order_triangles();
                    let nearer = if b.t < a.t {
                        copies[b.prim as usize]
                    } else {
                        let (k, j) = which(&p.instanced, &a, &offsets, p.triangles);
                        copies[(k * u64::from(p.triangles) + j) as usize]
                    };
                    let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
                    let margin = barycentric(&nearer.map(|v| v.as_dvec3()), o, d).1;
                    assert!(
                        margin.abs() < 1e-4,
                        "ray {i}: t {} against {}, {margin} inside",
                        a.t,
                        b.t
                    );
                    grazing += 1;
                    continue;
                }
                assert!(
                    (a.t - b.t).abs() <= tol,
                    "ray {i}: t {} against {}",
                    a.t,
                    b.t
                );
                let (wa, wb) = (
                    which(&p.instanced, &a, &offsets, p.triangles),
                    which(&p.copied, &b, &offsets, p.triangles),
                );
                if wa != wb {
                    // Only a tie at a shared edge may pick the other triangle.
                    other_triangle += 1;
                    continue;
                }
                let sa = p.instanced.geometry.surface(ray, &a);
                assert!(
                    (sa.p - sb.p).length() <= 1e-5 * (25.0 + sb.p.length()) / cos,
                    "ray {i}: point {:?} against {:?}",
                    sa.p,
                    sb.p
                );
                assert!(
                    sa.geometric_normal.dot(sb.geometric_normal) > 0.9999,
                    "ray {i}: normal {:?} against {:?} (inverse transpose under non-uniform scale)",
                    sa.geometric_normal,
                    sb.geometric_normal
                );
                assert!(sa.shading_normal.dot(sb.shading_normal) > 0.9999);
                assert_eq!(sa.material, sb.material);
                // The error bound covers the exact world point of the hit's
                // barycentrics, computed in f64 from the object-space triangle.
                let g = &p.instanced.geometry;
                let inst = g.instances()[wa.0 as usize];
                let v = g.object_triangle(&a).map(|x| x.as_dvec3());
                let (u, w) = (f64::from(a.u), f64::from(a.v));
                let exact = inst
                    .affine_f64()
                    .transform_point3((1.0 - u - w) * v[0] + u * v[1] + w * v[2]);
                let off = (sa.p.as_dvec3() - exact).abs().as_vec3();
                assert!(
                    (off - sa.p_error).max_element() <= 0.0,
                    "ray {i}: the point is {off:?} off, its bound {:?}",
                    sa.p_error
                );
            }
            (a, b) => panic!("ray {i}: instanced {a:?}, copied {b:?}"),
        }
    }
    assert!(hits > 3000, "most rays hit ({hits})");
    assert!(
        grazing * 1000 <= hits,
        "{grazing} of {hits} rays met another surface"
    );
    assert!(
        other_triangle * 1000 <= hits,
        "{other_triangle} of {hits} hits found another triangle"
    );
}

#[test]
fn packets_streams_and_occlusion_answer_an_instanced_scene_as_single_rays_do() {
    let p = pair(46, 20);
    let g = &p.instanced.geometry;
    let mut rng = seeded(8);
    let mut rays = rays(&p, &mut rng, 4096);
    // Shorter rays for occlusion: some end before what they would hit.
    for (i, r) in rays.iter_mut().enumerate() {
        if i % 3 == 0 {
            r.tmax = 25.0;
        }
    }
    let single: Vec<Option<PrimHit>> = rays.iter().map(|r| g.intersect(r)).collect();
    let mut stream = vec![None; rays.len()];
    g.intersect_stream(&rays, &mut stream);
    assert_eq!(stream, single, "a stream answers as single rays do");
    for (chunk, expect) in rays.chunks(8).zip(single.chunks(8)) {
        let mut out = [None; 8];
        g.intersect_packet(chunk, &mut out);
        assert_eq!(
            &out[..chunk.len()],
            expect,
            "a packet answers as single rays do"
        );
    }
    let blocked: Vec<bool> = rays.iter().map(|r| g.occluded(r)).collect();
    let mut occluded = vec![false; rays.len()];
    g.occluded_stream(&rays, u32::MAX, &mut occluded);
    assert_eq!(occluded, blocked);
    // Both answer for (tmin, tmax], a hit at tmax itself included.
    for (i, (r, s)) in rays.iter().zip(&single).enumerate() {
        assert_eq!(blocked[i], s.is_some_and(|h| h.t <= r.tmax), "ray {i}");
    }
    assert!(blocked.iter().any(|&b| b) && blocked.iter().any(|&b| !b));
}

/// A camera's rays (one origin, neighbours in order) travel as bundles
/// and packets, whose rays enter each instance's prototype together
/// (`geometry::instance_bundle`): they must answer as each ray alone does,
/// where two placements coincide (equal t, the lower id wins), in leaves
/// that also hold a sphere and world triangles, for rays cut short and
/// for an occlusion ray that skips one instance.
#[test]
fn alike_rays_enter_instances_together_and_answer_as_single_rays_do() {
    let dir = temp_dir("instancing-together");
    let mut rng = seeded(9);
    std::fs::write(dir.join("m.obj"), bumpy_sphere_obj(14, 10, 1.0, 0.25)).unwrap();
    std::fs::write(dir.join("w.obj"), bumpy_sphere_obj(3, 2, 1.3, 0.1)).unwrap();
    let mut placements: Vec<Affine3A> = (0..24).map(|_| random_affine(&mut rng, 5.0)).collect();
    // The same placement twice: every hit on one is a tie with the other.
    placements.push(placements[3]);
    let rows: Vec<String> = placements.iter().map(placement_row).collect();
    std::fs::write(dir.join("places.csv"), rows.join("\n") + "\n").unwrap();
    // The world mesh and the sphere amid two placements, so that some
    // leaves hold them beside instances.
    let (a, b) = (placements[0].translation, placements[1].translation);
    let s = scene_at(
        &format!(
            "{LIGHTS}[[objects]]\nmesh = \"m.obj\"\ninstances = \"places.csv\"\n\
             [[objects]]\nmesh = \"w.obj\"\ntransform = {{ translate = [{}, {}, {}] }}\n\
             [[objects]]\nsphere = {{ center = [{}, {}, {}], radius = 1.2 }}\n",
            a.x, a.y, a.z, b.x, b.y, b.z
        ),
        &dir.join("s.toml"),
    );
    let g = &s.geometry;
    assert!(g.instances().len() == placements.len() && g.triangle_count() > 0);
    // A pinhole grid from one point, row by row, some rays cut short.
    let eye = Vec3::new(0.5, 1.5, 18.0);
    let (w, h) = (96, 80);
    let rays: Vec<Ray> = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            let d = Vec3::new(x / w as f32 - 0.5, 0.45 - y / h as f32, -1.6);
            let mut r = Ray::new(eye, d.normalize());
            if k % 5 == 0 {
                r.tmax = 16.0 + (k % 7) as f32;
            }
            r
        })
        .collect();
    let single: Vec<Option<PrimHit>> = rays.iter().map(|r| g.intersect(r)).collect();
    let first = g.first_instance();
    let on = |k: u32| {
        single
            .iter()
            .flatten()
            .filter(|h| h.prim == first + k)
            .count()
    };
    assert!(on(3) > 50, "rays meet the doubled placement ({})", on(3));
    assert_eq!(on(24), 0, "a tie goes to the lower id");
    assert!(
        single.iter().flatten().any(|h| h.prim < first),
        "rays meet the sphere and the world triangles"
    );
    let mut stream = vec![None; rays.len()];
    g.intersect_stream(&rays, &mut stream);
    assert_eq!(stream, single, "a stream answers as single rays do");
    for (chunk, expect) in rays.chunks(8).zip(single.chunks(8)) {
        let mut out = [None; 8];
        g.intersect_packet(chunk, &mut out);
        assert_eq!(&out[..chunk.len()], expect, "a packet as single rays");
    }
    for except in [u32::MAX, first, first + 1, first + 3, first - 1] {
        let blocked: Vec<bool> = rays.iter().map(|r| g.occluded_except(r, except)).collect();
        let mut stream = vec![false; rays.len()];
        g.occluded_stream(&rays, except, &mut stream);
        assert_eq!(stream, blocked, "occlusion skipping {except}, a stream");
        for (chunk, expect) in rays.chunks(8).zip(blocked.chunks(8)) {
            let mut out = [false; 8];
            g.occluded_packet(chunk, except, &mut out);
            assert_eq!(&out[..chunk.len()], expect, "skipping {except}, a packet");
        }
        assert!(blocked.iter().any(|&b| b) && blocked.iter().any(|&b| !b));
    }
}

#[test]
fn an_instanced_mesh_renders_as_its_world_space_copies() {
    let p = pair(47, 6);
    let a = render_rgb(&p.instanced, 2);
    let b = render_rgb(&p.copied, 2);
    let total: f32 = b.iter().map(|c| c.element_sum()).sum();
    assert!(total > 0.0, "the scene is lit");
    let diff: f32 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (*x - *y).abs().element_sum())
        .sum();
    assert!(diff <= 1e-4 * total, "images differ by {diff} of {total}");
    let off = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| (**x - **y).abs().max_element() > 1e-3 * y.max_element().max(1e-3))
        .count();
    assert!(off * 200 <= a.len(), "{off} of {} pixels differ", a.len());
}

#[test]
fn a_mesh_file_placed_twice_is_stored_once() {
    let dir = temp_dir("instancing-twice");
    std::fs::write(dir.join("m.obj"), bumpy_sphere_obj(8, 6, 1.0, 0.1)).unwrap();
    let text = "[materials.red]\ndiffuse = [0.8, 0.1, 0.1]\n\
        [[objects]]\nmesh = \"m.obj\"\n\
        [[objects]]\nmesh = \"m.obj\"\nmaterial = \"red\"\ntransform = { translate = [3.0, 0.0, 0.0] }\n\
        [[objects]]\ngroup = [{ mesh = \"other.obj\" }]\n";
    std::fs::write(dir.join("other.obj"), bumpy_sphere_obj(4, 3, 1.0, 0.0)).unwrap();
    let s = scene_at(text, &dir.join("s.toml"));
    let g = &s.geometry;
    assert_eq!(
        (
            g.prototypes().len(),
            g.instances().len(),
            g.triangle_count()
        ),
        (1, 2, 24),
        "m.obj once, placed twice; other.obj, placed once, baked"
    );
    // Each placement keeps its own material.
    let hit_material = |x: f32| {
        let ray = Ray::new(Vec3::new(x, 0.0, 10.0), -Vec3::Z);
        let hit = g.intersect(&ray).expect("hit");
        s.materials[g.surface(&ray, &hit).material as usize].diffuse
    };
    assert_eq!(hit_material(0.0), s.materials[0].diffuse);
    assert_eq!(hit_material(3.0), Vec3::new(0.8, 0.1, 0.1));
}

#[test]
fn a_bad_instances_file_names_its_line_and_writes_nothing() {
    let dir = temp_dir("instancing-bad");
    std::fs::write(dir.join("m.obj"), bumpy_sphere_obj(6, 4, 1.0, 0.0)).unwrap();
    let good = "1,0,0,0, 0,1,0,0, 0,0,1,0";
    let cases = [
        (format!("{good}\n1,2,3\n"), "line 2", "expected 12 numbers"),
        (
            format!("# header\n{good}\n\n0,0,0,0,0,0,0,0,0,0,0,0\n"),
            "line 4",
            "singular",
        ),
        (
            format!("{good}\n1,0,0,NaN,0,1,0,0,0,0,1,0\n"),
            "line 2",
            "not finite",
        ),
        (
            format!("{good}\n1,0,0,x,0,1,0,0,0,0,1,0\n"),
            "line 2",
            "not a number",
        ),
    ];
    for (csv, line, what) in cases {
        std::fs::write(dir.join("i.csv"), &csv).unwrap();
        std::fs::write(
            dir.join("s.toml"),
            "[[objects]]\nmesh = \"m.obj\"\ninstances = \"i.csv\"\n[render]\nwidth = 8\nheight = 8\nspp = 1\n",
        )
        .unwrap();
        let out = strata(&dir, &["render", "s.toml", "-o", "out.png", "--quiet"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("i.csv") && err.contains(line) && err.contains(what),
            "{csv:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!dir.join("out.png").exists());
    }
    let out = strata(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "out.png",
            "--quiet",
            "--set",
            "objects[0].instances=\"none.csv\"",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("none.csv"), "{}", stderr(&out));
}

#[test]
fn a_thousand_instances_cost_the_mesh_once_and_at_most_200_bytes_each() {
    let dir = temp_dir("instancing-memory");
    std::fs::write(dir.join("m.obj"), bumpy_sphere_obj(64, 48, 1.0, 0.2)).unwrap();
    let mut rng = seeded(3);
    let rows: Vec<String> = (0..1000)
        .map(|_| placement_row(&random_affine(&mut rng, 100.0)))
        .collect();
    std::fs::write(dir.join("i.csv"), rows.join("\n")).unwrap();
    std::fs::write(dir.join("one.csv"), "1,0,0,0,0,1,0,0,0,0,1,0\n").unwrap();
    let bytes = |csv: &str| {
        let text = format!("[[objects]]\nmesh = \"m.obj\"\ninstances = \"{csv}\"\n");
        let s = scene_at(&text, &dir.join("s.toml"));
        (s.geometry.accel_bytes(), s.geometry.instances().len())
    };
    let (one, n1) = bytes("one.csv");
    let (thousand, n) = bytes("i.csv");
    assert_eq!((n1, n), (1, 1000));
    let per_instance = (thousand - one) as f64 / 999.0;
    assert!(
        per_instance <= 200.0,
        "{per_instance:.0} bytes per instance (mesh {one} bytes)"
    );
    // And the mesh is not copied: a thousand copies would be 1000x.
    assert!(thousand < 2 * one, "{thousand} against {one}");
}

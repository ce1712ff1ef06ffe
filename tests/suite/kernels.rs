//! The walks' kernels (`strata::accel::Kernel`: the build's own, and the
//! copy compiled for AVX-512 where the CPU has it) give the same hits bit
//! for bit, and those are brute force's: every triangle tested, the tie
//! on equal t to the lower id. Rays of every `strata rays` kind (random
//! chords, a camera's, grazing, aimed at shared edges and vertices, from
//! inside), some cut short, on a closed bumpy torus and on the bunny where
//! `tools/fetch-assets` has fetched it. Where the CPU lacks AVX-512 the
//! build's kernel is still held to brute force, and the skip is said.

use crate::common::process::repo;
use crate::common::{load_mesh_scene, skipped};
use glam::Vec3;
use strata::accel::{BuildQuality, Kernel};
use strata::geometry::Geometry;
use strata::math::ray::hit_before;
use strata::math::Ray;
use strata::rays::{generate, RayKind};
use strata::scene::mesh_geometry;
use strata::shape::triangle::{intersect, ShearedRay};

/// A torus (radii 1 and 0.35) with bumps, `nu` × `nv` quads split in two:
/// closed, every edge shared by two triangles.
fn bumpy_torus(nu: u32, nv: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b) = (
                i as f32 / nu as f32 * std::f32::consts::TAU,
                j as f32 / nv as f32 * std::f32::consts::TAU,
            );
            let r = 0.35 + 0.04 * (5.0 * a).sin() * (3.0 * b).cos();
            v.push(Vec3::new(
                (1.0 + r * b.cos()) * a.cos(),
                r * b.sin(),
                (1.0 + r * b.cos()) * a.sin(),
            ));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut f = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (v, f)
}

/// Brute force's closest hit, (t, triangle), and whether anything blocks.
fn brute(tris: &[[Vec3; 3]], ray: &Ray) -> (Option<(f32, u32)>, bool) {
    let s = ShearedRay::new(ray);
    let mut best: Option<(f32, u32)> = None;
    for (i, tri) in tris.iter().enumerate() {
        if let Some((t, _, _)) = intersect(ray, &s, tri) {
            let i = i as u32;
            if best.is_none_or(|(bt, bi)| hit_before(t, i, bt, bi)) {
                best = Some((t, i));
            }
        }
    }
    (best, best.is_some())
}

/// Every kernel's answers against the build kernel's and brute force's;
/// returns the hits found.
fn check(g: &Geometry, name: &str, rays_per_kind: usize) -> usize {
    let tris = g.file_order_triangles();
    let kernels = Kernel::available();
    let mut hits = 0;
    for kind in RayKind::ALL {
        let mut rays = generate(kind, &tris, rays_per_kind, 7).unwrap();
        // Every third ray cut short, somewhere along its first stretch.
        for (i, r) in rays.iter_mut().enumerate().filter(|(i, _)| i % 3 == 0) {
            r.tmax = r.tmax.min(0.1 + (i % 17) as f32 * 0.2);
        }
        for (i, ray) in rays.iter().enumerate() {
            let (closest, blocked) = brute(&tris, ray);
            let base = g.intersect_in(Kernel::build(), ray);
            assert_eq!(
                base.map(|h| (h.t, h.prim)),
                closest,
                "{name} {kind} ray {i} {ray:?}: the build's kernel against brute force"
            );
            hits += base.is_some() as usize;
            for &k in &kernels {
                let got = g.intersect_in(k, ray);
                assert_eq!(
                    got.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits(), h.part)),
                    base.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits(), h.part)),
                    "{name} {kind} ray {i}: kernel {}",
                    k.name()
                );
                assert_eq!(
                    g.occluded_except_in(k, ray, u32::MAX),
                    blocked,
                    "{name} {kind} ray {i}: kernel {} occlusion",
                    k.name()
                );
            }
        }
    }
    hits
}

#[test]
fn every_kernel_gives_brute_forces_hits_bit_for_bit() {
    if Kernel::avx512().is_none() {
        skipped(
            "every_kernel_gives_brute_forces_hits_bit_for_bit (avx512 part)",
            "this CPU lacks AVX-512; the build's kernel alone is checked",
        );
    }
    let (v, f) = bumpy_torus(48, 24);
    let g = mesh_geometry(v, f, BuildQuality::Auto).unwrap();
    let hits = check(&g, "torus", 1500);
    assert!(hits > 3000, "only {hits} hits: the rays must hit");
    let bunny = repo().join("assets/bunny.obj");
    if !bunny.exists() {
        skipped(
            "every_kernel_gives_brute_forces_hits_bit_for_bit (bunny part)",
            "assets/bunny.obj not fetched (tools/fetch-assets)",
        );
        return;
    }
    let (scene, _) = load_mesh_scene(&bunny, BuildQuality::Auto).unwrap();
    check(&scene.geometry, "bunny", 200);
}

/// `STRATA_SIMD` picks the kernel `strata trace` reports; a name it does
/// not know is a one-line input error naming the variable, exit 2, before
/// any work.
#[test]
fn strata_simd_picks_the_kernel_and_refuses_an_unknown_one() {
    use crate::common::process::strata_command;
    let dir = crate::common::temp_dir("kernels");
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let trace = |simd: &str, hits: &str| {
        strata_command(&dir)
            .env("STRATA_SIMD", simd)
            .args([
                "rays", "random", "tri.obj", "-n", "50", "-o", "r.rays", "--quiet",
            ])
            .output()
            .unwrap();
        strata_command(&dir)
            .env("STRATA_SIMD", simd)
            .args(["trace", "tri.obj", "--rays", "r.rays", "--hits", hits])
            .output()
            .unwrap()
    };
    for k in Kernel::available() {
        let out = trace(k.name(), "h.hits");
        assert!(out.status.success(), "{}", crate::common::stderr(&out));
        let text = crate::common::stdout(&out);
        assert!(text.contains(&format!("kernel {})", k.name())), "{text}");
    }
    let out = trace("avx9", "bad.hits");
    assert_eq!(out.status.code(), Some(2));
    let err = crate::common::stderr(&out);
    assert!(
        err.starts_with("error: <environment>: STRATA_SIMD: 'avx9' is not a kernel")
            && err.lines().count() == 1,
        "{err}"
    );
    assert!(!dir.join("bad.hits").exists(), "no output before the check");
}

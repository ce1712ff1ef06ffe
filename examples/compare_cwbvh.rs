//! The same rays through obvhs's own compressed-wide BVH (CWBVH, Ylitie et
//! al. 2017: its traversal and its triangle test) and through strata's
//! 8-wide layout, both built by obvhs PLOC with the medium preset, one
//! thread, median of 5 passes. The issue asked to measure both layouts.
//!
//! ```sh
//! strata rays random assets/bunny.obj -n 200000 --seed 9 -o random.rays
//! cargo run --release --example compare_cwbvh -- assets/bunny.obj random.rays strata
//! cargo run --release --example compare_cwbvh -- assets/bunny.obj random.rays cwbvh
//! ```
use glam::Vec3A;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use strata::scene::{compile, parse, RenderOverrides};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, mesh, rays_path, which] = &args[..] else {
        eprintln!("usage: compare_cwbvh MESH RAYS.bin strata|cwbvh");
        std::process::exit(2);
    };
    let abs = std::fs::canonicalize(mesh).unwrap();
    let text = format!("[[objects]]\nmesh = {:?}\n", abs.display().to_string());
    let p = PathBuf::from("x.toml");
    let desc = parse::parse_description(&p, &text).unwrap();
    let (scene, _) = compile::compile(
        &desc,
        &p,
        &RenderOverrides::default(),
        Default::default(),
        Instant::now(),
    )
    .unwrap();
    let rays = strata::rays::file::read_rays(std::path::Path::new(rays_path)).unwrap();
    let tris: Vec<Triangle> = scene
        .geometry
        .file_order_triangles()
        .iter()
        .map(|t| Triangle {
            v0: t[0].into(),
            v1: t[1].into(),
            v2: t[2].into(),
        })
        .collect();
    let bvh = build_cwbvh_from_tris(
        &tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let mut times = vec![];
    let mut hits = 0;
    for _ in 0..5 {
        let start = Instant::now();
        hits = 0;
        for r in &rays {
            if which == "cwbvh" {
                let ray = ORay::new(
                    Vec3A::from(r.origin),
                    Vec3A::from(r.direction),
                    r.tmin,
                    r.tmax,
                );
                let mut hit = RayHit::none();
                if cw(&bvh, &tris, ray, &mut hit) {
                    hits += 1;
                }
            } else if scene.geometry.intersect(r).is_some() {
                hits += 1;
            }
        }
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{which}: {hits} hits, {:.2} Mrays/s (median of 5)",
        rays.len() as f64 / times[2] / 1e6
    );
}
/// obvhs's closest-hit traversal with its own triangle test.
#[inline(never)]
fn cw(bvh: &obvhs::cwbvh::CwBvh, tris: &[Triangle], ray: ORay, hit: &mut RayHit) -> bool {
    bvh.ray_traverse(ray, hit, |ray, id| {
        tris[bvh.primitive_indices[id] as usize].intersect(ray)
    })
}

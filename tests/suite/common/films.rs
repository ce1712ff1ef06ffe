//! Films of rendered scenes, whole or sliced, for the tests of
//! bit-identity across threads and slices.

use glam::Vec3;
use std::path::PathBuf;
use strata::partial::format::{read_partial_from, write_partial_to, Partial, PartialHeader};
use strata::render::film::{Film, PixelSum, FIXED_SCALE};
use strata::render::schedule::render_pixel;
use strata::render::{render, RenderOptions, SliceSpec};
use strata::scene::Scene;
use strata::shade::Integrator;

/// `slice` of `scene` rendered on `threads` threads.
pub fn film_of(scene: &Scene, slice: SliceSpec, threads: usize) -> Film {
    let opts = RenderOptions {
        threads,
        slice,
        ..RenderOptions::default()
    };
    render(scene, &opts, None, ()).film
}

/// A slice rendered and sent through the partial format in memory.
pub fn part(scene: &Scene, slice: SliceSpec, threads: usize) -> (PathBuf, Partial) {
    let film = film_of(scene, slice, threads);
    let header = PartialHeader::for_scene(scene, slice, slice.samples(scene.settings.spp));
    let mut bytes = Vec::new();
    write_partial_to(&mut bytes, &header, &film).unwrap();
    let back = read_partial_from(bytes.as_slice(), bytes.len() as u64).unwrap();
    (PathBuf::from(format!("part_{}.strata", slice.index)), back)
}

/// Each pixel's mean of `scene` at `seed` and `spp` samples, in row
/// order, rendered pixel by pixel on this thread; no sample may be NaN or
/// infinite.
pub fn pixel_means(scene: &Scene, seed: u32, spp: u32) -> Vec<Vec3> {
    let mut s = scene.clone();
    s.settings.seed = seed;
    s.settings.spp = spp;
    let mut integrator = Integrator::new(&s);
    let n = (s.settings.width * s.settings.height) as usize;
    (0..n)
        .map(|i| {
            let mut acc = PixelSum::default();
            render_pixel(&mut integrator, &s, i, 0..spp, &mut acc);
            assert_eq!(acc.invalid, 0, "no NaN or infinite samples");
            Vec3::from(acc.sum.map(|c| c as f32)) / (FIXED_SCALE as f32 * acc.count as f32)
        })
        .collect()
}

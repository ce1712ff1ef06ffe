//! Films of rendered scenes, whole or sliced, for the tests of
//! bit-identity across threads and slices.

use std::path::PathBuf;
use strata::partial::format::{read_partial_from, write_partial_to, Partial, PartialHeader};
use strata::render::film::Film;
use strata::render::{render, RenderOptions, SliceSpec};
use strata::scene::Scene;

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

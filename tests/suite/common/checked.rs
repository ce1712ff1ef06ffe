//! `strata::scene`'s ways of loading a scene, with every BVH of the scene
//! checked by `Bvh8::validate_leaves` before the test sees it: the tests
//! run as release builds, which do not check the trees they build.

use std::path::Path;
use std::time::Instant;
use strata::accel::BuildQuality;
use strata::error::InputResult;
use strata::geometry::csg::{ClosedMesh, Solid};
use strata::geometry::Geometry;
use strata::math::Aabb;
use strata::scene::description::SceneDescription;
use strata::scene::{LoadTimings, RenderOverrides, Scene};

/// Panics unless the scene's BVH, and the BVH of each of its CSG mesh
/// operands, is valid: every primitive in one leaf, each triangle inside
/// its leaf's box, boxes nested, leaf blocks padded (see `Bvh8::validate`).
pub fn check_bvhs(scene: &Scene) {
    check_geometry(&scene.geometry);
}

/// [`check_bvhs`] for one tree and, recursively, its prototypes'; an
/// instance's box must hold every triangle of its prototype moved to
/// world space.
fn check_geometry(g: &Geometry) {
    for p in g.prototypes() {
        check_geometry(p);
    }
    // The scene keeps the tree's leaf slots in its leaf blocks, with the
    // triangles' vertices: their boxes are the boxes the tree was built on.
    let slots: Vec<u32> = g.leaf_slots().collect();
    let mut boxes = vec![None; g.primitive_count()];
    for (slot, &id) in (0..).zip(&slots) {
        if id < g.triangle_count() {
            boxes[id as usize] = Some(Aabb::from_points(&g.slot_triangle(slot)));
        }
    }
    for (k, inst) in g.instances().iter().enumerate() {
        let m = inst.affine();
        let placed = g.prototypes()[inst.prototype as usize]
            .file_order_triangles()
            .iter()
            .flatten()
            .fold(Aabb::EMPTY, |b, &p| b.grow(m.transform_point3(p)));
        boxes[g.first_instance() as usize + k] = Some(placed);
    }
    g.bvh()
        .validate_leaves(&slots, g.primitive_count(), |id| boxes[id as usize])
        .unwrap_or_else(|e| panic!("the scene's BVH is invalid: {e}"));
    for leaf in &g.csg().leaves {
        if let Solid::Mesh(ClosedMesh {
            first,
            count,
            bvh: Some(i),
        }) = leaf.solid
        {
            let tris = &g.csg().triangles[first as usize..(first + count) as usize];
            let boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
            g.csg().mesh_bvhs[i as usize]
                .validate_boxes(&boxes)
                .unwrap_or_else(|e| panic!("the BVH of CSG mesh {i} is invalid: {e}"));
        }
    }
}

fn checked<T>(loaded: InputResult<(Scene, T)>) -> InputResult<(Scene, T)> {
    if let Ok((scene, _)) = &loaded {
        check_bvhs(scene);
    }
    loaded
}

/// `strata::scene::load_scene`, checked.
pub fn load_scene(
    path: &Path,
    overrides: &RenderOverrides,
    quality: BuildQuality,
) -> InputResult<(Scene, LoadTimings)> {
    checked(strata::scene::load_scene(path, overrides, quality))
}

/// `strata::scene::load_mesh_scene`, checked.
pub fn load_mesh_scene(path: &Path, quality: BuildQuality) -> InputResult<(Scene, LoadTimings)> {
    checked(strata::scene::load_mesh_scene(path, quality))
}

/// `strata::scene::scene_from_str`, checked.
pub fn scene_from_str(text: &str, path: &Path, overrides: &RenderOverrides) -> InputResult<Scene> {
    let scene = strata::scene::scene_from_str(text, path, overrides)?;
    check_bvhs(&scene);
    Ok(scene)
}

/// `strata::scene::compile`, checked.
pub mod compile {
    use super::*;

    /// `strata::scene::compile::compile`, checked.
    pub fn compile(
        desc: &SceneDescription,
        path: &Path,
        overrides: &RenderOverrides,
        quality: BuildQuality,
        start: Instant,
    ) -> InputResult<(Scene, LoadTimings)> {
        checked(strata::scene::compile::compile(
            desc, path, overrides, quality, start,
        ))
    }
}

//! A 64-bit fingerprint of everything a render reads, and the checksum of
//! partial files.
//!
//! A partial file (`partial::format`) must not be merged with a part of a
//! different scene. We fingerprint the *compiled* scene rather than the
//! scene file's bytes: comments, key order, file names and paths do not
//! change the image and so do not change the fingerprint, while any change
//! to geometry (mesh files included), materials, lights, camera or
//! background does. The settings that the partial header stores on their
//! own (size, spp, seed, sampler, per-effect counts, depth) are left out
//! here so that a mismatch there gets a message naming the setting.
//!
//! Small, rarely large parts (materials, lights, camera, analytic shapes)
//! are hashed through their `Debug` text: Rust prints every `f32` so that it
//! parses back to the same bits, and a field added to one of those types is
//! covered without touching this file. Large arrays (triangles, normals,
//! texture coordinates, texels) are hashed as raw bits. If the `Debug` text
//! of a type ever changes, parts from old and new builds refuse to merge:
//! the failure is safe.
//!
//! [`scene_fingerprint`] destructures [`Scene`], [`Geometry`], [`MeshRange`],
//! [`Textures`] and [`RenderSettings`] without `..`, so a new field there is a compile error here until someone
//! decides whether it changes the image.
//!
//! The hash is not cryptographic: it catches mistakes (a wrong file, a
//! different scene, a flipped bit), not malice.

use crate::geometry::csg::Csg;
use crate::geometry::{Geometry, MeshAttribute, MeshRange};
use crate::scene::settings::IntegratorKind;
use crate::scene::{RenderSettings, Scene};
use crate::texture::Textures;
use std::fmt;

const K1: u64 = 0x9e37_79b9_7f4a_7c15;
const K2: u64 = 0xc2b2_ae3d_27d4_eb4f;

/// A streaming 64-bit hash over bytes: one multiply-rotate step per 8-byte
/// word (each step is a bijection of the state, so two inputs of equal
/// length that differ in one word always hash differently), then the
/// SplitMix64 finaliser.
#[derive(Debug, Clone)]
pub struct Hasher64 {
    state: u64,
    pending: u64,
    pending_bytes: u32,
    len: u64,
}

impl Default for Hasher64 {
    fn default() -> Self {
        Self::new()
    }
}

impl Hasher64 {
    pub fn new() -> Self {
        Self {
            state: K2,
            pending: 0,
            pending_bytes: 0,
            len: 0,
        }
    }

    #[inline]
    fn mix(&mut self, word: u64) {
        self.state = (self.state ^ word).wrapping_mul(K1).rotate_left(29);
    }

    pub fn write(&mut self, mut bytes: &[u8]) {
        self.len += bytes.len() as u64;
        // Fill a partial word first.
        while self.pending_bytes > 0 && !bytes.is_empty() {
            self.pending |= (bytes[0] as u64) << (8 * self.pending_bytes);
            self.pending_bytes += 1;
            bytes = &bytes[1..];
            if self.pending_bytes == 8 {
                let w = self.pending;
                self.mix(w);
                self.pending = 0;
                self.pending_bytes = 0;
            }
        }
        if bytes.is_empty() {
            return;
        }
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.mix(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        for (i, &b) in words.remainder().iter().enumerate() {
            self.pending |= (b as u64) << (8 * i);
        }
        self.pending_bytes = words.remainder().len() as u32;
    }

    pub fn write_u32(&mut self, v: u32) {
        self.write(&v.to_le_bytes());
    }

    pub fn write_u64(&mut self, v: u64) {
        self.write(&v.to_le_bytes());
    }

    pub fn write_f32(&mut self, v: f32) {
        self.write_u32(v.to_bits());
    }

    /// Hash a value's `Debug` text, after a tag that separates sections.
    pub fn write_debug(&mut self, tag: &str, value: &impl fmt::Debug) {
        self.write(tag.as_bytes());
        fmt::write(self, format_args!("{value:?}")).expect("hashing cannot fail");
        self.write(&[0]);
    }

    pub fn finish(&self) -> u64 {
        let mut h = self.clone();
        if h.pending_bytes > 0 {
            let w = h.pending ^ ((h.pending_bytes as u64) << 59);
            h.mix(w);
        }
        let len = h.len;
        h.mix(len);
        // SplitMix64 finaliser (Steele, Lea and Flood 2014).
        let mut z = h.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

impl fmt::Write for Hasher64 {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.write(s.as_bytes());
        Ok(())
    }
}

/// The fingerprint of a compiled scene: what the image depends on besides
/// the settings stored in a partial header. See the module docs.
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let Scene {
        geometry,
        materials,
        textures,
        lights,
        emitters: _, // made from the geometry and materials hashed here
        camera,
        settings,
        warnings: _, // what a loader said: the image does not depend on it
    } = scene;
    // Every field but the leaf store (private to `geometry`), whose
    // triangles are hashed in file order below, so the fingerprint does
    // not depend on the BVH's leaf order (which varies with --bvh-quality).
    let Geometry {
        triangle_count,
        meshes,
        shapes,
        transforms,
        csg,
        planes,
        instances,
        prototypes,
        bvh: _, // an acceleration structure: it changes speed, not hits
        ..
    } = geometry;
    let RenderSettings {
        // In the partial header, compared field by field.
        width: _,
        height: _,
        spp: _,
        shadow_samples: _,
        reflection_samples: _,
        max_depth: _,
        sampler: _,
        seed: _,
        background,
        light_sampling,
        glossy_sampling,
        noise,
        exposure,
        tonemap: _, // how an 8-bit output shows the film, not the film
        integrator,
    } = settings;
    let mut h = Hasher64::new();
    h.write(b"strata scene v1\0");
    let triangles = geometry.file_order_triangles();
    debug_assert_eq!(triangles.len(), *triangle_count as usize);
    h.write_u64(triangles.len() as u64);
    for tri in &triangles {
        for v in tri {
            for c in v.to_array() {
                h.write_f32(c);
            }
        }
    }
    h.write_u64(meshes.len() as u64);
    for mesh in meshes {
        let MeshRange {
            name: _, // a label for reports
            first,
            count,
            material,
            mirrored,
            normals,
            uvs,
            tangents,
        } = mesh;
        h.write_u32(*first);
        h.write_u32(*count);
        h.write_u32(*material);
        h.write_u32(u32::from(*mirrored));
        write_attribute(&mut h, normals.as_ref(), |v| v.to_array());
        write_attribute(&mut h, uvs.as_ref(), |v| v.to_array());
        write_attribute(&mut h, tangents.as_ref(), |v| v.to_array());
    }
    let Textures {
        images,
        textures: texture_list,
    } = textures;
    h.write_u64(images.len() as u64);
    for image in images {
        h.write_u32(image.width());
        h.write_u32(image.height());
        h.write(image.texels().as_flattened());
    }
    h.write_debug("textures", texture_list);
    let Csg {
        nodes: csg_nodes,
        leaves: csg_leaves,
        triangles: csg_triangles,
        triangle_materials: csg_materials,
        mesh_bvhs: _, // acceleration only
    } = csg;
    h.write_debug("csg nodes", csg_nodes);
    h.write_debug("csg leaves", csg_leaves);
    h.write_u64(csg_triangles.len() as u64);
    for tri in csg_triangles {
        for v in tri {
            for c in v.to_array() {
                h.write_f32(c);
            }
        }
    }
    h.write_u64(csg_materials.len() as u64);
    for m in csg_materials {
        h.write_u32(*m);
    }
    h.write_debug("shapes", shapes);
    h.write_debug("transforms", transforms);
    h.write_debug("planes", planes);
    h.write_debug("materials", materials);
    h.write_debug("lights", lights);
    h.write_debug("camera", camera);
    h.write_debug("background", background);
    // Sampling strategies change the noise, so parts must agree on them.
    h.write_debug("light_sampling", light_sampling);
    h.write_debug("glossy_sampling", glossy_sampling);
    // A noise target decides which samples each pixel takes, judged at
    // the exposure; hashed only when set, so that a render without one
    // keeps its fingerprint.
    if let Some(noise) = noise {
        h.write_f32(*noise);
        h.write_f32(*exposure);
    }
    // The light transport; hashed only for the path tracer, so that a
    // render of the seed's integrator keeps its fingerprint.
    if *integrator != IntegratorKind::Distribution {
        h.write_debug("integrator", integrator);
    }
    // Instanced meshes, each once, and their placements.
    h.write_u64(prototypes.len() as u64);
    for p in prototypes {
        h.write_u64(prototype_fingerprint(p));
    }
    h.write_debug("instances", instances);
    h.finish()
}

/// A prototype's triangles in file order and its meshes' materials and
/// attributes, as the scene's own are hashed above.
fn prototype_fingerprint(p: &Geometry) -> u64 {
    let mut h = Hasher64::new();
    for tri in p.file_order_triangles() {
        for v in tri {
            for c in v.to_array() {
                h.write_f32(c);
            }
        }
    }
    for mesh in &p.meshes {
        h.write_u32(mesh.first);
        h.write_u32(mesh.count);
        h.write_u32(mesh.material);
        write_attribute(&mut h, mesh.normals.as_ref(), |v| v.to_array());
        write_attribute(&mut h, mesh.uvs.as_ref(), |v| v.to_array());
    }
    h.finish()
}

/// A mesh's optional per-corner attribute, as raw bits: absent, or its
/// values (each as the floats `floats` gives) and index triples.
fn write_attribute<T, const N: usize>(
    h: &mut Hasher64,
    attribute: Option<&MeshAttribute<T>>,
    floats: impl Fn(&T) -> [f32; N],
) {
    let Some(a) = attribute else {
        h.write_u32(0);
        return;
    };
    h.write_u32(1);
    h.write_u64(a.values.len() as u64);
    for v in &a.values {
        for c in floats(v) {
            h.write_f32(c);
        }
    }
    h.write_u64(a.indices.len() as u64);
    for t in &a.indices {
        for i in t {
            h.write_u32(*i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunking_does_not_change_the_hash() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 31 % 251) as u8).collect();
        let mut whole = Hasher64::new();
        whole.write(&data);
        for split in [1usize, 3, 7, 8, 9, 500, 999] {
            let mut parts = Hasher64::new();
            for chunk in data.chunks(split) {
                parts.write(chunk);
            }
            assert_eq!(whole.finish(), parts.finish(), "chunks of {split}");
        }
    }

    #[test]
    fn any_single_byte_change_or_truncation_changes_the_hash() {
        let data: Vec<u8> = (0..64u8).collect();
        let base = {
            let mut h = Hasher64::new();
            h.write(&data);
            h.finish()
        };
        for i in 0..data.len() {
            let mut d = data.clone();
            d[i] ^= 0x10;
            let mut h = Hasher64::new();
            h.write(&d);
            assert_ne!(h.finish(), base, "byte {i}");
            let mut t = Hasher64::new();
            t.write(&data[..i]);
            assert_ne!(t.finish(), base, "truncated to {i}");
        }
        // Trailing zeros are not the same as no bytes.
        let mut a = Hasher64::new();
        a.write(&[1, 0]);
        let mut b = Hasher64::new();
        b.write(&[1]);
        assert_ne!(a.finish(), b.finish());
    }

    #[test]
    fn texture_coordinates_texels_and_wrap_modes_change_the_fingerprint() {
        use crate::geometry::MeshUvs;
        use crate::scene::{scene_from_str, RenderOverrides};
        use crate::texture::{Image, Texture, Wrap};
        use glam::Vec2;
        let mut scene = scene_from_str(
            "[[objects]]\ntriangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }",
            std::path::Path::new("t.toml"),
            &RenderOverrides::default(),
        )
        .unwrap();
        let untextured = scene_fingerprint(&scene);
        // Texture the triangle as a mesh file's material would.
        let image = Image::new(2, 1, vec![[255, 0, 0], [0, 0, 255]]).unwrap();
        scene.textures.add_image(image);
        scene.textures.add_texture(Texture {
            image: 0,
            wrap: [Wrap::Repeat; 2],
            encoding: crate::texture::Encoding::Srgb,
        });
        let material = scene.geometry.meshes[0].material as usize;
        scene.materials[material].diffuse_texture = Some(0);
        scene.geometry.meshes[0].uvs = Some(MeshUvs {
            values: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            indices: vec![[0, 1, 2]],
        });
        let textured = scene_fingerprint(&scene);
        assert_ne!(textured, untextured);

        let mut moved = scene.clone();
        moved.geometry.meshes[0].uvs.as_mut().unwrap().values[2].y = 0.5;
        let mut reindexed = scene.clone();
        reindexed.geometry.meshes[0].uvs.as_mut().unwrap().indices[0] = [0, 2, 1];
        let mut repainted = scene.clone();
        repainted.textures.images[0] = Image::new(2, 1, vec![[255, 0, 0], [0, 1, 255]]).unwrap();
        let mut resized = scene.clone();
        resized.textures.images[0] = Image::new(1, 2, vec![[255, 0, 0], [0, 0, 255]]).unwrap();
        let mut clamped = scene.clone();
        clamped.textures.textures[0].wrap[1] = Wrap::ClampToEdge;
        let mut no_uvs = scene.clone();
        no_uvs.geometry.meshes[0].uvs = None;
        for (what, changed) in [
            ("a texture coordinate", moved),
            ("a UV index", reindexed),
            ("one texel", repainted),
            ("the image's shape", resized),
            ("a wrap mode", clamped),
            ("dropping the UVs", no_uvs),
        ] {
            assert_ne!(scene_fingerprint(&changed), textured, "{what}");
        }
        assert_eq!(scene_fingerprint(&scene.clone()), textured);
    }
}

//! glTF 2.0 loader for `.gltf` (JSON, with buffers in files beside it or in
//! base64 `data:` URIs) and `.glb` (binary; buffer 0 is the `BIN` chunk).
//!
//! The loader walks the default scene (or scene 0, or, in a file without
//! scenes, every node that is no other node's child) depth first, children in
//! file order, composing each node's local transform (`matrix`, or
//! `translation` · `rotation` · `scale`) with its parent's. Each primitive of
//! a mesh that one node uses becomes one [`LoadedMesh`] with the world
//! transform baked in: positions by the matrix, normals by its inverse
//! transpose and then renormalised. A mesh that two or more nodes use is
//! read once, in its own space, and kept with one placement per node as a
//! [`SharedMesh`], which the scene compiler makes instances of (a use under
//! a singular transform, which no instance can place, is baked). Triangle
//! order, as [`LoadedAsset::baked_meshes`] gives it, is node order, then
//! primitive order, then the file's index order; index order is kept as
//! stored even where a mirroring transform (negative determinant) reverses
//! the apparent winding, and the mesh is marked `mirrored` instead.
//!
//! | Primitive mode                   | Result                                          |
//! |----------------------------------|-------------------------------------------------|
//! | `TRIANGLES` (4, the default)     | one triangle per three indices                  |
//! | `TRIANGLE_STRIP` (5)             | converted: triangle i = (i, i+1, i+2), odd i as (i, i+2, i+1) |
//! | `TRIANGLE_FAN` (6)               | converted: triangle i = (i+1, i+2, 0)           |
//! | `POINTS`, `LINES`, `LINE_LOOP`, `LINE_STRIP` | skipped                            |
//!
//! A primitive without `indices` uses its vertices in order (0, 1, 2, …).
//! Only `POSITION` (and `NORMAL`, when present) are read, both `VEC3`,
//! and, for a primitive whose material has a base colour texture, the
//! `TEXCOORD_n` set that texture names (`VEC2`); other primitives keep no
//! texture coordinates. Each is `FLOAT` or the integers glTF and
//! `KHR_mesh_quantization` allow it (`accessor::Attribute`). A sparse
//! accessor's values replace the elements it names, over its view or over
//! zeros.
//!
//! # Materials
//!
//! Every glTF material becomes one entry of [`LoadedAsset::materials`], in
//! file order (so a primitive's `material` index carries over unchanged), named
//! by its `name` or `material<i>`. A primitive without a material gets `None`,
//! i.e. the scene's default material. Alpha, and every texture but the base
//! colour's, are ignored. With base colour `c`, metallic `m` and roughness
//! `r`:
//!
//! | glTF (metallic-roughness)                          | [`Material`] field                                   |
//! |----------------------------------------------------|------------------------------------------------------|
//! | `baseColorFactor` rgb `c`, `metallicFactor` `m`    | `diffuse = c · (1 − m)`                              |
//! | `metallicFactor` `m`                               | `reflectivity = m`                                   |
//! | `roughnessFactor` `r`                              | `glossiness = n(r)` (Phong exponent of the fuzzy mirror); `r = 0` gives 0, a perfect mirror |
//! | `metallicFactor` `m`                               | `specular = 0.04 · (1 − m)` (grey), the dielectric highlight |
//! | `roughnessFactor` `r`                              | `shininess = n(r)` (`r = 0` gives the maximum, 10⁶)  |
//! | `emissiveFactor` `e` × `KHR_materials_emissive_strength` `s` | `emission = e · s`                         |
//! | `baseColorTexture`                                 | `diffuse_texture`: the image multiplies `diffuse` |
//! | `metallicRoughnessTexture`, `emissiveTexture`, `normalTexture` (`scale`) | `maps` (read as data but the emissive one; see `shade::maps`) |
//! | `occlusionTexture`                                 | ignored, with a warning                           |
//! | everything else                                    | [`Material::default`] (`transparency = 0`, `ior = 1.5`, no Fresnel) |
//!
//! where `n(r) = 2/α² − 2` with `α = r²` (the usual Phong-exponent equivalent
//! of a microfacet lobe of width α, Walter et al. 2007), clamped to [1, 10⁶].
//!
//! # Base colour textures
//!
//! ```text
//! "materials": [{ "pbrMetallicRoughness": {
//!     "baseColorFactor": [1, 1, 1, 1],
//!     "baseColorTexture": { "index": 0, "texCoord": 0 } } }],
//! "textures": [{ "source": 0, "sampler": 0 }],
//! "samplers": [{ "wrapS": 10497, "wrapT": 33071 }],
//! "images":   [{ "uri": "crate.png" }]
//! ```
//!
//! The texture's image is a PNG or JPEG file beside the glTF, a base64
//! `data:` URI, or a `bufferView` (GLB); the format is told by its bytes,
//! not `mimeType`. Its sampler's `wrapS`/`wrapT` become the wrap modes
//! (repeat without a sampler); its filters are ignored, lookups are always
//! bilinear (see [`crate::texture`]). Each image is decoded once however
//! many textures use it, and only images a material's map uses are read.
//! A mesh has one set of UVs, the first map's (base colour,
//! metallic-roughness, emissive, normal): its `KHR_texture_transform`
//! moves them as they are read (scale, rotation, offset; its `texCoord`
//! picks the set); another map's own set or transform is warned of. A missing or undecodable image is an error at `images[j]` that
//! names the file and the texture using it: `cannot read texture
//! dir/crate.png: No such file or directory (used by textures[0])`.
//!
//! # Cameras and lights
//!
//! Every node with a camera gives a [`LoadedCamera`] at the node's world
//! origin, looking along its world −Z with world +Y (made orthogonal to the
//! view direction) as up; a perspective camera's `yfov` is converted to
//! degrees, an orthographic camera's `ymag` doubled into `ortho_height`,
//! and the aspect ratio (`aspectRatio`, or `xmag / ymag`) kept for a
//! caller that sizes the image by it. `znear` and `zfar` are ignored: a ray
//! tracer needs no depth buffer to divide the depth range of, and clipping
//! the scene would only hide what is there.
//!
//! Every node with a `KHR_lights_punctual` light gives a [`LoadedLight`] at
//! the node's world origin; spot and directional lights shine along its
//! world −Z. glTF gives point and spot intensities in candela (lm/sr) and
//! directional ones in lux (lm/m²); we convert them to W/sr and W/m² with
//! the photometric constant, `color · intensity / 683`, as Blender's
//! exporter assumes. A spot light keeps its cone angles (glTF's falloff
//! between them is [`crate::light::spot_falloff`]). A light's `range` is
//! ignored (the falloff stays physical, 1/d²).
//!
//! # Validation
//!
//! Every problem is an [`InputError`] naming the file and the glTF location
//! (`meshes[2].primitives[0]`, `accessors[5]`, `buffers[0]`, `GLB header`):
//! malformed JSON or GLB container, anything the `gltf` crate's validator
//! rejects (bad references, unsupported required extensions), buffers whose
//! declared `byteLength` exceeds the data actually there (refused before
//! anything of that size is allocated), missing buffer files, views or
//! accessors reaching outside their buffer, indices outside the vertex count,
//! non-finite positions, normals and transforms, and primitives without
//! `POSITION`. Custom vertex attributes and missing `POSITION` `min`/`max`
//! are tolerated since the loader does not use them. Skins and morph
//! targets are not applied: meshes render in their rest pose and base
//! shape, with a warning for each kind. glTF 1.0 and every
//! `extensionsRequired` entry the loader does not read are refused by name
//! (`container.rs`), but for one of looks alone in a file read without
//! its materials ([`load_gltf_with`]). A scene that lists no nodes (or has no `nodes` key)
//! loads empty with a warning in [`LoadedAsset::warnings`], and so does a
//! file whose scene holds no triangles.
//!
//! # Layout
//!
//! | File           | Concern                                                         |
//! |----------------|-----------------------------------------------------------------|
//! | `mod.rs`       | [`load_gltf`] and the depth-first walk over the scene's nodes   |
//! | `container.rs` | GLB header and chunks, JSON parsing and validation              |
//! | `buffer.rs`    | buffers from the BIN chunk, base64 `data:` URIs or files beside |
//! | `accessor.rs`  | accessors and buffer views, bounds-checked against the buffers  |
//! | `primitive.rs` | one mesh primitive: attributes, indices, mode → triangles       |
//! | `node.rs`      | node transforms, world-space normals, cameras and lights        |
//! | `shared.rs`    | which meshes several nodes share: kept once, with placements    |
//! | `material.rs`  | metallic-roughness → [`Material`]                               |
//! | `texture.rs`   | base colour textures: samplers and images (file, URI or view)   |
//!
//! [`LoadedMesh`]: crate::scene::asset::LoadedMesh
//! [`SharedMesh`]: crate::scene::asset::SharedMesh
//! [`LoadedAsset::baked_meshes`]: crate::scene::asset::LoadedAsset::baked_meshes
//! [`LoadedCamera`]: crate::scene::asset::LoadedCamera
//! [`LoadedLight`]: crate::scene::asset::LoadedLight
//! [`Material`]: crate::material::Material
//! [`Material::default`]: crate::material::Material::default

mod accessor;
mod buffer;
mod container;
mod material;
mod node;
mod primitive;
mod shared;
#[cfg(test)]
mod test_support;
mod texture;

use super::io_message;
use crate::error::{InputError, InputResult};
use crate::scene::asset::LoadedAsset;
use ::gltf::json;
use buffer::load_buffers;
use container::{parse_root, split_glb};
use glam::Mat4;
use shared::MeshUse;
use std::borrow::Cow;
use std::path::Path;

/// Luminous efficacy used to turn candela (lm/sr) into W/sr: 683 lm/W.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Load a `.gltf` or `.glb` file; see the module documentation for what
/// comes through and how.
pub fn load_gltf(path: &Path) -> InputResult<LoadedAsset> {
    load_gltf_with(path, true)
}

/// [`load_gltf`], without its materials and their textures unless
/// `materials` (no image is decoded then, every primitive gets the
/// default material, and an extension of looks alone may be required).
pub fn load_gltf_with(path: &Path, materials: bool) -> InputResult<LoadedAsset> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let is_glb_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let (json_bytes, bin) = if bytes.starts_with(b"glTF") {
        split_glb(path, &bytes)?
    } else if is_glb_name {
        return Err(InputError::new(
            path,
            "GLB header",
            "not a binary glTF file: it does not start with the magic bytes 'glTF'",
        ));
    } else {
        (&bytes[..], None)
    };
    let root = parse_root(path, json_bytes, materials)?;
    let buffers = load_buffers(path, &root, bin)?;
    Loader {
        path,
        root: &root,
        buffers,
        read_materials: materials,
    }
    .load()
}

/// The parsed document with every buffer resolved; the concern files of this
/// folder each add their part of its methods.
struct Loader<'a> {
    path: &'a Path,
    root: &'a json::Root,
    buffers: Vec<Cow<'a, [u8]>>,
    /// Whether the materials and their textures are read.
    read_materials: bool,
}

impl Loader<'_> {
    fn error(&self, location: impl Into<String>, message: impl Into<String>) -> InputError {
        InputError::new(self.path, location, message)
    }

    fn load(&self) -> InputResult<LoadedAsset> {
        let (materials, textures) = match self.read_materials {
            true => self.materials()?,
            false => Default::default(),
        };
        let mut asset = LoadedAsset {
            materials,
            textures,
            ..Default::default()
        };
        let (scene, root_nodes) = self.root_nodes()?;
        let empty_scene = scene.is_some() && root_nodes.is_empty();
        if let (Some(scene), true) = (scene, empty_scene) {
            asset.warnings.push(self.error(
                format!("scenes[{scene}]"),
                "the scene lists no nodes, so nothing of this file renders",
            ));
        }
        let mut visited = vec![false; self.root.nodes.len()];
        let mut uses = Vec::new();
        for root_node in root_nodes {
            // Depth first, children in file order, without recursion.
            let mut stack = vec![(root_node, Mat4::IDENTITY)];
            while let Some((index, parent)) = stack.pop() {
                let node = self.root.nodes.get(index).ok_or_else(|| {
                    self.error(format!("nodes[{index}]"), "node does not exist".to_string())
                })?;
                if std::mem::replace(&mut visited[index], true) {
                    return Err(self.error(
                        format!("nodes[{index}]"),
                        "node appears more than once in the scene hierarchy \
                         (a cycle, or a node with two parents)",
                    ));
                }
                let world = parent * self.local_transform(index, node)?;
                if !world.is_finite() {
                    return Err(self.error(
                        format!("nodes[{index}]"),
                        "the world transform is not finite",
                    ));
                }
                self.visit(index, node, &world, &mut asset, &mut uses)?;
                for child in node.children.iter().flatten().rev() {
                    stack.push((child.value(), world));
                }
            }
        }
        self.place_meshes(&uses, &mut asset)?;
        self.warn_of_rest_poses(&uses, &mut asset);
        if self.read_materials {
            self.warn_of_unread_textures(&mut asset);
        }
        if !empty_scene {
            super::warn_without_triangles(
                &mut asset,
                self.path,
                "no triangles (no node of the scene has a mesh of triangles)",
            );
        }
        Ok(asset)
    }

    /// Skins and morph targets are not applied: a warning for each kind,
    /// naming the first node or mesh that has one and counting the others,
    /// so that a posed character does not render in its rest pose unsaid.
    fn warn_of_rest_poses(&self, uses: &[MeshUse], asset: &mut LoadedAsset) {
        let others = |n: usize, what: &str| match n {
            0 => String::new(),
            1 => format!(" (and 1 more {what})"),
            n => format!(" (and {n} more {what}s)"),
        };
        let skinned: Vec<usize> = uses
            .iter()
            .map(|u| u.node)
            .filter(|&n| self.root.nodes[n].skin.is_some())
            .collect();
        if let Some(&first) = skinned.first() {
            asset.warnings.push(self.error(
                format!("nodes[{first}].skin"),
                format!(
                    "skins are not applied: this mesh{} renders in its rest pose, as \
                     modelled, without its skeleton's pose or animation",
                    others(skinned.len() - 1, "skinned node")
                ),
            ));
        }
        let mut morphed: Vec<usize> = uses
            .iter()
            .map(|u| u.mesh)
            .filter(|&m| {
                self.root.meshes[m]
                    .primitives
                    .iter()
                    .any(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty()))
            })
            .collect();
        morphed.sort_unstable();
        morphed.dedup();
        if let Some(&first) = morphed.first() {
            asset.warnings.push(self.error(
                format!("meshes[{first}]"),
                format!(
                    "morph targets are not applied: this mesh{} renders in its base \
                     shape, without its weights' blend of the targets",
                    others(morphed.len() - 1, "mesh")
                ),
            ));
        }
    }

    /// The scene walked (its index, if the file has scenes) and its root
    /// nodes: the default scene, else scene 0, else every node that is
    /// nobody's child.
    fn root_nodes(&self) -> InputResult<(Option<usize>, Vec<usize>)> {
        let index = self.root.scene.map_or(0, |i| i.value());
        let scene = match self.root.scene {
            Some(_) => Some(
                self.root
                    .scenes
                    .get(index)
                    .ok_or_else(|| self.error("scene", format!("scene {index} does not exist")))?,
            ),
            None => self.root.scenes.first(),
        };
        if let Some(scene) = scene {
            return Ok((Some(index), scene.nodes.iter().map(|n| n.value()).collect()));
        }
        let mut is_child = vec![false; self.root.nodes.len()];
        for node in &self.root.nodes {
            for child in node.children.iter().flatten() {
                if let Some(flag) = is_child.get_mut(child.value()) {
                    *flag = true;
                }
            }
        }
        Ok((
            None,
            (0..self.root.nodes.len())
                .filter(|&i| !is_child[i])
                .collect(),
        ))
    }

    /// Collect what one node carries: the use of a mesh (read after the
    /// walk, when every use is known), a camera, a point light.
    fn visit(
        &self,
        index: usize,
        node: &json::Node,
        world: &Mat4,
        asset: &mut LoadedAsset,
        uses: &mut Vec<MeshUse>,
    ) -> InputResult<()> {
        if let Some(mesh_index) = node.mesh.map(|m| m.value()) {
            if mesh_index >= self.root.meshes.len() {
                return Err(self.error(
                    format!("nodes[{index}].mesh"),
                    format!("meshes[{mesh_index}] does not exist"),
                ));
            }
            uses.push(MeshUse {
                node: index,
                mesh: mesh_index,
                world: *world,
            });
        }
        if let Some(camera) = node.camera.map(|c| c.value()) {
            let camera = self.camera(index, camera, world)?;
            asset.cameras.push(camera);
        }
        let light = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value());
        if let Some(light) = light {
            asset.lights.push(self.light(index, light, world)?);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::*;

    #[test]
    fn traversal_is_depth_first_in_child_order() {
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"scenes":[{{"nodes":[0,3]}}],"nodes":[
                {{"children":[1,2]}},
                {{"mesh":0,"translation":[1,0,0],"children":[4]}},
                {{"mesh":0,"translation":[2,0,0]}},
                {{"mesh":0,"translation":[3,0,0]}},
                {{"mesh":0,"translation":[0,0,7]}}
            ]"#
        );
        let asset = load_baked(&b, &rest);
        let xs: Vec<Vec3> = asset.meshes.iter().map(|m| m.positions[0]).collect();
        assert_eq!(
            xs,
            [
                Vec3::new(1., 0., 0.),
                Vec3::new(1., 0., 7.),
                Vec3::new(2., 0., 0.),
                Vec3::new(3., 0., 0.)
            ]
        );
    }

    #[test]
    fn without_scenes_all_root_nodes_are_walked() {
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"children":[1]}},{{"mesh":0,"translation":[0,1,0]}},{{"mesh":0}}]"#
        );
        let asset = load_baked(&b, &rest);
        assert_eq!(asset.meshes.len(), 2);
        assert_eq!(asset.meshes[0].positions[0], Vec3::Y);
        assert_eq!(asset.meshes[1].positions[0], Vec3::ZERO);
    }

    /// Skins and morph targets render in the rest pose, each kind said
    /// once with the number of the others; the mesh itself loads.
    #[test]
    fn skins_and_morph_targets_are_warned_of() {
        let b = triangle_builder();
        let rest = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,
                "targets":[{"POSITION":0}]}],"weights":[0.5]},
                {"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
            "skins":[{"joints":[3]}],
            "nodes":[{"mesh":0,"skin":0},{"mesh":1,"skin":0},{"mesh":1,"skin":0},{}]"#;
        let asset = load_json(&b, rest).unwrap();
        assert_eq!(asset.triangle_count(), 3);
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(
            said[0].ends_with("nodes[0].skin: skins are not applied: this mesh (and 2 more skinned nodes) renders in its rest pose, as modelled, without its skeleton's pose or animation"),
            "{said:?}"
        );
        assert!(
            said[1].ends_with("meshes[0]: morph targets are not applied: this mesh renders in its base shape, without its weights' blend of the targets"),
            "{said:?}"
        );
        let plain = load_json(&b, &format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#)).unwrap();
        assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
    }

    #[test]
    fn node_cycles_are_errors() {
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"scenes":[{{"nodes":[0]}}],"nodes":[{{"children":[1]}},{{"children":[0]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[0]",
            "more than once",
        );
    }

    #[test]
    fn random_bytes_never_panic() {
        let dir = temp_dir("fuzz");
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"camera":0}}],"cameras":[{{"type":"perspective","perspective":{{"yfov":1,"znear":0.1}}}}]"#
        );
        let good = b.glb(&rest);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (glb, gltf) = (dir.join("f.glb"), dir.join("f.gltf"));
        for round in 0..400 {
            let bytes: Vec<u8> = match round % 3 {
                0 => (0..next() % 300).map(|_| next() as u8).collect(),
                1 => {
                    let mut bytes = b"glTF".to_vec();
                    bytes.extend((0..next() % 300).map(|_| next() as u8));
                    bytes
                }
                _ => {
                    // Flip a few bytes of a valid GLB (header, JSON or BIN).
                    let mut bytes = good.clone();
                    for _ in 0..1 + next() % 4 {
                        let at = (next() % bytes.len() as u64) as usize;
                        bytes[at] = next() as u8;
                    }
                    bytes
                }
            };
            std::fs::write(&glb, &bytes).unwrap();
            let _ = load_gltf(&glb);
            std::fs::write(&gltf, &bytes).unwrap();
            let _ = load_gltf(&gltf);
        }
    }

    #[test]
    fn mutated_numbers_in_valid_json_never_panic() {
        let mut b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        b.vec3(&[[0., 0., 1.], [0., 0., 1.], [0., 0., 1.]], false);
        b.u8s(&[0, 1, 2, 2, 1, 0]);
        let rest = format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":2}},"indices":1,"material":0}},
                {{"attributes":{{"POSITION":0}},"indices":3,"mode":5}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"metallicFactor":0.5}}}}],
            "scene":0,"scenes":[{{"nodes":[0,2]}}],
            "cameras":[{{"type":"perspective","perspective":{{"yfov":1,"znear":0.1}}}}],
            "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point"}}]}}}},
            "nodes":[{{"mesh":0,"children":[1],"rotation":[0,{s},0,{s}]}},
                     {{"camera":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}},
                     {{"mesh":0,"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}]"#
        );
        let dir = temp_dir("mutate");
        let json = b.json(Some(&b.data_uri()), &rest);
        assert!(load_gltf(&write(&dir, "ok.gltf", json.as_bytes())).is_ok());
        let digits: Vec<usize> = json
            .char_indices()
            .filter(|(i, c)| {
                c.is_ascii_digit()
                    && !json[..*i].ends_with(|p: char| p.is_ascii_alphanumeric() || p == '.')
            })
            .map(|(i, _)| i)
            .collect();
        let replacements = [
            "0",
            "1",
            "2",
            "3",
            "4",
            "5",
            "7",
            "9",
            "12",
            "255",
            "65535",
            "4294967295",
            "18446744073709551615",
            "-1",
            "1e38",
            "1e39",
            "0.5",
            "5121",
            "5125",
            "5126",
        ];
        let mut state = 0x1234_5678_9abc_def1u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let path = dir.join("m.gltf");
        let glb_path = dir.join("m.glb");
        for _ in 0..400 {
            let mut text = json.clone();
            for _ in 0..1 + next() % 3 {
                let start = digits[(next() % digits.len() as u64) as usize];
                if start >= text.len() || !text.as_bytes()[start].is_ascii_digit() {
                    continue;
                }
                let end = text[start..]
                    .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                    .map_or(text.len(), |n| start + n);
                let with = replacements[(next() % replacements.len() as u64) as usize];
                text.replace_range(start..end, with);
            }
            std::fs::write(&path, &text).unwrap();
            let _ = load_gltf(&path);
            std::fs::write(&glb_path, glb_bytes(text.as_bytes(), Some(&b.bin))).unwrap();
            let _ = load_gltf(&glb_path);
        }
    }
}

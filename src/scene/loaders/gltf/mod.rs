//! glTF 2.0 loader for `.gltf` (JSON, with buffers in files beside it or in
//! base64 `data:` URIs) and `.glb` (binary; buffer 0 is the `BIN` chunk).
//!
//! The loader walks the default scene (or scene 0, or, in a file without
//! scenes, every node that is no other node's child) depth first, children in
//! file order, composing each node's local transform (`matrix`, or
//! `translation` · `rotation` · `scale`) with its parent's. Each primitive of
//! each mesh node becomes one [`LoadedMesh`] with the world transform baked
//! in: positions by the matrix, normals by its inverse transpose and then
//! renormalised. Triangle order is node order, then primitive order, then the
//! file's index order; index order is kept as stored even where a mirroring
//! transform (negative determinant) reverses the apparent winding.
//!
//! | Primitive mode                   | Result                                          |
//! |----------------------------------|-------------------------------------------------|
//! | `TRIANGLES` (4, the default)     | one triangle per three indices                  |
//! | `TRIANGLE_STRIP` (5)             | converted: triangle i = (i, i+1, i+2), odd i as (i, i+2, i+1) |
//! | `TRIANGLE_FAN` (6)               | converted: triangle i = (i+1, i+2, 0)           |
//! | `POINTS`, `LINES`, `LINE_LOOP`, `LINE_STRIP` | skipped                            |
//!
//! A primitive without `indices` uses its vertices in order (0, 1, 2, …).
//! Only `POSITION` (and `NORMAL`, when present) are read; both must be
//! `FLOAT` `VEC3`. Sparse accessors are not supported.
//!
//! # Materials
//!
//! Every glTF material becomes one entry of [`LoadedAsset::materials`], in
//! file order (so a primitive's `material` index carries over unchanged), named
//! by its `name` or `material<i>`. A primitive without a material gets `None`,
//! i.e. the scene's default material. Textures and alpha are ignored. With
//! base colour `c`, metallic `m` and roughness `r`:
//!
//! | glTF (metallic-roughness)                          | [`Material`] field                                   |
//! |----------------------------------------------------|------------------------------------------------------|
//! | `baseColorFactor` rgb `c`, `metallicFactor` `m`    | `diffuse = c · (1 − m)`                              |
//! | `metallicFactor` `m`                               | `reflectivity = m`                                   |
//! | `roughnessFactor` `r`                              | `glossiness = n(r)` (Phong exponent of the fuzzy mirror); `r = 0` gives 0, a perfect mirror |
//! | `metallicFactor` `m`                               | `specular = 0.04 · (1 − m)` (grey), the dielectric highlight |
//! | `roughnessFactor` `r`                              | `shininess = n(r)` (`r = 0` gives the maximum, 10⁶)  |
//! | `emissiveFactor` `e` × `KHR_materials_emissive_strength` `s` | `emission = e · s`                         |
//! | everything else                                    | [`Material::default`] (`transparency = 0`, `ior = 1.5`, no Fresnel) |
//!
//! where `n(r) = 2/α² − 2` with `α = r²` (the usual Phong-exponent equivalent
//! of a microfacet lobe of width α, Walter et al. 2007), clamped to [1, 10⁶].
//!
//! # Cameras and lights
//!
//! Every node with a camera gives a [`LoadedCamera`] at the node's world
//! origin, looking along its world −Z with world +Y (made orthogonal to the
//! view direction) as up; a perspective camera's `yfov` is converted to
//! degrees, an orthographic camera's `ymag` doubled into `ortho_height`.
//!
//! Every node with a `KHR_lights_punctual` point light gives a
//! [`LoadedPointLight`] at the node's world origin. glTF gives a point light's
//! intensity in candela (lm/sr); we convert it to radiant intensity in W/sr
//! with the photometric constant, `intensity = color · intensity / 683`, so
//! the radiometric renderer sees W/sr. A light's `range` is ignored (the
//! falloff stays physical, 1/d²). Spot and directional lights are skipped
//! without error.
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
//! are tolerated since the loader does not use them.

use super::io_message;
use crate::error::{InputError, InputResult};
use crate::geometry::MeshNormals;
use crate::material::Material;
use crate::scene::asset::{LoadedAsset, LoadedCamera, LoadedMesh, LoadedPointLight};
use ::gltf::json;
use glam::{Mat3, Mat4, Quat, Vec3};
use json::accessor::{ComponentType, Type as AccessorType};
use json::mesh::{Mode, Semantic};
use json::validation::{Checked, Validate};
use std::borrow::Cow;
use std::io::Read;
use std::path::Path;

/// Luminous efficacy used to turn candela (lm/sr) into W/sr: 683 lm/W.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Largest Phong exponent the roughness mapping produces.
const MAX_PHONG_EXPONENT: f32 = 1.0e6;

/// Load a `.gltf` or `.glb` file; see the module documentation for what
/// comes through and how.
pub fn load_gltf(path: &Path) -> InputResult<LoadedAsset> {
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
    let root = parse_root(path, json_bytes)?;
    let buffers = load_buffers(path, &root, bin)?;
    Loader {
        path,
        root: &root,
        buffers,
    }
    .load()
}

fn u32_le(bytes: &[u8]) -> u32 {
    u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

/// Split a GLB container into its JSON chunk and optional BIN chunk, checking
/// every declared length against the bytes actually present.
fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> InputResult<(&'a [u8], Option<&'a [u8]>)> {
    let header = |message: String| InputError::new(path, "GLB header", message);
    if bytes.len() < 12 {
        return Err(header(format!(
            "the file is only {} bytes, too short for the 12-byte GLB header",
            bytes.len()
        )));
    }
    let version = u32_le(&bytes[4..]);
    if version != 2 {
        return Err(header(format!(
            "GLB version {version} is not supported (only version 2)"
        )));
    }
    let length = u32_le(&bytes[8..]) as usize;
    if length > bytes.len() {
        return Err(header(format!(
            "declares {length} bytes but the file has only {} (truncated?)",
            bytes.len()
        )));
    }
    if length < 12 {
        return Err(header(format!(
            "declares a total length of {length} bytes, less than the header itself"
        )));
    }
    let mut rest = &bytes[12..length];
    let (mut json, mut bin) = (None, None);
    let mut chunk = 0usize;
    while !rest.is_empty() {
        let at = |message: String| InputError::new(path, format!("GLB chunk {chunk}"), message);
        if rest.len() < 8 {
            return Err(at(format!(
                "only {} bytes left, too few for a chunk header (truncated?)",
                rest.len()
            )));
        }
        let chunk_length = u32_le(rest) as usize;
        let kind = &rest[4..8];
        let available = rest.len() - 8;
        if chunk_length > available {
            return Err(at(format!(
                "declares {chunk_length} bytes but only {available} remain (truncated?)"
            )));
        }
        let data = &rest[8..8 + chunk_length];
        match (chunk, kind) {
            (0, b"JSON") => json = Some(data),
            (0, _) => return Err(at("the first chunk must be the JSON chunk".to_string())),
            (1, b"BIN\0") => bin = Some(data),
            _ => {} // unknown chunks are to be ignored
        }
        rest = &rest[8 + chunk_length..];
        chunk += 1;
    }
    let json = json.ok_or_else(|| header("the file has no JSON chunk".to_string()))?;
    Ok((json, bin))
}

/// Parse and validate the JSON document.
///
/// The `gltf` crate's validator indexes the POSITION accessor without a
/// bounds check, so that reference is checked first.
fn parse_root(path: &Path, json_bytes: &[u8]) -> InputResult<json::Root> {
    let root: json::Root = json::deserialize::from_slice(json_bytes)
        .map_err(|e| InputError::file(path, format!("invalid glTF JSON: {e}")))?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
            {
                if index.value() >= root.accessors.len() {
                    return Err(InputError::new(
                        path,
                        format!("meshes[{m}].primitives[{p}]"),
                        format!(
                            "POSITION refers to accessors[{}] but the file has {} accessors",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let mut problems: Vec<(String, json::validation::Error)> = Vec::new();
    root.validate(&root, json::Path::new, &mut |where_, error| {
        problems.push((where_().to_string(), error))
    });
    // We read neither POSITION's min/max nor custom attributes, so files
    // that get those wrong still load.
    problems.retain(|(where_, error)| {
        let unused_bounds = where_.contains(".attributes[")
            && (where_.ends_with(".min") || where_.ends_with(".max"));
        let custom_attribute =
            *error == json::validation::Error::Invalid && where_.contains(".attributes[");
        !(unused_bounds || custom_attribute)
    });
    if let Some((location, error)) = problems.first() {
        let mut message = format!("invalid glTF: {error}");
        if problems.len() > 1 {
            let others: Vec<String> = problems[1..]
                .iter()
                .take(4)
                .map(|(w, e)| format!("{w}: {e}"))
                .collect();
            message.push_str(&format!(
                " (and {} more: {}{})",
                problems.len() - 1,
                others.join("; "),
                if problems.len() > 5 { "; ..." } else { "" }
            ));
        }
        return Err(InputError::new(path, location.clone(), message));
    }
    Ok(root)
}

/// Resolve every buffer to its bytes, exactly `byteLength` long.
fn load_buffers<'a>(
    path: &Path,
    root: &json::Root,
    bin: Option<&'a [u8]>,
) -> InputResult<Vec<Cow<'a, [u8]>>> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let at = |message: String| InputError::new(path, format!("buffers[{i}]"), message);
        let declared = buffer.byte_length.0;
        let data = match buffer.uri.as_deref() {
            None => {
                let bin = match (i, bin) {
                    (0, Some(bin)) => bin,
                    (0, None) => {
                        return Err(at(
                            "has no uri and the file has no GLB BIN chunk".to_string()
                        ))
                    }
                    _ => {
                        return Err(at("has no uri (only buffer 0 of a .glb file may \
                                       use the BIN chunk)"
                            .to_string()))
                    }
                };
                if declared > bin.len() as u64 {
                    return Err(at(format!(
                        "declares byteLength {declared} but the GLB BIN chunk has only {} bytes",
                        bin.len()
                    )));
                }
                Cow::Borrowed(&bin[..declared as usize])
            }
            Some(uri) if uri.starts_with("data:") => {
                Cow::Owned(decode_data_uri(uri, declared).map_err(at)?)
            }
            Some(uri) => Cow::Owned(read_buffer_file(path, uri, declared).map_err(at)?),
        };
        buffers.push(data);
    }
    Ok(buffers)
}

/// Decode a base64 `data:` URI holding at least `declared` bytes.
fn decode_data_uri(uri: &str, declared: u64) -> Result<Vec<u8>, String> {
    let Some((header, payload)) = uri.split_once(',') else {
        return Err("data: URI has no ',' before its data".to_string());
    };
    if !header.ends_with(";base64") {
        return Err("only base64 data: URIs are supported".to_string());
    }
    // Refuse before decoding if the text cannot possibly hold the bytes.
    let at_most = payload.len() as u64 / 4 * 3 + 3;
    if declared > at_most {
        return Err(format!(
            "declares byteLength {declared} but its data: URI holds at most {at_most} bytes"
        ));
    }
    let mut data = decode_base64(payload)?;
    if (data.len() as u64) < declared {
        return Err(format!(
            "declares byteLength {declared} but its data: URI holds only {} bytes",
            data.len()
        ));
    }
    data.truncate(declared as usize);
    Ok(data)
}

/// Standard (or URL-safe) base64, padding optional, whitespace ignored.
fn decode_base64(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    let (mut bits, mut bit_count) = (0u32, 0u32);
    let mut padding = false;
    for c in text.bytes() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            b' ' | b'\t' | b'\r' | b'\n' => continue,
            other => {
                return Err(format!(
                    "data: URI contains '{}', which is not base64",
                    char::from(other).escape_default()
                ))
            }
        };
        if padding {
            return Err("data: URI has base64 data after '=' padding".to_string());
        }
        bits = (bits << 6) | u32::from(value);
        bit_count += 6;
        if bit_count >= 8 {
            bit_count -= 8;
            out.push((bits >> bit_count) as u8);
            bits &= (1 << bit_count) - 1;
        }
    }
    Ok(out)
}

/// Read `declared` bytes of a buffer file named by a relative URI.
fn read_buffer_file(gltf_path: &Path, uri: &str, declared: u64) -> Result<Vec<u8>, String> {
    let scheme_end = uri.find(':');
    let slash = uri.find('/').unwrap_or(uri.len());
    if let Some(colon) = scheme_end.filter(|&c| c < slash && c > 1) {
        return Err(format!(
            "uri scheme '{}:' is not supported; use a relative file path or a data: URI",
            &uri[..colon]
        ));
    }
    let name = percent_decode(uri)?;
    let file = gltf_path.parent().unwrap_or(Path::new("")).join(name);
    let cannot = |e: std::io::Error| format!("cannot read {}: {}", file.display(), io_message(&e));
    let size = std::fs::metadata(&file).map_err(cannot)?.len();
    if size < declared {
        return Err(format!(
            "declares byteLength {declared} but {} has only {size} bytes",
            file.display()
        ));
    }
    let mut data = Vec::with_capacity(declared as usize);
    std::fs::File::open(&file)
        .map_err(cannot)?
        .take(declared)
        .read_to_end(&mut data)
        .map_err(cannot)?;
    if (data.len() as u64) < declared {
        return Err(format!(
            "declares byteLength {declared} but only {} bytes could be read from {}",
            data.len(),
            file.display()
        ));
    }
    Ok(data)
}

fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = uri
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("uri '{uri}' has a malformed %-escape"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("uri '{uri}' does not decode to UTF-8"))
}

/// An accessor's elements, bounds-checked against its buffer.
struct AccessorData<'b> {
    /// From the accessor's first element to the end of its view.
    bytes: &'b [u8],
    stride: usize,
    count: usize,
}

impl AccessorData<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.bytes[i * self.stride..]
    }
}

struct Loader<'a> {
    path: &'a Path,
    root: &'a json::Root,
    buffers: Vec<Cow<'a, [u8]>>,
}

impl Loader<'_> {
    fn error(&self, location: impl Into<String>, message: impl Into<String>) -> InputError {
        InputError::new(self.path, location, message)
    }

    fn load(&self) -> InputResult<LoadedAsset> {
        let mut asset = LoadedAsset {
            materials: self.materials()?,
            ..Default::default()
        };
        let root_nodes = self.root_nodes()?;
        let mut visited = vec![false; self.root.nodes.len()];
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
                self.visit(index, node, &world, &mut asset)?;
                for child in node.children.iter().flatten().rev() {
                    stack.push((child.value(), world));
                }
            }
        }
        Ok(asset)
    }

    /// The scene's root nodes: the default scene, else scene 0, else every
    /// node that is nobody's child.
    fn root_nodes(&self) -> InputResult<Vec<usize>> {
        let scene = match self.root.scene {
            Some(index) => Some(self.root.scenes.get(index.value()).ok_or_else(|| {
                self.error("scene", format!("scene {} does not exist", index.value()))
            })?),
            None => self.root.scenes.first(),
        };
        if let Some(scene) = scene {
            return Ok(scene.nodes.iter().map(|n| n.value()).collect());
        }
        let mut is_child = vec![false; self.root.nodes.len()];
        for node in &self.root.nodes {
            for child in node.children.iter().flatten() {
                if let Some(flag) = is_child.get_mut(child.value()) {
                    *flag = true;
                }
            }
        }
        Ok((0..self.root.nodes.len())
            .filter(|&i| !is_child[i])
            .collect())
    }

    fn local_transform(&self, index: usize, node: &json::Node) -> InputResult<Mat4> {
        let matrix = match node.matrix {
            Some(m) => Mat4::from_cols_array(&m),
            None => {
                let translation = Vec3::from(node.translation.unwrap_or([0.0; 3]));
                let scale = Vec3::from(node.scale.unwrap_or([1.0; 3]));
                let rotation = Quat::from_array(
                    node.rotation
                        .as_ref()
                        .map(|q| q.0)
                        .unwrap_or([0.0, 0.0, 0.0, 1.0]),
                );
                let length = rotation.length();
                if !(length.is_finite() && length > 0.0) {
                    return Err(self.error(
                        format!("nodes[{index}].rotation"),
                        "rotation is not a usable quaternion (zero or not finite)",
                    ));
                }
                Mat4::from_scale_rotation_translation(scale, rotation / length, translation)
            }
        };
        if !matrix.is_finite() {
            return Err(self.error(
                format!("nodes[{index}]"),
                "transform has values that are not finite",
            ));
        }
        Ok(matrix)
    }

    /// Collect what one node carries: meshes, a camera, a point light.
    fn visit(
        &self,
        index: usize,
        node: &json::Node,
        world: &Mat4,
        asset: &mut LoadedAsset,
    ) -> InputResult<()> {
        if let Some(mesh_index) = node.mesh.map(|m| m.value()) {
            let mesh = self.root.meshes.get(mesh_index).ok_or_else(|| {
                self.error(
                    format!("nodes[{index}].mesh"),
                    format!("meshes[{mesh_index}] does not exist"),
                )
            })?;
            let base_name = mesh
                .name
                .clone()
                .or_else(|| node.name.clone())
                .unwrap_or_else(|| format!("mesh{mesh_index}"));
            for (p, primitive) in mesh.primitives.iter().enumerate() {
                let name = if mesh.primitives.len() > 1 {
                    format!("{base_name}[{p}]")
                } else {
                    base_name.clone()
                };
                let location = format!("meshes[{mesh_index}].primitives[{p}]");
                if let Some(loaded) = self.primitive(&location, primitive, name, asset)? {
                    asset.meshes.push(self.place(index, loaded, world)?);
                }
            }
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
            if let Some(light) = self.point_light(index, light, world)? {
                asset.point_lights.push(light);
            }
        }
        Ok(())
    }

    /// Read one primitive in its mesh's local space; `None` for point and
    /// line primitives.
    fn primitive(
        &self,
        location: &str,
        primitive: &json::mesh::Primitive,
        name: String,
        asset: &LoadedAsset,
    ) -> InputResult<Option<LoadedMesh>> {
        let mode = match primitive.mode {
            Checked::Valid(mode) => mode,
            Checked::Invalid => return Err(self.error(location, "invalid primitive mode")),
        };
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            return Ok(None);
        }
        let position_accessor = primitive
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
            .ok_or_else(|| self.error(location, "primitive has no POSITION attribute"))?
            .value();
        let positions = self.read_vec3(position_accessor, "POSITION")?;
        let vertex_count = positions.len();
        if vertex_count > u32::MAX as usize {
            return Err(self.error(location, "more than 2³² vertices"));
        }
        let normals = match primitive.attributes.get(&Checked::Valid(Semantic::Normals)) {
            Some(accessor) => {
                let normals = self.read_vec3(accessor.value(), "NORMAL")?;
                if normals.len() != vertex_count {
                    return Err(self.error(
                        location,
                        format!(
                            "NORMAL has {} elements but POSITION has {vertex_count}",
                            normals.len()
                        ),
                    ));
                }
                Some(normals)
            }
            None => None,
        };
        let order: Vec<u32> = match primitive.indices {
            Some(accessor) => {
                let accessor = accessor.value();
                let indices = self.read_indices(accessor)?;
                if let Some((k, bad)) = indices
                    .iter()
                    .enumerate()
                    .find(|(_, &i)| i as usize >= vertex_count)
                {
                    return Err(self.error(
                        location,
                        format!(
                            "index {bad} (element {k} of accessors[{accessor}]) is out of \
                             range: the primitive has {vertex_count} vertices"
                        ),
                    ));
                }
                indices
            }
            None => (0..vertex_count as u32).collect(),
        };
        let indices =
            assemble_triangles(mode, &order).map_err(|message| self.error(location, message))?;
        let material = match primitive.material.map(|m| m.value()) {
            Some(m) if m >= asset.materials.len() => {
                return Err(self.error(
                    format!("{location}.material"),
                    format!("materials[{m}] does not exist"),
                ))
            }
            other => other,
        };
        Ok(Some(LoadedMesh {
            name,
            positions,
            normals: normals.map(|values| MeshNormals {
                values,
                indices: indices.clone(),
            }),
            indices,
            material,
        }))
    }

    /// Bake a node's world transform into a mesh read in local space.
    fn place(&self, node: usize, mut mesh: LoadedMesh, world: &Mat4) -> InputResult<LoadedMesh> {
        for p in &mut mesh.positions {
            *p = world.transform_point3(*p);
            if !p.is_finite() {
                return Err(self.error(
                    format!("nodes[{node}]"),
                    format!(
                        "the node's transform takes positions of mesh '{}' to infinity",
                        mesh.name
                    ),
                ));
            }
        }
        if let Some(normals) = &mut mesh.normals {
            let normal_matrix = normal_matrix(world);
            for n in &mut normals.values {
                *n = (normal_matrix * *n).normalize_or_zero();
            }
        }
        Ok(mesh)
    }

    fn camera(&self, node: usize, index: usize, world: &Mat4) -> InputResult<LoadedCamera> {
        use json::camera::Type;
        let location = format!("cameras[{index}]");
        let camera = self.root.cameras.get(index).ok_or_else(|| {
            self.error(
                format!("nodes[{node}].camera"),
                format!("{location} does not exist"),
            )
        })?;
        let (yfov_degrees, ortho_height) = match camera.type_ {
            Checked::Valid(Type::Perspective) => {
                let p = camera.perspective.as_ref().ok_or_else(|| {
                    self.error(
                        &location,
                        "type is perspective but there is no perspective object",
                    )
                })?;
                if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(self.error(
                        format!("{location}.perspective.yfov"),
                        format!("yfov must be between 0 and π radians, found {}", p.yfov),
                    ));
                }
                (Some(p.yfov.to_degrees()), None)
            }
            Checked::Valid(Type::Orthographic) => {
                let o = camera.orthographic.as_ref().ok_or_else(|| {
                    self.error(
                        &location,
                        "type is orthographic but there is no orthographic object",
                    )
                })?;
                if !(o.ymag.is_finite() && o.ymag > 0.0) {
                    return Err(self.error(
                        format!("{location}.orthographic.ymag"),
                        format!("ymag must be a positive number, found {}", o.ymag),
                    ));
                }
                (None, Some(2.0 * o.ymag))
            }
            Checked::Invalid => return Err(self.error(location, "invalid camera type")),
        };
        let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y);
        let up = (up - forward * up.dot(forward)).normalize_or_zero();
        if forward == Vec3::ZERO || up == Vec3::ZERO {
            return Err(self.error(
                format!("nodes[{node}]"),
                "the camera's world transform is degenerate (zero scale?)",
            ));
        }
        Ok(LoadedCamera {
            position: world.transform_point3(Vec3::ZERO),
            forward,
            up,
            yfov_degrees,
            ortho_height,
        })
    }

    fn point_light(
        &self,
        node: usize,
        index: usize,
        world: &Mat4,
    ) -> InputResult<Option<LoadedPointLight>> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let location = format!("extensions.KHR_lights_punctual.lights[{index}]");
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| {
                self.error(
                    format!("nodes[{node}].extensions.KHR_lights_punctual"),
                    format!("{location} does not exist"),
                )
            })?;
        match light.type_ {
            Checked::Valid(Type::Point) => {}
            Checked::Valid(Type::Spot | Type::Directional) => return Ok(None),
            Checked::Invalid => return Err(self.error(location, "invalid light type")),
        }
        let intensity = Vec3::from(light.color) * light.intensity / LUMENS_PER_WATT;
        if !intensity.is_finite() || intensity.min_element() < 0.0 {
            return Err(self.error(
                location,
                "color and intensity must be finite and not negative",
            ));
        }
        Ok(Some(LoadedPointLight {
            position: world.transform_point3(Vec3::ZERO),
            intensity,
        }))
    }

    fn materials(&self) -> InputResult<Vec<(String, Material)>> {
        let mut materials = Vec::with_capacity(self.root.materials.len());
        for (i, m) in self.root.materials.iter().enumerate() {
            let location = format!("materials[{i}]");
            let pbr = &m.pbr_metallic_roughness;
            let base = pbr.base_color_factor.0;
            let metallic = pbr.metallic_factor.0;
            let roughness = pbr.roughness_factor.0;
            let strength = m
                .extensions
                .as_ref()
                .and_then(|e| e.emissive_strength.as_ref())
                .map_or(1.0, |s| s.emissive_strength.0);
            let emission = Vec3::from(m.emissive_factor.0) * strength;
            let factors_ok = base.iter().all(|c| c.is_finite() && *c >= 0.0)
                && (0.0..=1.0).contains(&metallic)
                && (0.0..=1.0).contains(&roughness)
                && emission.is_finite()
                && emission.min_element() >= 0.0;
            if !factors_ok {
                return Err(self.error(
                    location,
                    "baseColorFactor, emissive factor and strength must be finite and not \
                     negative, metallicFactor and roughnessFactor between 0 and 1",
                ));
            }
            let name = m.name.clone().unwrap_or_else(|| format!("material{i}"));
            let base = Vec3::new(base[0], base[1], base[2]);
            materials.push((name, pbr_material(base, metallic, roughness, emission)));
        }
        Ok(materials)
    }

    /// Locate an accessor's bytes, checking view and buffer bounds.
    fn accessor(
        &self,
        index: usize,
        what: &str,
        accepts: impl Fn(ComponentType, AccessorType) -> bool,
    ) -> InputResult<(AccessorData<'_>, ComponentType)> {
        let location = format!("accessors[{index}]");
        let accessor = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.error(&location, "accessor does not exist"))?;
        let (Checked::Valid(component), Checked::Valid(dimensions)) =
            (&accessor.component_type, &accessor.type_)
        else {
            return Err(self.error(&location, "invalid componentType or type"));
        };
        let component = component.0;
        if !accepts(component, *dimensions) {
            return Err(self.error(
                &location,
                format!("{what} cannot be {component:?} {dimensions:?}"),
            ));
        }
        if accessor.sparse.is_some() {
            return Err(self.error(&location, "sparse accessors are not supported"));
        }
        let view_index = accessor
            .buffer_view
            .ok_or_else(|| self.error(&location, "accessor has no bufferView"))?
            .value();
        let view_location = format!("bufferViews[{view_index}]");
        let view = self
            .root
            .buffer_views
            .get(view_index)
            .ok_or_else(|| self.error(&location, format!("{view_location} does not exist")))?;
        let buffer_index = view.buffer.value();
        let buffer = self.buffers.get(buffer_index).ok_or_else(|| {
            self.error(
                &view_location,
                format!("buffers[{buffer_index}] does not exist"),
            )
        })?;
        let view_offset = view.byte_offset.map_or(0, |o| o.0);
        let view_length = view.byte_length.0;
        let view_end = view_offset
            .checked_add(view_length)
            .filter(|&end| end <= buffer.len() as u64)
            .ok_or_else(|| {
                self.error(
                    &view_location,
                    format!(
                        "byteOffset {view_offset} + byteLength {view_length} reach past the \
                         end of buffers[{buffer_index}] ({} bytes)",
                        buffer.len()
                    ),
                )
            })?;
        let view_bytes = &buffer[view_offset as usize..view_end as usize];

        let element_size = (component.size() * dimensions.multiplicity()) as u64;
        let stride = view.byte_stride.map_or(element_size, |s| s.0 as u64);
        if stride < element_size {
            return Err(self.error(
                &view_location,
                format!("byteStride {stride} is smaller than the {element_size}-byte elements of {location}"),
            ));
        }
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let count = accessor.count.0;
        let needed = if count == 0 {
            Some(offset)
        } else {
            (count - 1)
                .checked_mul(stride)
                .and_then(|n| n.checked_add(element_size))
                .and_then(|n| n.checked_add(offset))
        };
        match needed {
            Some(needed) if needed <= view_length => {}
            _ => {
                return Err(self.error(
                    &location,
                    format!(
                    "{count} elements of {element_size} bytes (stride {stride}) from byteOffset \
                         {offset} do not fit in {view_location} ({view_length} bytes)"
                ),
                ))
            }
        }
        Ok((
            AccessorData {
                bytes: &view_bytes[offset as usize..],
                stride: stride as usize,
                count: count as usize,
            },
            component,
        ))
    }

    fn read_vec3(&self, index: usize, what: &str) -> InputResult<Vec<Vec3>> {
        let (data, _) = self.accessor(index, what, |c, t| {
            c == ComponentType::F32 && t == AccessorType::Vec3
        })?;
        let mut values = Vec::with_capacity(data.count);
        for i in 0..data.count {
            let e = data.element(i);
            let v = Vec3::new(
                f32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                f32::from_le_bytes([e[4], e[5], e[6], e[7]]),
                f32::from_le_bytes([e[8], e[9], e[10], e[11]]),
            );
            if !v.is_finite() {
                return Err(self.error(
                    format!("accessors[{index}]"),
                    format!("{what} element {i} is not finite: {v}"),
                ));
            }
            values.push(v);
        }
        Ok(values)
    }

    fn read_indices(&self, index: usize) -> InputResult<Vec<u32>> {
        let (data, component) = self.accessor(index, "indices", |c, t| {
            matches!(
                c,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            ) && t == AccessorType::Scalar
        })?;
        Ok((0..data.count)
            .map(|i| {
                let e = data.element(i);
                match component {
                    ComponentType::U8 => u32::from(e[0]),
                    ComponentType::U16 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                    _ => u32_le(e),
                }
            })
            .collect())
    }
}

/// Turn a primitive's vertex order into triangles as its mode says.
fn assemble_triangles(mode: Mode, order: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    let n = order.len();
    match mode {
        Mode::TriangleStrip => Ok((0..n.saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [order[i], order[i + 1], order[i + 2]]
                } else {
                    [order[i], order[i + 2], order[i + 1]]
                }
            })
            .collect()),
        Mode::TriangleFan => Ok((0..n.saturating_sub(2))
            .map(|i| [order[i + 1], order[i + 2], order[0]])
            .collect()),
        _ => {
            if !n.is_multiple_of(3) {
                return Err(format!(
                    "a triangle list needs a multiple of 3 vertices, this one has {n}"
                ));
            }
            Ok(order.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect())
        }
    }
}

/// A matrix proportional to the inverse transpose of `world`'s upper 3×3
/// (its cofactor matrix, sign-corrected), so normals stay on the side they
/// were on. Defined even for singular transforms.
fn normal_matrix(world: &Mat4) -> Mat3 {
    let m = Mat3::from_mat4(*world);
    let cofactor = Mat3::from_cols(
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    );
    if m.determinant() < 0.0 {
        -cofactor
    } else {
        cofactor
    }
}

/// Phong exponent matching roughness `r`: `2/α² − 2` with `α = r²`,
/// clamped to [1, 10⁶].
fn phong_exponent(roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    let alpha2 = alpha * alpha;
    if alpha2 <= 0.0 {
        return MAX_PHONG_EXPONENT;
    }
    (2.0 / alpha2 - 2.0).clamp(1.0, MAX_PHONG_EXPONENT)
}

/// The metallic-roughness mapping in the module documentation's table.
fn pbr_material(base: Vec3, metallic: f32, roughness: f32, emission: Vec3) -> Material {
    let exponent = phong_exponent(roughness);
    Material {
        diffuse: base * (1.0 - metallic),
        specular: Vec3::splat(0.04 * (1.0 - metallic)),
        shininess: exponent,
        reflectivity: metallic,
        glossiness: if roughness == 0.0 { 0.0 } else { exponent },
        emission,
        ..Material::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    use super::super::test_files::{temp_dir, write};

    /// Builds one binary buffer with views and accessors into it.
    #[derive(Default)]
    struct Builder {
        bin: Vec<u8>,
        views: Vec<String>,
        accessors: Vec<String>,
    }

    impl Builder {
        fn view(&mut self, bytes: &[u8]) -> usize {
            while !self.bin.len().is_multiple_of(4) {
                self.bin.push(0);
            }
            let offset = self.bin.len();
            self.bin.extend_from_slice(bytes);
            self.views.push(format!(
                r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
                bytes.len()
            ));
            self.views.len() - 1
        }

        fn accessor(&mut self, json: String) -> usize {
            self.accessors.push(json);
            self.accessors.len() - 1
        }

        fn vec3(&mut self, values: &[[f32; 3]], bounds: bool) -> usize {
            let bytes: Vec<u8> = values
                .iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect();
            let view = self.view(&bytes);
            let bounds = if bounds {
                let lo = (0..3).map(|k| values.iter().map(|v| v[k]).fold(f32::MAX, f32::min));
                let hi = (0..3).map(|k| values.iter().map(|v| v[k]).fold(f32::MIN, f32::max));
                let list = |it: &mut dyn Iterator<Item = f32>| {
                    it.map(|v| format!("{v:?}")).collect::<Vec<_>>().join(",")
                };
                format!(
                    r#","min":[{}],"max":[{}]"#,
                    list(&mut { lo }),
                    list(&mut { hi })
                )
            } else {
                String::new()
            };
            self.accessor(format!(
                r#"{{"bufferView":{view},"componentType":5126,"count":{},"type":"VEC3"{bounds}}}"#,
                values.len()
            ))
        }

        fn positions(&mut self, values: &[[f32; 3]]) -> usize {
            self.vec3(values, true)
        }

        fn u16s(&mut self, values: &[u16]) -> usize {
            let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            let view = self.view(&bytes);
            self.accessor(format!(
                r#"{{"bufferView":{view},"componentType":5123,"count":{},"type":"SCALAR"}}"#,
                values.len()
            ))
        }

        fn u8s(&mut self, values: &[u8]) -> usize {
            let view = self.view(values);
            self.accessor(format!(
                r#"{{"bufferView":{view},"componentType":5121,"count":{},"type":"SCALAR"}}"#,
                values.len()
            ))
        }

        fn u32s(&mut self, values: &[u32]) -> usize {
            let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            let view = self.view(&bytes);
            self.accessor(format!(
                r#"{{"bufferView":{view},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
                values.len()
            ))
        }

        /// The glTF JSON; `uri` is the buffer's uri (None for a GLB), `rest`
        /// the remaining top-level members (nodes, meshes, ...).
        fn json(&self, uri: Option<&str>, rest: &str) -> String {
            let uri = uri.map(|u| format!(r#","uri":"{u}""#)).unwrap_or_default();
            let rest = if rest.is_empty() {
                String::new()
            } else {
                format!(",{rest}")
            };
            format!(
                r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}{uri}}}],"bufferViews":[{}],"accessors":[{}]{rest}}}"#,
                self.bin.len(),
                self.views.join(","),
                self.accessors.join(",")
            )
        }

        fn data_uri(&self) -> String {
            format!(
                "data:application/octet-stream;base64,{}",
                encode_base64(&self.bin)
            )
        }

        fn glb(&self, rest: &str) -> Vec<u8> {
            glb_bytes(self.json(None, rest).as_bytes(), Some(&self.bin))
        }

        /// Write `name`.gltf with `name`.bin beside it.
        fn write_gltf(&self, dir: &Path, name: &str, rest: &str) -> PathBuf {
            write(dir, &format!("{name}.bin"), &self.bin);
            let json = self.json(Some(&format!("{name}.bin")), rest);
            write(dir, &format!("{name}.gltf"), json.as_bytes())
        }
    }

    fn glb_bytes(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
        let mut json = json.to_vec();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut chunks = Vec::new();
        chunks.extend_from_slice(&(json.len() as u32).to_le_bytes());
        chunks.extend_from_slice(b"JSON");
        chunks.extend_from_slice(&json);
        if let Some(bin) = bin {
            let mut bin = bin.to_vec();
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            chunks.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            chunks.extend_from_slice(b"BIN\0");
            chunks.extend_from_slice(&bin);
        }
        let mut out = b"glTF".to_vec();
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&((12 + chunks.len()) as u32).to_le_bytes());
        out.extend_from_slice(&chunks);
        out
    }

    fn encode_base64(bytes: &[u8]) -> String {
        const ALPHABET: &[u8; 64] =
            b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
            for k in 0..4 {
                if k <= chunk.len() {
                    out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    /// A builder holding one indexed triangle as mesh 0 (accessors 0 and 1).
    fn triangle_builder() -> Builder {
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        b.u16s(&[0, 1, 2]);
        b
    }

    const TRIANGLE_MESH: &str =
        r#""meshes":[{"name":"tri","primitives":[{"attributes":{"POSITION":0},"indices":1}]}]"#;

    fn load_json(b: &Builder, rest: &str) -> InputResult<LoadedAsset> {
        let dir = temp_dir("json");
        load_gltf(&b.write_gltf(&dir, "scene", rest))
    }

    fn corners(mesh: &LoadedMesh) -> Vec<[Vec3; 3]> {
        mesh.indices
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect()
    }

    fn assert_close(a: Vec3, b: Vec3) {
        assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
    }

    fn assert_corners(mesh: &LoadedMesh, expected: [[f32; 3]; 3]) {
        let got = corners(mesh);
        assert_eq!(got.len(), 1);
        for k in 0..3 {
            assert_close(got[0][k], Vec3::from(expected[k]));
        }
    }

    #[test]
    fn node_transforms_are_baked_into_positions() {
        let b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let rest = format!(
            r#"{TRIANGLE_MESH},"scene":0,"scenes":[{{"nodes":[0,1,2,3,4]}}],"nodes":[
                {{"mesh":0,"translation":[1,2,3]}},
                {{"mesh":0,"rotation":[0,0,{s},{s}]}},
                {{"mesh":0,"scale":[2,3,4]}},
                {{"mesh":0,"matrix":[2,0,0,0, 0,2,0,0, 0,0,2,0, 10,0,0,1]}},
                {{"translation":[0,0,5],"scale":[2,2,2],"children":[5]}},
                {{"mesh":0,"translation":[1,0,0]}}
            ]"#
        );
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.meshes.len(), 5);
        assert!(asset.meshes.iter().all(|m| m.name == "tri"));
        assert_corners(&asset.meshes[0], [[1., 2., 3.], [2., 2., 3.], [1., 3., 3.]]);
        assert_corners(
            &asset.meshes[1],
            [[0., 0., 0.], [0., 1., 0.], [-1., 0., 0.]],
        );
        assert_corners(&asset.meshes[2], [[0., 0., 0.], [2., 0., 0.], [0., 3., 0.]]);
        assert_corners(
            &asset.meshes[3],
            [[10., 0., 0.], [12., 0., 0.], [10., 2., 0.]],
        );
        // Parent T(0,0,5)·S(2) applied after the child's T(1,0,0).
        assert_corners(&asset.meshes[4], [[2., 0., 5.], [4., 0., 5.], [2., 2., 5.]]);
        assert_eq!(asset.triangle_count(), 5);
    }

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
        let asset = load_json(&b, &rest).unwrap();
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
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.meshes.len(), 2);
        assert_eq!(asset.meshes[0].positions[0], Vec3::Y);
        assert_eq!(asset.meshes[1].positions[0], Vec3::ZERO);
    }

    #[test]
    fn cameras_and_point_lights_are_placed_in_world_space() {
        let b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let rest = format!(
            r#"{TRIANGLE_MESH},"scenes":[{{"nodes":[0,2,4]}}],
            "cameras":[{{"type":"perspective","perspective":{{"yfov":0.5,"znear":0.1}}}},
                       {{"type":"orthographic","orthographic":{{"xmag":4,"ymag":3,"znear":0.1,"zfar":100}}}}],
            "extensions":{{"KHR_lights_punctual":{{"lights":[
                {{"type":"point","color":[1,0.5,0.25],"intensity":683}},
                {{"type":"spot","spot":{{}}}},
                {{"type":"directional"}}]}}}},
            "nodes":[
                {{"translation":[0,1,0],"children":[1]}},
                {{"camera":0,"translation":[0,0,5],"rotation":[0,{s},0,{s}]}},
                {{"camera":1,"extensions":{{"KHR_lights_punctual":{{"light":0}}}},"translation":[3,4,5]}},
                {{"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
                {{"children":[3,5]}},
                {{"extensions":{{"KHR_lights_punctual":{{"light":2}}}}}}
            ]"#
        );
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.cameras.len(), 2);
        let perspective = &asset.cameras[0];
        assert_close(perspective.position, Vec3::new(0., 1., 5.));
        // A quarter turn about +Y takes −Z to −X.
        assert_close(perspective.forward, Vec3::new(-1., 0., 0.));
        assert_close(perspective.up, Vec3::Y);
        assert!((perspective.yfov_degrees.unwrap() - 0.5f32.to_degrees()).abs() < 1e-4);
        assert_eq!(perspective.ortho_height, None);
        let ortho = &asset.cameras[1];
        assert_close(ortho.position, Vec3::new(3., 4., 5.));
        assert_close(ortho.forward, -Vec3::Z);
        assert_eq!(ortho.ortho_height, Some(6.0));
        assert_eq!(ortho.yfov_degrees, None);

        assert_eq!(
            asset.point_lights.len(),
            1,
            "spot and directional are skipped"
        );
        assert_close(asset.point_lights[0].position, Vec3::new(3., 4., 5.));
        assert_close(asset.point_lights[0].intensity, Vec3::new(1.0, 0.5, 0.25));
    }

    #[test]
    fn materials_follow_the_mapping_table() {
        let mut b = triangle_builder();
        b.u8s(&[2, 1, 0]);
        let rest = r#""materials":[
                {"name":"plastic","pbrMetallicRoughness":{"baseColorFactor":[0.5,0.25,1,1],"metallicFactor":0,"roughnessFactor":1}},
                {"pbrMetallicRoughness":{"baseColorFactor":[0.9,0.8,0.7,1],"metallicFactor":1,"roughnessFactor":0}},
                {"name":"satin","pbrMetallicRoughness":{"metallicFactor":0.5,"roughnessFactor":0.5},
                 "emissiveFactor":[1,0.5,0],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":10}}}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":2},
                                     {"attributes":{"POSITION":0},"indices":2}]}],
            "nodes":[{"mesh":0}]"#;
        let asset = load_json(&b, rest).unwrap();
        let names: Vec<&str> = asset.materials.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["plastic", "material1", "satin"]);

        let plastic = asset.materials[0].1;
        assert_close(plastic.diffuse, Vec3::new(0.5, 0.25, 1.0));
        assert_eq!(plastic.reflectivity, 0.0);
        assert_close(plastic.specular, Vec3::splat(0.04));
        assert_eq!(
            plastic.shininess, 1.0,
            "r = 1 gives 2/1 − 2 = 0, clamped to 1"
        );
        assert_eq!(plastic.glossiness, 1.0);
        assert_eq!(plastic.emission, Vec3::ZERO);

        let metal = asset.materials[1].1;
        assert_eq!(metal.diffuse, Vec3::ZERO);
        assert_eq!(metal.reflectivity, 1.0);
        assert_eq!(metal.specular, Vec3::ZERO);
        assert_eq!(metal.glossiness, 0.0, "r = 0 is a perfect mirror");
        assert_eq!(metal.shininess, 1.0e6);

        let satin = asset.materials[2].1;
        assert_close(satin.diffuse, Vec3::splat(0.5));
        assert_eq!(satin.reflectivity, 0.5);
        assert_close(satin.specular, Vec3::splat(0.02));
        // α = 0.25, 2/α² − 2 = 30.
        assert!(
            (satin.glossiness - 30.0).abs() < 1e-3,
            "{}",
            satin.glossiness
        );
        assert!((satin.shininess - 30.0).abs() < 1e-3);
        assert_close(satin.emission, Vec3::new(10.0, 5.0, 0.0));
        assert_eq!(satin.transparency, 0.0);
        assert_eq!(satin.ior, 1.5);

        assert_eq!(asset.meshes.len(), 2);
        assert_eq!(asset.meshes[0].name, "mesh0[0]");
        assert_eq!(asset.meshes[0].material, Some(2));
        assert_eq!(asset.meshes[1].material, None);
        assert_eq!(asset.meshes[1].indices, vec![[2, 1, 0]]);
    }

    #[test]
    fn non_indexed_strip_and_fan_primitives() {
        let mut b = Builder::default();
        let quad = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [1., 1., 0.]];
        b.positions(&[
            [0., 0., 0.],
            [1., 0., 0.],
            [0., 1., 0.],
            [5., 0., 0.],
            [6., 0., 0.],
            [5., 1., 0.],
        ]);
        b.positions(&quad);
        b.u32s(&[0, 1, 2, 3]);
        let rest = r#""meshes":[{"primitives":[
                {"attributes":{"POSITION":0}},
                {"attributes":{"POSITION":1},"mode":5},
                {"attributes":{"POSITION":1},"indices":2,"mode":6},
                {"attributes":{"POSITION":1},"mode":0},
                {"attributes":{"POSITION":1},"mode":1}]}],
            "nodes":[{"mesh":0}]"#;
        let asset = load_json(&b, rest).unwrap();
        assert_eq!(asset.meshes.len(), 3, "points and lines are skipped");
        assert_eq!(asset.meshes[0].indices, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(asset.meshes[1].indices, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(asset.meshes[2].indices, vec![[1, 2, 0], [2, 3, 0]]);
    }

    #[test]
    fn normals_use_the_inverse_transpose() {
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        b.vec3(&[[s, s, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], false);
        let rest = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1}}]}],
            "nodes":[{"mesh":0,"scale":[2,1,1]},{"mesh":0,"scale":[-1,1,1]},{"mesh":0}]"#;
        let asset = load_json(&b, rest).unwrap();
        let normals = |m: usize| asset.meshes[m].normals.clone().expect("normals");
        let stretched = normals(0);
        assert_close(stretched.values[0], Vec3::new(0.5, 1.0, 0.0).normalize());
        assert_close(stretched.values[1], Vec3::X);
        assert_eq!(stretched.indices, asset.meshes[0].indices);
        let mirrored = normals(1);
        assert_close(mirrored.values[1], -Vec3::X);
        assert_close(mirrored.values[2], Vec3::Z);
        assert_eq!(
            asset.meshes[1].indices,
            vec![[0, 1, 2]],
            "winding kept as stored"
        );
        assert_close(asset.meshes[1].positions[1], -Vec3::X);
        assert_close(normals(2).values[0], Vec3::new(s, s, 0.0));
    }

    #[test]
    fn bin_file_data_uri_and_glb_load_the_same() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"translation":[0,0,-1]}}]"#);
        let dir = temp_dir("same");
        let from_bin = load_gltf(&b.write_gltf(&dir, "separate", &rest)).unwrap();
        let embedded = b.json(Some(&b.data_uri()), &rest);
        let from_uri = load_gltf(&write(&dir, "embedded.gltf", embedded.as_bytes())).unwrap();
        let from_glb = load_gltf(&write(&dir, "binary.glb", &b.glb(&rest))).unwrap();
        assert_eq!(from_bin, from_uri);
        assert_eq!(from_bin, from_glb);
        assert_corners(
            &from_glb.meshes[0],
            [[0., 0., -1.], [1., 0., -1.], [0., 1., -1.]],
        );
        // A percent-encoded file name resolves too.
        write(&dir, "with space.bin", &b.bin);
        let json = b.json(Some("with%20space.bin"), &rest);
        let spaced = load_gltf(&write(&dir, "spaced.gltf", json.as_bytes())).unwrap();
        assert_eq!(spaced, from_bin);
    }

    fn expect_error(result: InputResult<LoadedAsset>, file: &str, location: &str, needle: &str) {
        let err = result.expect_err("expected an error");
        let shown = err.to_string();
        assert!(err.file.ends_with(file), "{shown} should name {file}");
        assert_eq!(err.location, location, "{shown}");
        assert!(shown.contains(location), "{shown}");
        assert!(shown.contains(needle), "{shown} should contain '{needle}'");
    }

    #[test]
    fn malformed_json_and_validation_errors() {
        let dir = temp_dir("json-errors");
        let path = write(
            &dir,
            "broken.gltf",
            b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [",
        );
        expect_error(load_gltf(&path), "broken.gltf", "", "invalid glTF JSON");
        let b = triangle_builder();
        expect_error(
            load_json(&b, r#""nodes":[{"mesh":3}]"#),
            "scene.gltf",
            "nodes[0].mesh",
            "Index out of bounds",
        );
        // The gltf crate's own validator would panic on this one.
        expect_error(
            load_json(
                &b,
                r#""meshes":[{"primitives":[{"attributes":{"POSITION":9}}]}]"#,
            ),
            "scene.gltf",
            "meshes[0].primitives[0]",
            "accessors[9]",
        );
        expect_error(
            load_json(
                &b,
                r#""extensionsRequired":["KHR_draco_mesh_compression"],"extensionsUsed":["KHR_draco_mesh_compression"]"#,
            ),
            "scene.gltf",
            "extensionsRequired[0] = \"KHR_draco_mesh_compression\"",
            "Unsupported extension",
        );
    }

    #[test]
    fn missing_position_is_an_error() {
        let mut b = Builder::default();
        b.vec3(&TRIANGLE, false);
        let err = load_json(
            &b,
            r#""meshes":[{"primitives":[{"attributes":{"NORMAL":0}}]}],"nodes":[{"mesh":0}]"#,
        )
        .unwrap_err();
        assert!(err.location.starts_with("meshes[0].primitives[0]"), "{err}");
        assert!(err.to_string().contains("POSITION"), "{err}");
        assert!(err.file.ends_with("scene.gltf"));
    }

    #[test]
    fn custom_attributes_and_missing_bounds_are_tolerated() {
        let mut b = Builder::default();
        b.vec3(&TRIANGLE, false);
        let asset = load_json(
            &b,
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"_BATCHID":0}}]}],"nodes":[{"mesh":0}]"#,
        )
        .unwrap();
        assert_eq!(asset.triangle_count(), 1);
    }

    #[test]
    fn index_out_of_range_names_the_primitive() {
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        b.u16s(&[0, 1, 3]);
        let rest = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "meshes[0].primitives[0]",
            "index 3",
        );
    }

    #[test]
    fn non_finite_positions_are_refused() {
        let mut b = Builder::default();
        b.vec3(
            &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
            false,
        );
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "accessors[0]",
            "not finite",
        );
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"scale":[1e30,1,1],"children":[1]}},{{"mesh":0,"scale":[1e30,1,1]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[1]",
            "world transform is not finite",
        );
        // A finite transform can still take a vertex to infinity.
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"scale":[3e38,1,1],"translation":[3e38,0,0]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[0]",
            "to infinity",
        );
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"translation":[1e39,0,0]}}]"#);
        expect_error(load_json(&b, &rest), "scene.gltf", "nodes[0]", "not finite");
    }

    #[test]
    fn accessors_and_views_out_of_range() {
        let mut b = triangle_builder();
        // Accessor 2 claims 4 elements from the 3-element view 0.
        b.accessor(r#"{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}"#.to_string());
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":2}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "accessors[2]",
            "do not fit in bufferViews[0]",
        );

        let mut b = triangle_builder();
        b.views
            .push(r#"{"buffer":0,"byteOffset":8,"byteLength":1000000}"#.to_string());
        b.accessor(r#"{"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}"#.to_string());
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":2}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "bufferViews[2]",
            "past the end of buffers[0]",
        );

        let mut b = triangle_builder();
        b.accessor(
            r#"{"bufferView":0,"componentType":5126,"count":18446744073709551615,"type":"VEC3"}"#
                .to_string(),
        );
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":2}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "accessors[2]",
            "do not fit",
        );

        let b = triangle_builder();
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":1}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "accessors[1]",
            "POSITION cannot be U16 Scalar",
        );
    }

    #[test]
    fn buffers_shorter_than_declared_are_refused() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let dir = temp_dir("short");
        // External file shorter than byteLength.
        let path = b.write_gltf(&dir, "short", &rest);
        write(&dir, "short.bin", &b.bin[..10]);
        expect_error(
            load_gltf(&path),
            "short.gltf",
            "buffers[0]",
            "has only 10 bytes",
        );
        // A huge declared length is refused without trying to allocate it.
        let json = b.json(Some("short.bin"), &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":1000000000000000",
            1,
        );
        let path = write(&dir, "huge.gltf", json.as_bytes());
        expect_error(
            load_gltf(&path),
            "huge.gltf",
            "buffers[0]",
            "byteLength 1000000000000000",
        );
        // data: URI shorter than byteLength.
        let json = b.json(Some(&b.data_uri()), &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":1000000000000",
            1,
        );
        let path = write(&dir, "uri.gltf", json.as_bytes());
        expect_error(
            load_gltf(&path),
            "uri.gltf",
            "buffers[0]",
            "data: URI holds at most",
        );
        // GLB whose BIN chunk is shorter than the buffer's byteLength.
        let json = b.json(None, &rest).replacen(
            &format!("\"byteLength\":{}", b.bin.len()),
            "\"byteLength\":4096",
            1,
        );
        let path = write(&dir, "short.glb", &glb_bytes(json.as_bytes(), Some(&b.bin)));
        expect_error(
            load_gltf(&path),
            "short.glb",
            "buffers[0]",
            "BIN chunk has only",
        );
        // GLB without a BIN chunk at all.
        let path = write(
            &dir,
            "nobin.glb",
            &glb_bytes(b.json(None, &rest).as_bytes(), None),
        );
        expect_error(
            load_gltf(&path),
            "nobin.glb",
            "buffers[0]",
            "no GLB BIN chunk",
        );
    }

    #[test]
    fn missing_buffer_file_is_named() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let dir = temp_dir("missing");
        let path = write(
            &dir,
            "lonely.gltf",
            b.json(Some("gone.bin"), &rest).as_bytes(),
        );
        expect_error(
            load_gltf(&path),
            "lonely.gltf",
            "buffers[0]",
            "gone.bin: No such file or directory",
        );
        let path = write(
            &dir,
            "web.gltf",
            b.json(Some("https://example.com/x.bin"), &rest).as_bytes(),
        );
        expect_error(
            load_gltf(&path),
            "web.gltf",
            "buffers[0]",
            "scheme 'https:'",
        );
    }

    #[test]
    fn bad_glb_headers() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let good = b.glb(&rest);
        let dir = temp_dir("glb");
        let mut v1 = good.clone();
        v1[4] = 1;
        expect_error(
            load_gltf(&write(&dir, "v1.glb", &v1)),
            "v1.glb",
            "GLB header",
            "version 1",
        );
        let mut long = good.clone();
        long[8..12].copy_from_slice(&(good.len() as u32 + 1).to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "long.glb", &long)),
            "long.glb",
            "GLB header",
            "truncated",
        );
        let mut tiny = good.clone();
        tiny[8..12].copy_from_slice(&3u32.to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "tiny.glb", &tiny)),
            "tiny.glb",
            "GLB header",
            "less than the header",
        );
        expect_error(
            load_gltf(&write(&dir, "text.glb", b"hello")),
            "text.glb",
            "GLB header",
            "magic",
        );
        let mut chunk = good.clone();
        chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "chunk.glb", &chunk)),
            "chunk.glb",
            "GLB chunk 0",
            "truncated",
        );

        // Every truncation of a valid GLB is an error, never a panic.
        let path = dir.join("cut.glb");
        for len in 0..good.len() {
            let mut cut = good[..len].to_vec();
            if len >= 12 {
                cut[8..12].copy_from_slice(&(len as u32).to_le_bytes());
            }
            std::fs::write(&path, &cut).unwrap();
            assert!(load_gltf(&path).is_err(), "truncated to {len} bytes");
            std::fs::write(&path, &good[..len]).unwrap();
            assert!(load_gltf(&path).is_err(), "cut to {len} bytes");
        }
        std::fs::write(&path, &good).unwrap();
        assert_eq!(load_gltf(&path).unwrap().triangle_count(), 1);
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

    #[test]
    fn base64_round_trips() {
        for len in 0..20 {
            let data: Vec<u8> = (0..len).map(|i| (i * 37 + 11) as u8).collect();
            assert_eq!(decode_base64(&encode_base64(&data)).unwrap(), data);
        }
        assert!(decode_base64("ab!c").is_err());
    }
}

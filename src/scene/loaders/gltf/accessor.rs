//! Accessors and buffer views: where an attribute's or index list's elements
//! lie in a buffer, with every offset, stride and count checked against the
//! bytes there before a single element is read.

use super::container::u32_le;
use super::Loader;
use crate::error::InputResult;
use ::gltf::json;
use glam::{Vec2, Vec3};
use json::accessor::{ComponentType, Type as AccessorType};
use json::validation::Checked;
use std::borrow::Cow;

/// An accessor's elements, bounds-checked against its buffer.
struct AccessorData<'b> {
    /// From the accessor's first element to the end of its view; or, for a
    /// sparse accessor, its elements with the substitutions made.
    bytes: Cow<'b, [u8]>,
    stride: usize,
    count: usize,
}

impl AccessorData<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.bytes[i * self.stride..]
    }
}

impl Loader<'_> {
    /// A buffer view and its bytes, checked against its buffer; `referrer`
    /// is the location of what names the view, for the error if it does not
    /// exist.
    pub(super) fn view(
        &self,
        view_index: usize,
        referrer: &str,
    ) -> InputResult<(&json::buffer::View, &[u8])> {
        let view_location = format!("bufferViews[{view_index}]");
        let view = self
            .root
            .buffer_views
            .get(view_index)
            .ok_or_else(|| self.error(referrer, format!("{view_location} does not exist")))?;
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
        Ok((view, &buffer[view_offset as usize..view_end as usize]))
    }

    /// Locate an accessor's bytes, checking view and buffer bounds.
    fn accessor(
        &self,
        index: usize,
        what: &str,
        accepts: impl Fn(ComponentType, AccessorType, bool) -> bool,
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
        if !accepts(component, *dimensions, accessor.normalized) {
            let normalized = if accessor.normalized {
                "normalized "
            } else {
                ""
            };
            return Err(self.error(
                &location,
                format!("{what} cannot be {normalized}{component:?} {dimensions:?}"),
            ));
        }
        let element_size = (component.size() * dimensions.multiplicity()) as u64;
        let count = accessor.count.0;
        let data = match accessor.buffer_view {
            Some(view) => self.dense(&location, view.value(), accessor, element_size)?,
            // glTF: without a bufferView the elements are zeros, which a
            // sparse accessor then replaces in part.
            None if accessor.sparse.is_some() => {
                let bytes = count
                    .checked_mul(element_size)
                    .filter(|&n| n <= MAX_ZERO_BYTES)
                    .ok_or_else(|| {
                        self.error(
                            &location,
                            format!(
                                "{count} elements of {element_size} bytes without a bufferView \
                                 (zeros) are more than strata reads ({MAX_ZERO_BYTES} bytes)"
                            ),
                        )
                    })?;
                AccessorData {
                    bytes: Cow::Owned(vec![0; bytes as usize]),
                    stride: element_size as usize,
                    count: count as usize,
                }
            }
            None => return Err(self.error(&location, "accessor has no bufferView")),
        };
        let data = match &accessor.sparse {
            Some(sparse) => self.substituted(&location, data, sparse, element_size as usize)?,
            None => data,
        };
        Ok((data, component))
    }

    /// The elements of `accessor` (at `location`) in buffer view
    /// `view_index`, checked to fit in it.
    fn dense(
        &self,
        location: &str,
        view_index: usize,
        accessor: &json::Accessor,
        element_size: u64,
    ) -> InputResult<AccessorData<'_>> {
        let view_location = format!("bufferViews[{view_index}]");
        let (view, view_bytes) = self.view(view_index, location)?;
        let view_length = view_bytes.len() as u64;
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
                    location,
                    format!(
                    "{count} elements of {element_size} bytes (stride {stride}) from byteOffset \
                         {offset} do not fit in {view_location} ({view_length} bytes)"
                ),
                ))
            }
        }
        Ok(AccessorData {
            bytes: Cow::Borrowed(&view_bytes[offset as usize..]),
            stride: stride as usize,
            count: count as usize,
        })
    }

    /// `base`'s elements, tightly packed, with those a sparse accessor names
    /// (at `location`) replaced by its values: `sparse.count` indices, each
    /// below the element count, and as many values of `element_size` bytes.
    fn substituted(
        &self,
        location: &str,
        base: AccessorData<'_>,
        sparse: &json::accessor::sparse::Sparse,
        element_size: usize,
    ) -> InputResult<AccessorData<'static>> {
        let n = sparse.count.0;
        let indices_location = format!("{location}.sparse.indices");
        let values_location = format!("{location}.sparse.values");
        let Checked::Valid(index_type) = &sparse.indices.component_type else {
            return Err(self.error(&indices_location, "invalid componentType"));
        };
        let index_size = index_type.0.size();
        let part = |view: usize, at: &str, offset: u64, size: usize| {
            let (_, bytes) = self.view(view, at)?;
            let length = bytes.len();
            n.checked_mul(size as u64)
                .and_then(|k| k.checked_add(offset))
                .filter(|&end| end <= length as u64)
                .map(|end| &bytes[offset as usize..end as usize])
                .ok_or_else(|| {
                    self.error(
                        at,
                        format!(
                            "{n} entries of {size} bytes from byteOffset {offset} do not fit in \
                             bufferViews[{view}] ({length} bytes)"
                        ),
                    )
                })
        };
        let indices = part(
            sparse.indices.buffer_view.value(),
            &indices_location,
            sparse.indices.byte_offset.0,
            index_size,
        )?;
        let values = part(
            sparse.values.buffer_view.value(),
            &values_location,
            sparse.values.byte_offset.0,
            element_size,
        )?;
        let mut bytes = match base.bytes {
            Cow::Owned(bytes) => bytes,
            Cow::Borrowed(_) => (0..base.count)
                .flat_map(|i| &base.element(i)[..element_size])
                .copied()
                .collect(),
        };
        for (k, (at, value)) in indices
            .chunks_exact(index_size)
            .zip(values.chunks_exact(element_size))
            .enumerate()
        {
            let i = index_at(at, index_type.0) as usize;
            if i >= base.count {
                return Err(self.error(
                    &indices_location,
                    format!(
                        "entry {k} is element {i}, past the accessor's {} elements",
                        base.count
                    ),
                ));
            }
            bytes[i * element_size..(i + 1) * element_size].copy_from_slice(value);
        }
        Ok(AccessorData {
            bytes: Cow::Owned(bytes),
            stride: element_size,
            count: base.count,
        })
    }

    /// A `VEC3` attribute (`POSITION`, `NORMAL`): floats, or the integers
    /// `attribute` may have, each element finite.
    pub(super) fn read_vec3(&self, index: usize, attribute: Attribute) -> InputResult<Vec<Vec3>> {
        let (data, component, normalized) = self.attribute(index, attribute)?;
        self.finite_elements(index, &attribute.name(), &data, |e| {
            let c = |k: usize| decode(e, component, k, normalized);
            Vec3::new(c(0), c(1), c(2))
        })
    }

    /// A `VEC4` attribute (glTF `TANGENT`), every value finite.
    pub(super) fn read_vec4(&self, index: usize) -> InputResult<Vec<glam::Vec4>> {
        let attribute = Attribute::Tangent;
        let (data, component, normalized) = self.attribute(index, attribute)?;
        self.finite_elements(index, &attribute.name(), &data, |e| {
            let c = |k: usize| decode(e, component, k, normalized);
            glam::Vec4::new(c(0), c(1), c(2), c(3))
        })
    }

    /// Texture coordinates (`VEC2`) of set `set`: floats, or integers (n/255
    /// and n/65535 for normalized unsigned bytes and shorts, as glTF reads
    /// them; the rest as `KHR_mesh_quantization` allows).
    pub(super) fn read_uvs(&self, index: usize, set: usize) -> InputResult<Vec<Vec2>> {
        let attribute = Attribute::TexCoord(set);
        let (data, component, normalized) = self.attribute(index, attribute)?;
        self.finite_elements(index, &attribute.name(), &data, |e| {
            let c = |k: usize| decode(e, component, k, normalized);
            Vec2::new(c(0), c(1))
        })
    }

    /// An attribute accessor's elements, its component type and whether it
    /// is normalized, refused unless `attribute` may have them.
    fn attribute(
        &self,
        index: usize,
        attribute: Attribute,
    ) -> InputResult<(AccessorData<'_>, ComponentType, bool)> {
        let (data, component) = self.accessor(index, &attribute.name(), |c, t, normalized| {
            t == attribute.dimensions() && attribute.accepts(c, normalized)
        })?;
        // A float is never normalized: the flag is ignored there.
        let normalized = self.root.accessors[index].normalized;
        Ok((data, component, normalized))
    }

    /// Decode every element of `data`, refusing the first that is not finite
    /// (a NaN position or UV would poison the BVH or the texture lookup).
    fn finite_elements<T: FiniteValue>(
        &self,
        index: usize,
        what: &str,
        data: &AccessorData,
        decode: impl Fn(&[u8]) -> T,
    ) -> InputResult<Vec<T>> {
        let mut values = Vec::with_capacity(data.count);
        for i in 0..data.count {
            let v = decode(data.element(i));
            if !v.finite() {
                return Err(self.error(
                    format!("accessors[{index}]"),
                    format!("{what} element {i} is not finite: {v}"),
                ));
            }
            values.push(v);
        }
        Ok(values)
    }

    pub(super) fn read_indices(&self, index: usize) -> InputResult<Vec<u32>> {
        let (data, component) = self.accessor(index, "indices", |c, t, _| {
            matches!(
                c,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            ) && t == AccessorType::Scalar
        })?;
        Ok((0..data.count)
            .map(|i| index_at(data.element(i), component))
            .collect())
    }
}

/// The unsigned index at the start of `e`, of component type `component`
/// (a byte, a short or an int, as glTF's index lists and a sparse
/// accessor's indices hold them).
fn index_at(e: &[u8], component: ComponentType) -> u32 {
    match component {
        ComponentType::U8 => u32::from(e[0]),
        ComponentType::U16 => u32::from(u16::from_le_bytes([e[0], e[1]])),
        _ => u32_le(e),
    }
}

/// A vertex attribute strata reads, and the component types it may have:
/// glTF's own (floats; normalized unsigned bytes and shorts for texture
/// coordinates) and those `KHR_mesh_quantization` adds (Khronos, "glTF
/// extension registry": positions as bytes or shorts, normalized or not;
/// normals and tangents as normalized signed ones; texture coordinates as
/// any of the four, normalized or not). They are read whether or not a file
/// declares the extension: the component type says how to read them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Attribute {
    Position,
    Normal,
    Tangent,
    TexCoord(usize),
}

impl Attribute {
    /// The attribute's name in a primitive's `attributes`.
    pub(super) fn name(self) -> String {
        match self {
            Self::Position => "POSITION".into(),
            Self::Normal => "NORMAL".into(),
            Self::Tangent => "TANGENT".into(),
            Self::TexCoord(set) => format!("TEXCOORD_{set}"),
        }
    }

    fn dimensions(self) -> AccessorType {
        match self {
            Self::Position | Self::Normal => AccessorType::Vec3,
            Self::Tangent => AccessorType::Vec4,
            Self::TexCoord(_) => AccessorType::Vec2,
        }
    }

    fn accepts(self, component: ComponentType, normalized: bool) -> bool {
        use ComponentType::{F32, I16, I8, U16, U8};
        match (self, component) {
            (_, F32) => true,
            (Self::Position | Self::TexCoord(_), I8 | U8 | I16 | U16) => true,
            (Self::Normal | Self::Tangent, I8 | I16) => normalized,
            _ => false,
        }
    }
}

/// Component `k` of element `e`: a float as it is; an integer as its value,
/// or normalized as glTF says (n/255 and n/65535 unsigned, max(n/127, −1)
/// and max(n/32767, −1) signed).
fn decode(e: &[u8], component: ComponentType, k: usize, normalized: bool) -> f32 {
    let (value, scale, signed) = match component {
        ComponentType::I8 => (f32::from(e[k] as i8), 127.0, true),
        ComponentType::U8 => (f32::from(e[k]), 255.0, false),
        ComponentType::I16 => (
            f32::from(i16::from_le_bytes([e[2 * k], e[2 * k + 1]])),
            32767.0,
            true,
        ),
        ComponentType::U16 => (
            f32::from(u16::from_le_bytes([e[2 * k], e[2 * k + 1]])),
            65535.0,
            false,
        ),
        // Never an attribute's (`Attribute::accepts`); read as its value.
        ComponentType::U32 => (u32_le(&e[4 * k..]) as f32, u32::MAX as f32, false),
        ComponentType::F32 => {
            return f32::from_le_bytes([e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]])
        }
    };
    match (normalized, signed) {
        (false, _) => value,
        (true, false) => value / scale,
        (true, true) => (value / scale).max(-1.0),
    }
}

/// The most bytes of zeros an accessor without a bufferView may stand for
/// (glTF's sparse accessors over zeros): 2³⁰, 89 million `VEC3` floats, so
/// that a file cannot make the loader ask for more memory than it holds.
const MAX_ZERO_BYTES: u64 = 1 << 30;

/// The vector types an accessor decodes to, which must be finite.
trait FiniteValue: std::fmt::Display {
    fn finite(&self) -> bool;
}

impl FiniteValue for Vec3 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

impl FiniteValue for glam::Vec4 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

impl FiniteValue for Vec2 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;

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

    /// A file of one non-indexed triangle whose POSITION is accessor
    /// `position`.
    fn positions_of(b: &Builder, position: usize) -> InputResult<LoadedAsset> {
        let rest = format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":{position}}}}}]}}],"nodes":[{{"mesh":0}}]"#
        );
        load_json(b, &rest)
    }

    /// Little-endian f32 bytes of `values`.
    fn floats(values: &[[f32; 3]]) -> Vec<u8> {
        values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    #[test]
    fn sparse_accessors_replace_the_elements_they_name() {
        // Over a view: corner 1 of the triangle moved to (2, 0, 0), named
        // by an unsigned byte.
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        let indices = b.view(&[1]);
        let values = b.view(&floats(&[[2.0, 0.0, 0.0]]));
        let sparse = |view: &str| {
            format!(
                r#"{{{view}"componentType":5126,"count":3,"type":"VEC3","sparse":{{"count":1,
                   "indices":{{"bufferView":{indices},"componentType":5121}},
                   "values":{{"bufferView":{values}}}}}}}"#
            )
        };
        let over_view = b.accessor(sparse(r#""bufferView":0,"#));
        let asset = positions_of(&b, over_view).unwrap();
        assert_eq!(
            asset.meshes[0].positions,
            [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::Y]
        );
        // Over zeros (no bufferView): corners 1 and 2 set, by unsigned
        // shorts from a byte offset.
        let mut b = Builder::default();
        let indices = b.view(&[9, 9, 1, 0, 2, 0]);
        let values = b.view(&floats(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]));
        let zeros = b.accessor(format!(
            r#"{{"componentType":5126,"count":3,"type":"VEC3","sparse":{{"count":2,
               "indices":{{"bufferView":{indices},"byteOffset":2,"componentType":5123}},
               "values":{{"bufferView":{values}}}}}}}"#
        ));
        let asset = positions_of(&b, zeros).unwrap();
        assert_eq!(asset.meshes[0].positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    }

    #[test]
    fn sparse_accessors_that_reach_outside_are_errors_naming_the_part() {
        let sparse = |count: u64, index: u8, value_bytes: usize| {
            let mut b = Builder::default();
            b.positions(&TRIANGLE);
            let indices = b.view(&[index]);
            let values = b.view(&vec![0; value_bytes]);
            let position = b.accessor(format!(
                r#"{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","sparse":{{"count":{count},
                   "indices":{{"bufferView":{indices},"componentType":5121}},
                   "values":{{"bufferView":{values}}}}}}}"#
            ));
            positions_of(&b, position)
        };
        expect_error(
            sparse(1, 3, 12),
            "scene.gltf",
            "accessors[1].sparse.indices",
            "entry 0 is element 3, past the accessor's 3 elements",
        );
        expect_error(
            sparse(1, 0, 8),
            "scene.gltf",
            "accessors[1].sparse.values",
            "1 entries of 12 bytes from byteOffset 0 do not fit in bufferViews[2] (8 bytes)",
        );
        expect_error(
            sparse(2, 0, 24),
            "scene.gltf",
            "accessors[1].sparse.indices",
            "do not fit in bufferViews[1]",
        );
        // Zeros past what strata reads, and an accessor with neither.
        let mut b = Builder::default();
        let indices = b.view(&[0]);
        let values = b.view(&floats(&[[1.0, 0.0, 0.0]]));
        let huge = b.accessor(format!(
            r#"{{"componentType":5126,"count":1000000000,"type":"VEC3","sparse":{{"count":1,
               "indices":{{"bufferView":{indices},"componentType":5121}},
               "values":{{"bufferView":{values}}}}}}}"#
        ));
        expect_error(
            positions_of(&b, huge),
            "scene.gltf",
            "accessors[0]",
            "without a bufferView (zeros) are more than strata reads",
        );
    }

    /// Integers as glTF reads them (max(c/127, −1), c/255, max(c/32767, −1),
    /// c/65535 normalized; the value otherwise), worked out here in f64.
    fn dequantized(c: i64, component: u32, normalized: bool) -> f32 {
        let scale = match component {
            5120 => 127.0,
            5121 => 255.0,
            5122 => 32767.0,
            _ => 65535.0,
        };
        let v = c as f64;
        (if normalized { (v / scale).max(-1.0) } else { v }) as f32
    }

    /// `values` as little-endian integers of glTF componentType `component`.
    fn integers(values: &[i64], component: u32) -> Vec<u8> {
        values
            .iter()
            .flat_map(|&v| match component {
                5120 | 5121 => vec![v as u8],
                _ => (v as u16).to_le_bytes().to_vec(),
            })
            .collect()
    }

    /// A file of one triangle whose positions (and, where given, normals)
    /// are accessors 0 (and 1), placed by `node`, requiring
    /// KHR_mesh_quantization.
    fn quantized(b: &Builder, normals: bool, node: &str) -> InputResult<LoadedAsset> {
        let normals = if normals { r#","NORMAL":1"# } else { "" };
        let rest = format!(
            r#""extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],
               "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0{normals}}}}}]}}],"nodes":[{{"mesh":0{node}}}]"#
        );
        load_json(b, &rest)
    }

    #[test]
    fn quantized_positions_read_as_the_values_they_stand_for() {
        // Each component type's extremes and a value between, at every
        // corner; three corners of each type's values a triangle.
        let cases: [(u32, [i64; 9]); 4] = [
            (5120, [-128, -127, 0, 127, 1, -1, 64, -64, 100]),
            (5121, [0, 255, 1, 128, 254, 7, 200, 3, 99]),
            (5122, [-32768, -32767, 0, 32767, 1, -1, 12345, -20000, 2]),
            (5123, [0, 65535, 1, 32768, 65534, 7, 40000, 3, 999]),
        ];
        for (component, values) in cases {
            for normalized in [false, true] {
                let mut b = Builder::default();
                b.raw_accessor(&integers(&values, component), component, "VEC3", normalized);
                let asset = quantized(&b, false, "").unwrap();
                let got = &asset.meshes[0].positions;
                for (i, p) in got.iter().enumerate() {
                    for k in 0..3 {
                        let want = dequantized(values[3 * i + k], component, normalized);
                        assert_eq!(p[k], want, "{component} {normalized} corner {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_node_dequantizes_positions_as_gltfpack_writes_them() {
        // gltfpack's layout: unnormalized shorts, four to an element (the
        // fourth pads it to 8 bytes), scaled and moved by the node.
        let mut b = Builder::default();
        let shorts = [0, 0, 0, 0, 1000, 0, 0, 0, 0, 2000, -500, 0];
        let view = b.view(&integers(&shorts, 5122));
        b.views[view] = b.views[view].replace('}', r#","byteStride":8}"#);
        b.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5122,"count":3,"type":"VEC3"}}"#
        ));
        let node = r#","scale":[0.001,0.001,0.002],"translation":[5,0,-1]"#;
        let asset = quantized(&b, false, node).unwrap().into_baked();
        assert_corners(
            &asset.meshes[0],
            [[5.0, 0.0, -1.0], [6.0, 0.0, -1.0], [5.0, 2.0, -2.0]],
        );
    }

    #[test]
    fn quantized_normals_must_be_normalized_signed_integers() {
        for (component, normalized, error) in [
            (5120, true, None),
            (5122, true, None),
            (5120, false, Some("NORMAL cannot be I8 Vec3")),
            (5121, true, Some("NORMAL cannot be normalized U8 Vec3")),
            (5123, true, Some("NORMAL cannot be normalized U16 Vec3")),
        ] {
            let mut b = Builder::default();
            b.positions(&TRIANGLE);
            let values = [0, 0, 127, 0, 0, -128, 90, 0, 30];
            b.raw_accessor(&integers(&values, component), component, "VEC3", normalized);
            let result = quantized(&b, true, "");
            match error {
                Some(needle) => expect_error(result, "scene.gltf", "accessors[1]", needle),
                None => {
                    let normals = result.unwrap().meshes[0].normals.clone().unwrap().values;
                    // The loader keeps normals of unit length.
                    for (i, &n) in normals.iter().enumerate() {
                        let want = Vec3::from_array(std::array::from_fn(|k| {
                            dequantized(values[3 * i + k], component, true)
                        }));
                        assert_close(n, want.normalize());
                    }
                }
            }
        }
    }
}

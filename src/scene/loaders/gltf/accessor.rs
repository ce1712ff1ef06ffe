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
        let (view, view_bytes) = self.view(view_index, &location)?;
        let view_length = view_bytes.len() as u64;

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

    pub(super) fn read_vec3(&self, index: usize, what: &str) -> InputResult<Vec<Vec3>> {
        let (data, _) = self.accessor(index, what, |c, t| {
            c == ComponentType::F32 && t == AccessorType::Vec3
        })?;
        self.finite_elements(index, what, &data, |e| {
            Vec3::new(
                f32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                f32::from_le_bytes([e[4], e[5], e[6], e[7]]),
                f32::from_le_bytes([e[8], e[9], e[10], e[11]]),
            )
        })
    }

    /// Texture coordinates: `FLOAT`, or normalized `UNSIGNED_BYTE` or
    /// `UNSIGNED_SHORT` (read as n/255, n/65535), `VEC2`, as the glTF
    /// specification allows for `TEXCOORD_n`.
    /// A `VEC4` float accessor (glTF `TANGENT`), every value finite.
    pub(super) fn read_vec4(&self, index: usize, what: &str) -> InputResult<Vec<glam::Vec4>> {
        let (data, _) = self.accessor(index, what, |c, t| {
            c == ComponentType::F32 && t == AccessorType::Vec4
        })?;
        self.finite_elements(index, what, &data, |e| {
            let f = |k: usize| f32::from_le_bytes([e[k], e[k + 1], e[k + 2], e[k + 3]]);
            glam::Vec4::new(f(0), f(4), f(8), f(12))
        })
    }

    pub(super) fn read_uvs(&self, index: usize, what: &str) -> InputResult<Vec<Vec2>> {
        let (data, component) = self.accessor(index, what, |c, t| {
            matches!(
                c,
                ComponentType::F32 | ComponentType::U8 | ComponentType::U16
            ) && t == AccessorType::Vec2
        })?;
        let normalized = self.root.accessors.get(index).is_some_and(|a| a.normalized);
        if component != ComponentType::F32 && !normalized {
            return Err(self.error(
                format!("accessors[{index}]"),
                format!("{what} of {component:?} must be normalized"),
            ));
        }
        self.finite_elements(index, what, &data, |e| match component {
            ComponentType::U8 => Vec2::new(f32::from(e[0]), f32::from(e[1])) / 255.0,
            ComponentType::U16 => {
                Vec2::new(
                    f32::from(u16::from_le_bytes([e[0], e[1]])),
                    f32::from(u16::from_le_bytes([e[2], e[3]])),
                ) / 65535.0
            }
            _ => Vec2::new(
                f32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                f32::from_le_bytes([e[4], e[5], e[6], e[7]]),
            ),
        })
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
}

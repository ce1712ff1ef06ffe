//! One mesh primitive in its mesh's local space: its `POSITION`, `NORMAL`,
//! `TEXCOORD_n` (if its material has a base colour texture) and indices
//! read, and its mode's vertex order turned into triangles.

use super::super::strip::triangles_of_strip;
use super::accessor::Attribute;
use super::Loader;
use crate::error::InputResult;
use crate::geometry::{MeshNormals, MeshTangents, MeshUvs};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use ::gltf::json;
use glam::{Affine2, Mat2, Vec2};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

impl Loader<'_> {
    /// Read one primitive in its mesh's local space; `None` for point and
    /// line primitives.
    pub(super) fn primitive(
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
        let positions = self.read_vec3(position_accessor, Attribute::Position)?;
        let vertex_count = positions.len();
        if vertex_count > u32::MAX as usize {
            return Err(self.error(location, "more than 2³² vertices"));
        }
        let normals = match primitive.attributes.get(&Checked::Valid(Semantic::Normals)) {
            Some(accessor) => {
                let normals = self.read_vec3(accessor.value(), Attribute::Normal)?;
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
        let read = self.read_materials;
        let material = match primitive.material.map(|m| m.value()).filter(|_| read) {
            Some(m) if m >= asset.materials.len() => {
                return Err(self.error(
                    format!("{location}.material"),
                    format!("materials[{m}] does not exist"),
                ))
            }
            other => other,
        };
        // UVs only for a textured material, from the set its first map
        // names (KHR_texture_transform's texCoord overrides the texture's
        // own); a primitive without that set gets none.
        let source = material
            .filter(|&m| asset.materials[m].1.is_textured())
            .and_then(|m| self.root.materials.get(m))
            .and_then(super::material::uv_source);
        let transform = source.and_then(|(_, t, _)| t);
        let uv_set = source.map(|(set, _, _)| set);
        let uv_accessor = uv_set.and_then(|set| {
            primitive
                .attributes
                .get(&Checked::Valid(Semantic::TexCoords(set)))
                .map(|a| (set, a.value()))
        });
        let uvs = match uv_accessor {
            Some((set, accessor)) => {
                let mut values = self.read_uvs(accessor, set as usize)?;
                if let Some(t) = transform {
                    let m = material.unwrap_or_default();
                    let key = source.map_or("", |(_, _, key)| key);
                    let at = format!("materials[{m}].{key}.extensions.KHR_texture_transform");
                    let uv = uv_transform(t.offset.0, t.rotation.0, t.scale.0);
                    for v in &mut values {
                        *v = uv.transform_point2(*v);
                    }
                    if !(uv.is_finite() && values.iter().all(|v| v.is_finite())) {
                        return Err(self.error(at, "takes texture coordinates to infinity"));
                    }
                }
                if values.len() != vertex_count {
                    return Err(self.error(
                        location,
                        format!(
                            "TEXCOORD_{set} has {} elements but POSITION has {vertex_count}",
                            values.len()
                        ),
                    ));
                }
                Some(MeshUvs {
                    values,
                    indices: indices.clone(),
                })
            }
            None => None,
        };
        // Tangents only for a normal-mapped material; without them the
        // frame comes from the UVs at the hit.
        let mapped = material.is_some_and(|m| asset.materials[m].1.maps.normal.is_some());
        let tangents = match primitive
            .attributes
            .get(&Checked::Valid(Semantic::Tangents))
            .filter(|_| mapped && uvs.is_some())
        {
            Some(accessor) => {
                let values = self.read_vec4(accessor.value())?;
                if values.len() != vertex_count {
                    return Err(self.error(
                        location,
                        format!(
                            "TANGENT has {} elements but POSITION has {vertex_count}",
                            values.len()
                        ),
                    ));
                }
                Some(MeshTangents {
                    values,
                    indices: indices.clone(),
                })
            }
            None => None,
        };
        Ok(Some(LoadedMesh {
            tangents,
            name,
            positions,
            normals: normals.map(|values| MeshNormals {
                values,
                indices: indices.clone(),
            }),
            indices,
            material,
            uvs,
            mirrored: false,
            // glTF's positions are float32 (its spec's accessor types).
            exact_positions: None,
        }))
    }
}

/// `KHR_texture_transform`'s affine map of texture coordinates: scale,
/// then rotate by `rotation` radians, then offset. Its sense is that of the
/// extension's example (offset [0, 1], rotation π/2, scale ½ maps the unit
/// square onto the image's lower-left quadrant, turned clockwise):
/// u' = cos·sₓu + sin·s_y v + oₓ, v' = −sin·sₓu + cos·s_y v + o_y.
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Affine2 {
    let (sin, cos) = rotation.sin_cos();
    let linear = Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos))
        * Mat2::from_diagonal(Vec2::from(scale));
    Affine2::from_mat2_translation(linear, Vec2::from(offset))
}

/// Turn a primitive's vertex order into triangles as its mode says.
fn assemble_triangles(mode: Mode, order: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    let n = order.len();
    match mode {
        Mode::TriangleStrip => Ok(triangles_of_strip(order).collect()),
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

#[cfg(test)]
mod tests {
    use super::super::test_support::*;

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

    /// The extension's own example maps the unit square's corners onto the
    /// image's lower-left quadrant turned a quarter clockwise, and its
    /// texCoord picks the UV set.
    #[test]
    fn texture_transform_follows_the_extensions_example() {
        use crate::scene::loaders::test_files::png;
        let m = super::uv_transform([0.0, 1.0], std::f32::consts::FRAC_PI_2, [0.5, 0.5]);
        for (uv, expected) in [
            ([0.0, 0.0], [0.0, 1.0]),
            ([1.0, 0.0], [0.0, 0.5]),
            ([1.0, 1.0], [0.5, 0.5]),
            ([0.0, 1.0], [0.5, 1.0]),
        ] {
            let got = m.transform_point2(uv.into());
            assert!(got.abs_diff_eq(expected.into(), 1e-6), "{uv:?} -> {got}");
        }
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        b.vec2(&[[0.25, 0.25]; 3]);
        let dir = temp_dir("uv-transform");
        write(&dir, "t.png", &png(1, 1, &[[255, 255, 255]]));
        let with = |extension: &str| {
            let rest = format!(
                r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2}},"material":0}}]}}],
                "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0{extension}}}}}}}],
                "textures":[{{"source":0}}],"images":[{{"uri":"t.png"}}],"nodes":[{{"mesh":0}}]"#
            );
            let asset = load_gltf(&b.write_gltf(&dir, "uv", &rest)).unwrap();
            asset.meshes[0].uvs.clone().unwrap().values
        };
        let plain = with("");
        assert_eq!(plain[1], glam::Vec2::new(1.0, 0.0));
        let moved = with(
            r#","extensions":{"KHR_texture_transform":{"offset":[0,1],"rotation":1.5707964,"scale":[0.5,0.5]}}"#,
        );
        assert!(
            moved[1].abs_diff_eq(glam::Vec2::new(0.0, 0.5), 1e-6),
            "{moved:?}"
        );
        let other_set =
            with(r#","extensions":{"KHR_texture_transform":{"texCoord":1,"scale":[2,2]}}"#);
        assert_eq!(other_set[0], glam::Vec2::splat(0.5));
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
}

//! glTF metallic-roughness materials mapped onto strata's [`Material`], as
//! the table in the loader's documentation (`mod.rs`) says.

use super::texture::TextureCache;
use super::Loader;
use crate::error::InputResult;
use crate::material::{Maps, Material, NormalMap, NormalMapKind};
use crate::scene::asset::LoadedAsset;
use ::gltf::json;

/// Whether a glTF material has one kind of texture.
type HasTexture = fn(&::gltf::json::Material) -> bool;
use crate::texture::{Encoding, Textures};
use glam::Vec3;

impl Loader<'_> {
    /// Every material, in file order, and the base colour textures they
    /// name (decoded here, so a missing image is an error even if no
    /// primitive uses the material).
    pub(super) fn materials(&self) -> InputResult<(Vec<(String, Material)>, Textures)> {
        let mut materials = Vec::with_capacity(self.root.materials.len());
        let mut textures = TextureCache::default();
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
            let mut read = |index: Option<usize>, encoding, key: &str| match index {
                Some(index) => self
                    .texture(&mut textures, index, encoding, &format!("{location}.{key}"))
                    .map(Some),
                None => Ok(None),
            };
            let info_index =
                |info: &Option<json::texture::Info>| info.as_ref().map(|i| i.index.value());
            let diffuse_texture = read(
                info_index(&pbr.base_color_texture),
                Encoding::Srgb,
                "pbrMetallicRoughness.baseColorTexture",
            )?;
            let maps = Maps {
                metallic_roughness: read(
                    info_index(&pbr.metallic_roughness_texture),
                    Encoding::Linear,
                    "pbrMetallicRoughness.metallicRoughnessTexture",
                )?,
                emission: read(
                    info_index(&m.emissive_texture),
                    Encoding::Srgb,
                    "emissiveTexture",
                )?,
                normal: match &m.normal_texture {
                    Some(n) => {
                        if !n.scale.is_finite() {
                            return Err(self.error(
                                format!("{location}.normalTexture.scale"),
                                "must be finite",
                            ));
                        }
                        read(Some(n.index.value()), Encoding::Linear, "normalTexture")?.map(
                            |texture| NormalMap {
                                texture,
                                kind: NormalMapKind::Normal,
                                scale: n.scale,
                            },
                        )
                    }
                    None => None,
                },
            };
            let name = m.name.clone().unwrap_or_else(|| format!("material{i}"));
            let base = Vec3::new(base[0], base[1], base[2]);
            let material = Material {
                diffuse_texture,
                maps,
                ..Material::metallic_roughness(base, metallic, roughness, emission)
            };
            materials.push((name, material));
        }
        Ok((materials, textures.textures))
    }

    /// What of a material's textures is not read: occlusion maps (Cycles
    /// ignores them too: light that is computed needs no baked shadow), a
    /// map whose `texCoord` is not the set the mesh's coordinates come from
    /// (one set a mesh: [`uv_source`]'s), and `KHR_texture_transform` on
    /// any map but the one the coordinates come from. A warning for each
    /// kind, naming the first material that has one and counting the
    /// others, so that a model does not lose its detail unsaid.
    pub(super) fn warn_of_unread_textures(&self, asset: &mut LoadedAsset) {
        let materials = &self.root.materials;
        let kinds: [(&str, &str, HasTexture); 3] = [
            (
                "occlusionTexture",
                "not read: this occlusion texture{more} is ignored (light is computed, not \
                 baked); the material's factors apply alone",
                |m| m.occlusion_texture.is_some(),
            ),
            (
                "texCoord",
                "not read: a map of this material{more} names another TEXCOORD set than its \
                 first map; every map reads the first one's",
                |m| {
                    let sets = map_sets(m);
                    sets.iter().any(|&(s, _, _)| s != sets[0].0)
                },
            ),
            (
                "KHR_texture_transform",
                "not read: a map of this material{more} has its own texture transform; every \
                 map reads the coordinates of its first map, moved by that map's transform alone",
                |m| map_sets(m).iter().skip(1).any(|&(_, moved, _)| moved),
            ),
        ];
        for (key, what, has) in kinds {
            let with: Vec<usize> = (0..materials.len())
                .filter(|&i| has(&materials[i]))
                .collect();
            let Some(&first) = with.first() else {
                continue;
            };
            let more = match with.len() - 1 {
                0 => String::new(),
                1 => " (and 1 more material)".to_string(),
                n => format!(" (and {n} more materials)"),
            };
            asset.warnings.push(self.error(
                format!("materials[{first}].{key}"),
                what.replace("{more}", &more),
            ));
        }
    }
}

/// Every map of material `m` in the order its coordinates are chosen
/// (base colour, metallic-roughness, emissive, normal): its `texCoord`,
/// whether it has a texture transform (or other extension), and its key.
fn map_sets(m: &json::Material) -> Vec<(u32, bool, &'static str)> {
    let pbr = &m.pbr_metallic_roughness;
    let info = |i: &Option<json::texture::Info>, key| {
        i.as_ref().map(|i| {
            let transform = i
                .extensions
                .as_ref()
                .and_then(|e| e.texture_transform.as_ref());
            (
                transform.and_then(|t| t.tex_coord).unwrap_or(i.tex_coord),
                transform.is_some(),
                key,
            )
        })
    };
    [
        info(
            &pbr.base_color_texture,
            "pbrMetallicRoughness.baseColorTexture",
        ),
        info(
            &pbr.metallic_roughness_texture,
            "pbrMetallicRoughness.metallicRoughnessTexture",
        ),
        info(&m.emissive_texture, "emissiveTexture"),
        m.normal_texture
            .as_ref()
            .map(|n| (n.tex_coord, n.extensions.is_some(), "normalTexture")),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The texture info whose `texCoord` (and `KHR_texture_transform`) give a
/// mesh of material `m` its one set of coordinates: the first map of
/// [`map_sets`]'s order, and its key; the normal map has no transform
/// read.
pub(super) fn uv_source(
    m: &json::Material,
) -> Option<(
    u32,
    Option<&json::extensions::texture::TextureTransform>,
    &'static str,
)> {
    let pbr = &m.pbr_metallic_roughness;
    let first_info = [
        (
            &pbr.base_color_texture,
            "pbrMetallicRoughness.baseColorTexture",
        ),
        (
            &pbr.metallic_roughness_texture,
            "pbrMetallicRoughness.metallicRoughnessTexture",
        ),
        (&m.emissive_texture, "emissiveTexture"),
    ]
    .into_iter()
    .find_map(|(i, key)| i.as_ref().map(|i| (i, key)));
    match first_info {
        Some((i, key)) => {
            let transform = i
                .extensions
                .as_ref()
                .and_then(|e| e.texture_transform.as_ref());
            Some((
                transform.and_then(|t| t.tex_coord).unwrap_or(i.tex_coord),
                transform,
                key,
            ))
        }
        None => m
            .normal_texture
            .as_ref()
            .map(|n| (n.tex_coord, None, "normalTexture")),
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;

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

        let pbr = plastic.pbr.expect("a glTF material is metallic-roughness");
        assert_close(pbr.base_color, Vec3::new(0.5, 0.25, 1.0));
        assert_eq!((pbr.metallic, pbr.roughness), (0.0, 1.0));

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
    fn textures_not_read_are_warned_of_once_per_kind() {
        let mut b = triangle_builder();
        b.u8s(&[2, 1, 0]);
        let rest = format!(
            r#""materials":[
                {{"occlusionTexture":{{"index":0}}}},
                {{"occlusionTexture":{{"index":0}},"emissiveTexture":{{"index":0,"texCoord":1}},
                  "pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}},
                {{"pbrMetallicRoughness":{{"metallicRoughnessTexture":{{"index":0}}}},"normalTexture":{{"index":0}}}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
            "nodes":[{{"mesh":0}}],
            "textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{}"}}]"#,
            encode_base64(&crate::scene::loaders::test_files::png(1, 1, &[[1, 2, 3]]))
        );
        let asset = load_json(&b, &rest).unwrap();
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(
            said[0].contains("materials[0].occlusionTexture: not read: this occlusion texture (and 1 more material) is ignored"),
            "{said:?}"
        );
        assert!(said[1].contains("materials[1].texCoord"), "{said:?}");
        // The maps that are read: one image, as colour and as data.
        let m = asset.materials[2].1;
        let (mr, normal) = (m.maps.metallic_roughness.unwrap(), m.maps.normal.unwrap());
        assert_eq!(mr, normal.texture, "one texture, both read as data");
        assert_eq!(normal.scale, 1.0);
        let colour = asset.materials[1].1.diffuse_texture.unwrap();
        assert_ne!(colour, mr);
        use crate::texture::Encoding;
        assert_eq!(
            asset.textures.textures[colour as usize].encoding,
            Encoding::Srgb
        );
        assert_eq!(
            asset.textures.textures[mr as usize].encoding,
            Encoding::Linear
        );
        assert_eq!(asset.textures.images.len(), 1);
    }
}

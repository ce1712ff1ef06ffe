//! glTF metallic-roughness materials mapped onto strata's [`Material`], as
//! the table in the loader's documentation (`mod.rs`) says.

use super::texture::TextureCache;
use super::Loader;
use crate::error::InputResult;
use crate::material::Material;
use crate::scene::asset::LoadedAsset;

/// Whether a glTF material has one kind of texture.
type HasTexture = fn(&::gltf::json::Material) -> bool;
use crate::texture::Textures;
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
            let diffuse_texture = match &pbr.base_color_texture {
                Some(info) => Some(self.texture(
                    &mut textures,
                    info.index.value(),
                    &format!("{location}.pbrMetallicRoughness.baseColorTexture"),
                )?),
                None => None,
            };
            let name = m.name.clone().unwrap_or_else(|| format!("material{i}"));
            let base = Vec3::new(base[0], base[1], base[2]);
            let material = Material {
                diffuse_texture,
                ..Material::metallic_roughness(base, metallic, roughness, emission)
            };
            materials.push((name, material));
        }
        Ok((materials, textures.textures))
    }

    /// The textures no renderer here reads (metallic-roughness, normal,
    /// emissive and occlusion maps): a warning for each kind, naming the
    /// first material that has one and counting the others, so that a
    /// model does not lose its detail unsaid.
    pub(super) fn warn_of_unread_textures(&self, asset: &mut LoadedAsset) {
        let materials = &self.root.materials;
        let kinds: [(&str, &str, HasTexture); 4] = [
            (
                "pbrMetallicRoughness.metallicRoughnessTexture",
                "metallic-roughness texture",
                |m| {
                    m.pbr_metallic_roughness
                        .metallic_roughness_texture
                        .is_some()
                },
            ),
            ("normalTexture", "normal map", |m| {
                m.normal_texture.is_some()
            }),
            ("emissiveTexture", "emissive texture", |m| {
                m.emissive_texture.is_some()
            }),
            ("occlusionTexture", "occlusion texture", |m| {
                m.occlusion_texture.is_some()
            }),
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
                format!(
                    "not read: this {what}{more} is ignored; the material's factors apply alone"
                ),
            ));
        }
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
        let rest = r#""materials":[
                {"normalTexture":{"index":0}},
                {"normalTexture":{"index":0},"emissiveTexture":{"index":0}},
                {"pbrMetallicRoughness":{"metallicRoughnessTexture":{"index":0}}}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
            "nodes":[{"mesh":0}],
            "textures":[{"source":0}],"images":[{"uri":"never-read.png"}]"#;
        let asset = load_json(&b, rest).unwrap();
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(said.len(), 3, "{said:?}");
        assert!(
            said[0].contains("materials[2].pbrMetallicRoughness.metallicRoughnessTexture"),
            "{said:?}"
        );
        assert!(said[1].contains("materials[0].normalTexture: not read: this normal map (and 1 more material) is ignored"), "{said:?}");
        assert!(said[2].contains("materials[1].emissiveTexture"), "{said:?}");
    }
}

//! `[materials.NAME]` tables, and the materials mesh files bring.

use super::Compiler;
use crate::error::InputResult;
use crate::material::Material;
use crate::scene::description::MaterialDesc;

impl Compiler<'_> {
    pub(super) fn add_material(&mut self, name: String, m: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.materials.push(m);
        self.material_ids.insert(name, id);
        id
    }

    pub(super) fn material(&self, m: &MaterialDesc, key: &str) -> InputResult<Material> {
        let k = |field: &str| format!("{key}.{field}");
        if m.base_color.is_some() || m.metallic.is_some() || m.roughness.is_some() {
            return self.metallic_roughness(m, key);
        }
        let [diffuse, specular, emission] = [
            (m.diffuse, "diffuse"),
            (m.specular, "specular"),
            (m.emission, "emission"),
        ]
        .map(|(c, name)| self.colour(c, &k(name)));
        let [shininess, reflectivity, glossiness, transparency] = [
            (m.shininess, "shininess"),
            (m.reflectivity, "reflectivity"),
            (m.glossiness, "glossiness"),
            (m.transparency, "transparency"),
        ]
        .map(|(x, name)| self.non_negative(x, &k(name)));
        let ior = self.positive(m.ior, &k("ior"));
        super::validate::all_passed([
            diffuse.as_ref().err(),
            specular.as_ref().err(),
            emission.as_ref().err(),
            shininess.as_ref().err(),
            reflectivity.as_ref().err(),
            glossiness.as_ref().err(),
            transparency.as_ref().err(),
            ior.as_ref().err(),
        ])?;
        Ok(Material {
            diffuse: diffuse?,
            specular: specular?,
            shininess: shininess?,
            reflectivity: reflectivity?,
            glossiness: glossiness?,
            transparency: transparency?,
            ior: ior?,
            fresnel: m.fresnel,
            emission: emission?,
            one_sided: false,
            diffuse_texture: None,
            pbr: None,
            maps: crate::material::Maps::default(),
        })
    }

    /// A material written with `base_color`, `metallic` and `roughness`
    /// (glTF's model), which takes no Phong key but `emission`.
    fn metallic_roughness(&self, m: &MaterialDesc, key: &str) -> InputResult<Material> {
        let k = |field: &str| format!("{key}.{field}");
        const PHONG: [&str; 8] = [
            "diffuse",
            "specular",
            "shininess",
            "reflectivity",
            "glossiness",
            "transparency",
            "ior",
            "fresnel",
        ];
        if let Some(phong) = PHONG.iter().find(|f| self.source.contains(&k(f))) {
            return Err(self.err(
                &k(phong),
                "a material with base_color, metallic or roughness is glTF's \
                 metallic-roughness model, which takes no Phong key (diffuse, specular, \
                 shininess, reflectivity, glossiness, transparency, ior, fresnel); write \
                 one model or the other",
            ));
        }
        let base = self.colour(m.base_color.unwrap_or([0.8; 3]), &k("base_color"))?;
        if base.max_element() > 1.0 {
            return Err(self.err(
                &k("base_color"),
                format!(
                    "must be a reflectance between 0 and 1, got {}",
                    super::validate::written(base)
                ),
            ));
        }
        let unit = |x: Option<f32>, field: &str, default: f32| {
            let x = x.unwrap_or(default);
            if (0.0..=1.0).contains(&x) {
                Ok(x)
            } else {
                Err(self.err(&k(field), format!("must be between 0 and 1, got {x}")))
            }
        };
        let (metallic, roughness) = (
            unit(m.metallic, "metallic", 0.0),
            unit(m.roughness, "roughness", 0.5),
        );
        let emission = self.colour(m.emission, &k("emission"));
        super::validate::all_passed([
            metallic.as_ref().err(),
            roughness.as_ref().err(),
            emission.as_ref().err(),
        ])?;
        let (metallic, roughness, emission) = (metallic?, roughness?, emission?);
        Ok(Material::metallic_roughness(
            base, metallic, roughness, emission,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{compiled, rejected};
    use crate::material::Material;
    use glam::Vec3;

    #[test]
    fn named_materials_keep_their_values_and_unset_fields_their_defaults() {
        let s = compiled(
            r#"
[materials.mirror]
reflectivity = 0.9
[materials.red]
diffuse = [0.7, 0.1, 0.1]
[[objects]]
sphere = { radius = 1.0 }
material = "red"
"#,
        );
        // Material 0 is the default; named ones follow in name order.
        assert_eq!(s.materials[0], Material::default());
        let red = s.materials[s.geometry.shapes[0].material as usize];
        assert_eq!(red.diffuse, Vec3::new(0.7, 0.1, 0.1));
        assert_eq!(red.ior, Material::default().ior);
        assert!(s.materials.iter().any(|m| m.reflectivity == 0.9));
        let e = rejected("[[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"blue\"");
        assert_eq!(e.location, "objects[0].material");
        assert!(e.message.contains("unknown material 'blue'"), "{e}");
    }

    #[test]
    fn metallic_roughness_keys_make_that_model_and_refuse_phong_keys() {
        let s = compiled(
            "[materials.gold]\nbase_color = [1.0, 0.77, 0.34]\nmetallic = 1.0\nroughness = 0.3\n\
             [[objects]]\nsphere = { radius = 1.0 }\nmaterial = \"gold\"\n",
        );
        let gold = s.materials[s.geometry.shapes[0].material as usize];
        let pbr = gold.pbr.expect("a metallic-roughness material");
        assert_eq!(pbr.base_color, Vec3::new(1.0, 0.77, 0.34));
        assert_eq!((pbr.metallic, pbr.roughness), (1.0, 0.3));
        // Its Phong stand-in, for the distribution integrator.
        assert_eq!(gold.reflectivity, 1.0);
        for (text, key, needle) in [
            (
                "roughness = 0.2\ndiffuse = 0.5",
                "materials.m.diffuse",
                "takes no Phong key",
            ),
            ("metallic = 1.5", "materials.m.metallic", "between 0 and 1"),
            (
                "base_color = [2.0, 0.5, 0.5]",
                "materials.m.base_color",
                "between 0 and 1",
            ),
        ] {
            let e = rejected(&format!(
                "[materials.m]\n{text}\n[[objects]]\nsphere = {{ radius = 1.0 }}\nmaterial = \"m\""
            ));
            assert_eq!(e.location, key, "{e}");
            assert!(e.message.contains(needle), "{e}");
        }
    }
}

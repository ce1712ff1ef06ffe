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
        Ok(Material {
            diffuse: self.colour(m.diffuse, &k("diffuse"))?,
            specular: self.colour(m.specular, &k("specular"))?,
            shininess: self.non_negative(m.shininess, &k("shininess"))?,
            reflectivity: self.non_negative(m.reflectivity, &k("reflectivity"))?,
            glossiness: self.non_negative(m.glossiness, &k("glossiness"))?,
            transparency: self.non_negative(m.transparency, &k("transparency"))?,
            ior: self.positive(m.ior, &k("ior"))?,
            fresnel: m.fresnel,
            emission: self.colour(m.emission, &k("emission"))?,
            one_sided: false,
            diffuse_texture: None,
        })
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
}

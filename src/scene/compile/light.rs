//! `[[lights]]`: each light is validated and added; area lights are also
//! visible, one-sided emitting primitives that their own shadow rays skip.

use super::Compiler;
use crate::error::InputResult;
use crate::geometry::{AnalyticPrim, Shape, NO_TRANSFORM};
use crate::light::Light;
use crate::material::Material;
use crate::scene::description::LightDesc;
use crate::shape::disk::Disk;
use crate::shape::rect::Rect;
use crate::shape::sphere::Sphere;
use glam::Vec3;

impl Compiler {
    /// Validate a light and add it; area lights also become visible,
    /// one-sided emitting primitives.
    pub(super) fn light(&mut self, l: &LightDesc, key: &str) -> InputResult<()> {
        let k = |field: &str| format!("{key}.{field}");
        let light = match l {
            LightDesc::Point {
                position,
                intensity,
            } => Light::Point {
                position: self.v3(*position, &k("position"))?,
                intensity: self.colour(*intensity, &k("intensity"))?,
            },
            LightDesc::Directional {
                direction,
                irradiance,
            } => Light::Directional {
                direction: self.direction(*direction, &k("direction"))?,
                irradiance: self.colour(*irradiance, &k("irradiance"))?,
            },
            LightDesc::Rect {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                let corner = self.v3(*corner, &k("corner"))?;
                let eu = self.v3(*edge_u, &k("edge_u"))?;
                let ev = self.v3(*edge_v, &k("edge_v"))?;
                let rect = Rect::new(corner, eu, ev).ok_or_else(|| {
                    self.err(key, "edge_u and edge_v must be non-zero and not parallel")
                })?;
                let radiance = self.colour(*radiance, &k("radiance"))?;
                let prim = self.emitter(Shape::Rect(rect), radiance, true);
                Light::Rect {
                    rect,
                    radiance,
                    prim,
                }
            }
            LightDesc::Disk {
                center,
                normal,
                radius,
                radiance,
            } => {
                let disk = Disk::new(
                    self.v3(*center, &k("center"))?,
                    self.direction(*normal, &k("normal"))?,
                    self.positive(*radius, &k("radius"))?,
                );
                let radiance = self.colour(*radiance, &k("radiance"))?;
                let prim = self.emitter(Shape::Disk(disk), radiance, true);
                Light::Disk {
                    disk,
                    radiance,
                    prim,
                }
            }
            LightDesc::Sphere {
                center,
                radius,
                radiance,
            } => {
                let center = self.v3(*center, &k("center"))?;
                let radius = self.positive(*radius, &k("radius"))?;
                let radiance = self.colour(*radiance, &k("radiance"))?;
                let prim = self.emitter(Shape::Sphere(Sphere { center, radius }), radiance, false);
                Light::Sphere {
                    center,
                    radius,
                    radiance,
                    prim,
                }
            }
        };
        self.lights.push(light);
        Ok(())
    }

    /// Add the visible surface of an area light: an emitting primitive that
    /// reflects nothing. Returns its index among the analytic shapes; the
    /// global primitive id is fixed up once the triangle count is known.
    pub(super) fn emitter(&mut self, shape: Shape, radiance: Vec3, one_sided: bool) -> u32 {
        let material = Material {
            diffuse: Vec3::ZERO,
            emission: radiance,
            one_sided,
            ..Material::default()
        };
        self.materials.push(material);
        let material = self.materials.len() as u32 - 1;
        self.shapes.push(AnalyticPrim {
            shape,
            transform: NO_TRANSFORM,
            material,
        });
        self.shapes.len() as u32 - 1
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{compiled, rejected};
    use crate::light::Light;

    #[test]
    fn area_lights_become_emitters_their_shadow_rays_skip() {
        let s = compiled(
            r#"
[[lights]]
type = "rect"
corner = [-0.5, 3.0, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
radiance = [5.0, 5.0, 5.0]
[[lights]]
type = "sphere"
center = [0.0, 2.0, 0.0]
radius = 0.25
radiance = [1.0, 2.0, 3.0]
[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = [10.0, 10.0, 10.0]
[[objects]]
triangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }
"#,
        );
        let g = &s.geometry;
        assert_eq!(s.lights.len(), 3);
        assert_eq!(s.lights[2].prim(), None, "a point light has no surface");
        for (light, one_sided) in [(&s.lights[0], true), (&s.lights[1], false)] {
            // The light's primitive id counts after the scene's triangle.
            let prim = light.prim().unwrap();
            assert!(prim >= g.triangle_count);
            let shape = &g.shapes[(prim - g.triangle_count) as usize];
            let m = &s.materials[shape.material as usize];
            assert!(m.is_emissive() && m.diffuse == glam::Vec3::ZERO);
            assert_eq!(m.one_sided, one_sided);
        }
        if let Light::Sphere { radiance, .. } = s.lights[1] {
            assert_eq!(radiance, glam::Vec3::new(1.0, 2.0, 3.0));
        }
        let e = rejected(
            "[[lights]]\ntype = \"rect\"\ncorner = [0.0, 0.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [2.0, 0.0, 0.0]\nradiance = [1.0, 1.0, 1.0]",
        );
        assert_eq!(e.location, "lights[0]");
        assert!(e.message.contains("parallel"), "{e}");
    }
}

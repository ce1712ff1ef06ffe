//! `[[lights]]`: each light is validated and added; area lights are also
//! visible, one-sided emitting primitives that their own shadow rays skip.

use super::Compiler;
use crate::error::{io_message, InputError, InputResult};
use crate::geometry::{AnalyticPrim, Shape, NO_TRANSFORM};
use crate::light::environment::{Emission, EnvMap, Environment};
use crate::light::Light;
use crate::material::Material;
use crate::math::Aabb;
use crate::scene::description::{LightDesc, LightType, V3};
use crate::scene::RenderSettings;
use crate::shape::disk::Disk;
use crate::shape::plane::Plane;
use crate::shape::rect::Rect;
use crate::shape::sphere::Sphere;
use glam::{Mat3, Vec3};
use std::sync::Arc;

impl Compiler<'_> {
    /// Validate a light and add it; area lights also become visible,
    /// one-sided emitting primitives.
    pub(super) fn light(&mut self, l: &LightDesc, key: &str) -> InputResult<()> {
        let k = |field: &str| format!("{key}.{field}");
        let article = if l.kind == LightType::Environment {
            "an"
        } else {
            "a"
        };
        let what = format!("{article} {} light", l.kind);
        let given = [
            ("position", l.position.is_some()),
            ("intensity", l.intensity.is_some()),
            ("direction", l.direction.is_some()),
            ("irradiance", l.irradiance.is_some()),
            ("corner", l.corner.is_some()),
            ("edge_u", l.edge_u.is_some()),
            ("edge_v", l.edge_v.is_some()),
            ("center", l.center.is_some()),
            ("normal", l.normal.is_some()),
            ("radius", l.radius.is_some()),
            ("radiance", l.radiance.is_some()),
            ("map", l.map.is_some()),
            ("scale", l.scale.is_some()),
            ("rotate", l.rotate.is_some()),
            ("look_at", l.look_at.is_some()),
            ("inner_angle", l.inner_angle.is_some()),
            ("outer_angle", l.outer_angle.is_some()),
        ];
        let takes: &[&str] = match l.kind {
            LightType::Point => &["position", "intensity"],
            LightType::Spot => &[
                "position",
                "direction",
                "look_at",
                "intensity",
                "inner_angle",
                "outer_angle",
            ],
            // `intensity` is accepted as another name for a directional
            // light's irradiance.
            LightType::Directional => &["direction", "irradiance", "intensity"],
            LightType::Rect => &["corner", "edge_u", "edge_v", "radiance"],
            LightType::Disk => &["center", "normal", "radius", "radiance"],
            LightType::Sphere => &["center", "radius", "radiance"],
            LightType::Environment => &["radiance", "map", "scale", "rotate"],
        };
        self.only(key, &what, &given, takes)?;
        let need = |value: Option<V3>, name: &str| self.need(value, key, name, &what);
        let light = match l.kind {
            LightType::Point => Light::Point {
                position: self.v3(need(l.position, "position")?, &k("position"))?,
                intensity: self.colour(need(l.intensity, "intensity")?, &k("intensity"))?,
            },
            LightType::Spot => self.spot(l, key)?,
            LightType::Directional => {
                let (value, name) = match (l.irradiance, l.intensity) {
                    (Some(_), Some(_)) => {
                        return Err(self.err(key, "give irradiance or intensity, not both"))
                    }
                    (None, Some(v)) => (v, "intensity"),
                    (irradiance, None) => (need(irradiance, "irradiance")?, "irradiance"),
                };
                Light::Directional {
                    direction: self.direction(need(l.direction, "direction")?, &k("direction"))?,
                    irradiance: self.colour(value, &k(name))?,
                }
            }
            LightType::Rect => {
                let corner = self.v3(need(l.corner, "corner")?, &k("corner"))?;
                let eu = self.v3(need(l.edge_u, "edge_u")?, &k("edge_u"))?;
                let ev = self.v3(need(l.edge_v, "edge_v")?, &k("edge_v"))?;
                let rect = Rect::new(corner, eu, ev).ok_or_else(|| {
                    self.err(key, "edge_u and edge_v must be non-zero and not parallel")
                })?;
                let radiance = self.colour(need(l.radiance, "radiance")?, &k("radiance"))?;
                let prim = self.emitter(Shape::Rect(rect), radiance, true);
                Light::Rect {
                    rect,
                    radiance,
                    prim,
                }
            }
            LightType::Disk => {
                let disk = Disk::new(
                    self.v3(need(l.center, "center")?, &k("center"))?,
                    self.direction(need(l.normal, "normal")?, &k("normal"))?,
                    self.positive(self.need(l.radius, key, "radius", &what)?, &k("radius"))?,
                );
                let radiance = self.colour(need(l.radiance, "radiance")?, &k("radiance"))?;
                let prim = self.emitter(Shape::Disk(disk), radiance, true);
                Light::Disk {
                    disk,
                    radiance,
                    prim,
                }
            }
            LightType::Sphere => {
                let center = self.v3(need(l.center, "center")?, &k("center"))?;
                let radius =
                    self.positive(self.need(l.radius, key, "radius", &what)?, &k("radius"))?;
                let radiance = self.colour(need(l.radiance, "radiance")?, &k("radiance"))?;
                let prim = self.emitter(Shape::Sphere(Sphere { center, radius }), radiance, false);
                Light::Sphere {
                    center,
                    radius,
                    radiance,
                    prim,
                }
            }
            LightType::Environment => Light::Environment(self.environment(l, key)?),
        };
        self.lights.push(light);
        Ok(())
    }

    /// An environment light's emission and rotation; its map, if it has
    /// one, read relative to the scene file. A scene has at most one.
    fn environment(&self, l: &LightDesc, key: &str) -> InputResult<Environment> {
        let k = |field: &str| format!("{key}.{field}");
        if self.lights.iter().any(|l| l.environment().is_some()) {
            return Err(self.err(key, "a scene takes one environment light; this is a second"));
        }
        let scale = match l.scale {
            Some(s) => self.colour(s, &k("scale"))?,
            None => Vec3::ONE,
        };
        let to_world = match l.rotate {
            Some([x, y, z, deg]) => {
                let axis = self.direction([x, y, z], &k("rotate"))?;
                Mat3::from_axis_angle(axis, self.finite(deg, &k("rotate"))?.to_radians())
            }
            None => Mat3::IDENTITY,
        };
        let emission = match (l.radiance, &l.map) {
            (Some(_), Some(_)) => return Err(self.err(key, "give radiance or map, not both")),
            (None, None) => {
                return Err(self.err(key, "an environment light needs `radiance` or `map`"))
            }
            (Some(radiance), None) => {
                Emission::Constant(self.colour(radiance, &k("radiance"))? * scale)
            }
            (None, Some(file)) => {
                let path = self.base_dir.join(file);
                let bytes = std::fs::read(&path).map_err(|e| {
                    let message = format!("cannot read '{}': {}", path.display(), io_message(&e));
                    self.err(&k("map"), message)
                })?;
                let map = EnvMap::decode(&bytes, scale)
                    .map_err(|e| self.err(&k("map"), format!("'{}': {e}", path.display())))?;
                Emission::Map(Arc::new(map))
            }
        };
        Ok(Environment { emission, to_world })
    }

    /// What rays that hit nothing see is said once: by an environment
    /// light, or by `render.background`, not both.
    pub(super) fn check_background(&self, settings: &RenderSettings) -> InputResult<()> {
        let environment = self.lights.iter().any(|l| l.environment().is_some());
        if environment && settings.background != Vec3::ZERO {
            return Err(self.err(
                "render.background",
                "rays that hit nothing see the environment light; drop the background or the light",
            ));
        }
        Ok(())
    }

    /// A `spot` light: its axis from `direction` or `look_at` (one of
    /// them), its half-angles in degrees (glTF's defaults, 0 and 45), with
    /// 0 ≤ inner ≤ outer ≤ 180 and outer > 0.
    fn spot(&self, l: &LightDesc, key: &str) -> InputResult<Light> {
        let k = |field: &str| format!("{key}.{field}");
        let what = "a spot light";
        let position = self.v3(
            self.need(l.position, key, "position", what)?,
            &k("position"),
        )?;
        let direction = match (l.direction, l.look_at) {
            (Some(_), Some(_)) => return Err(self.err(key, "give direction or look_at, not both")),
            (Some(d), None) => self.direction(d, &k("direction"))?,
            (None, Some(target)) => {
                let to = self.v3(target, &k("look_at"))? - position;
                let d = to.normalize_or_zero();
                if d == Vec3::ZERO || !d.is_finite() {
                    return Err(self.err(&k("look_at"), "equals the light's position"));
                }
                d
            }
            (None, None) => {
                return Err(self.err(key, "a spot light needs `direction` or `look_at`"))
            }
        };
        let intensity = self.colour(
            self.need(l.intensity, key, "intensity", what)?,
            &k("intensity"),
        )?;
        let inner = self.finite(l.inner_angle.unwrap_or(0.0), &k("inner_angle"))?;
        let outer = self.finite(l.outer_angle.unwrap_or(45.0), &k("outer_angle"))?;
        if !(outer > 0.0 && outer <= 180.0) {
            return Err(self.err(
                &k("outer_angle"),
                format!("must be more than 0 and at most 180 degrees, got {outer}"),
            ));
        }
        if !(0.0..=outer).contains(&inner) {
            return Err(self.err(
                &k("inner_angle"),
                format!("must be between 0 and outer_angle ({outer}) degrees, got {inner}"),
            ));
        }
        Ok(Light::Spot {
            position,
            direction,
            intensity,
            cos_inner: inner.to_radians().cos(),
            cos_outer: outer.to_radians().cos(),
        })
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

/// Where a light can send light, as far as an object's box can tell.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reach {
    /// Every direction: point, sphere, directional and environment lights.
    Everywhere,
    /// The open half-space in front of a one-sided area light.
    Front { point: Vec3, normal: Vec3 },
    /// A spot light's cone: its apex, unit axis and half-angle (radians).
    Cone { apex: Vec3, axis: Vec3, half: f32 },
}

impl Reach {
    fn of(light: &Light) -> Reach {
        match light {
            Light::Rect { rect, .. } => Reach::Front {
                point: rect.corner,
                normal: rect.normal,
            },
            Light::Disk { disk, .. } => Reach::Front {
                point: disk.center,
                normal: disk.frame.z,
            },
            Light::Spot {
                position,
                direction,
                cos_outer,
                ..
            } => Reach::Cone {
                apex: *position,
                axis: *direction,
                half: cos_outer.clamp(-1.0, 1.0).acos(),
            },
            _ => Reach::Everywhere,
        }
    }

    /// Whether some of `b` may lie where the light shines. Conservative:
    /// a spot's cone is tested against the box's bounding sphere, and
    /// anything not finite counts as reached.
    fn reaches_box(&self, b: &Aabb) -> bool {
        match *self {
            Reach::Everywhere => true,
            Reach::Front { point, normal } => {
                // The box's farthest corner along the normal.
                let far = (b.min - point) * normal;
                let far = far.max((b.max - point) * normal);
                !(far.x + far.y + far.z <= 0.0)
            }
            Reach::Cone { apex, axis, half } => {
                let to = b.center() - apex;
                let (d, r) = (to.length(), 0.5 * b.diagonal().length());
                if !(d > r) {
                    return true;
                }
                let off_axis = (axis.dot(to) / d).clamp(-1.0, 1.0).acos();
                !(off_axis - (r / d).asin() >= half)
            }
        }
    }

    /// Whether the light shines on some of an infinite plane.
    fn reaches_plane(&self, plane: &Plane) -> bool {
        let (q, m) = (plane.point, plane.normal);
        match *self {
            Reach::Everywhere => true,
            // A plane not parallel to the light's crosses its front.
            Reach::Front { point, normal } => {
                normal.cross(m).length() > 1e-6 || !(normal.dot(q - point) <= 0.0)
            }
            Reach::Cone { apex, axis, half } => {
                let side = m.dot(apex - q);
                if side == 0.0 {
                    return true;
                }
                // Some direction of the cone heads towards the plane.
                let towards = if side > 0.0 { -m } else { m };
                let angle = axis.dot(towards).clamp(-1.0, 1.0).acos();
                !(angle - half >= std::f32::consts::FRAC_PI_2)
            }
        }
    }
}

/// What to say of a light whose [`Reach`] meets none of `boxes` (but
/// those at the sorted indices `skip`) and none of `planes`, or `None`.
fn unreached(light: &Light, boxes: &[Aabb], skip: &[u32], planes: &[Plane]) -> Option<String> {
    let reach = Reach::of(light);
    if reach == Reach::Everywhere {
        return None;
    }
    let objects = boxes
        .iter()
        .enumerate()
        .filter(|(i, _)| skip.binary_search(&(*i as u32)).is_err())
        .map(|(_, b)| b);
    let mut any = false;
    for b in objects {
        if reach.reaches_box(b) {
            return None;
        }
        any = true;
    }
    if planes.iter().any(|p| reach.reaches_plane(p)) {
        return None;
    }
    if !any && planes.is_empty() {
        // Nothing to light at all: not a light turned the wrong way.
        return None;
    }
    let v = |v: Vec3| format!("[{}, {}, {}]", round(v.x), round(v.y), round(v.z));
    Some(match (light, reach) {
        (Light::Rect { rect, .. }, _) => format!(
            "lights nothing: every object lies behind it (a rect light shines to the side of edge_u × edge_v, here {}); swap edge_u and edge_v to turn it round",
            v(rect.normal)
        ),
        (Light::Disk { disk, .. }, _) => format!(
            "lights nothing: every object lies behind it (a disk light shines to the side its normal points, here {}); negate normal to turn it round",
            v(disk.frame.z)
        ),
        (Light::Spot { direction, .. }, Reach::Cone { half, .. }) => format!(
            "lights nothing: its cone (outer_angle {}°) around {} misses every object; aim it with direction or look_at",
            round(half.to_degrees()),
            v(*direction)
        ),
        _ => return None,
    })
}

/// `x` to three decimals, without a trailing ".0" or a "-0".
fn round(x: f32) -> f32 {
    (x * 1000.0).round() / 1000.0 + 0.0
}

impl Compiler<'_> {
    /// A warning for each of the scene file's first `count` lights (its
    /// `[[lights]]`) that can light none of the objects whose world boxes
    /// are `boxes` (the lights' own surfaces skipped) or the planes: an
    /// area light facing away from all of them, a spot light aimed past.
    pub(super) fn unreached_lights(&self, count: usize, boxes: &[Aabb]) -> Vec<InputError> {
        let mut emitters: Vec<u32> = self.lights.iter().filter_map(Light::prim).collect();
        emitters.sort_unstable();
        let lights = self.lights.iter().take(count).enumerate();
        lights
            .filter_map(|(i, light)| {
                let message = unreached(light, boxes, &emitters, &self.planes)?;
                Some(self.err(&format!("lights[{i}]"), message))
            })
            .collect()
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

    #[test]
    fn a_spot_light_aims_by_direction_or_target_and_checks_its_angles() {
        let s = "[[lights]]\ntype = \"spot\"\nposition = [0.0, 4.0, 0.0]\nintensity = 3.0\n";
        let aimed = compiled(&format!(
            "{s}look_at = [0.0, 0.0, 0.0]\ninner_angle = 10\nouter_angle = 20\n"
        ));
        let Light::Spot {
            position,
            direction,
            intensity,
            cos_inner,
            cos_outer,
        } = aimed.lights[0]
        else {
            panic!("{:?}", aimed.lights[0]);
        };
        assert_eq!((position, direction), (glam::Vec3::Y * 4.0, -glam::Vec3::Y));
        assert_eq!(intensity, glam::Vec3::splat(3.0));
        assert_eq!(cos_inner, 10f32.to_radians().cos());
        assert_eq!(cos_outer, 20f32.to_radians().cos());
        // glTF's defaults: inner 0, outer 45 degrees.
        let default = compiled(&format!("{s}direction = [0.0, -2.0, 0.0]\n"));
        assert!(
            matches!(default.lights[0], Light::Spot { direction, cos_inner, cos_outer, .. }
            if direction == -glam::Vec3::Y && cos_inner == 1.0 && cos_outer == 45f32.to_radians().cos())
        );
        for (extra, at, needle) in [
            ("", "lights[0]", "needs `direction` or `look_at`"),
            (
                "direction = [0.0, -1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\n",
                "lights[0]",
                "not both",
            ),
            (
                "look_at = [0.0, 4.0, 0.0]\n",
                "lights[0].look_at",
                "equals the light's position",
            ),
            (
                "direction = [0.0, -1.0, 0.0]\nouter_angle = 0\n",
                "lights[0].outer_angle",
                "more than 0",
            ),
            (
                "direction = [0.0, -1.0, 0.0]\nouter_angle = 181\n",
                "lights[0].outer_angle",
                "at most 180",
            ),
            (
                "direction = [0.0, -1.0, 0.0]\ninner_angle = 50\n",
                "lights[0].inner_angle",
                "outer_angle (45)",
            ),
            (
                "direction = [0.0, -1.0, 0.0]\nradius = 1\n",
                "lights[0].radius",
                "does not apply to a spot light",
            ),
        ] {
            let e = rejected(&format!("{s}{extra}"));
            assert_eq!(e.location, at, "{extra}: {e}");
            assert!(e.message.contains(needle), "{extra}: {e}");
        }
    }

    #[test]
    fn keys_a_light_type_does_not_take_are_errors_on_their_line() {
        let e = rejected(
            "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nradius = 0.5\n",
        );
        assert_eq!((e.location.as_str(), e.line), ("lights[0].radius", Some(5)));
        assert!(
            e.message
                .contains("does not apply to a point light, which takes position and intensity"),
            "{e}"
        );
        let e = rejected(
            "[[lights]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradiance = [1.0, 1.0, 1.0]\n",
        );
        assert_eq!((e.location.as_str(), e.line), ("lights[0]", Some(1)));
        assert!(e.message.contains("a sphere light needs `radius`"), "{e}");
        // A directional light's irradiance may be called intensity, not both.
        let d = "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\n";
        assert!(matches!(
            compiled(&format!("{d}intensity = [2.0, 2.0, 2.0]")).lights[0],
            Light::Directional { irradiance, .. } if irradiance == glam::Vec3::splat(2.0)
        ));
        let e = rejected(&format!(
            "{d}intensity = [2.0, 2.0, 2.0]\nirradiance = [1.0, 1.0, 1.0]"
        ));
        assert!(e.message.contains("not both"), "{e}");
    }

    /// The warnings a scene's lights get for reaching nothing.
    fn unreached(lights: &str, objects: &str) -> Vec<String> {
        let s = compiled(&format!("{lights}\n{objects}"));
        let said: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
        said.into_iter()
            .filter(|w| w.contains("lights nothing"))
            .collect()
    }

    const FLOOR: &str =
        "[[objects]]\ntriangle = { v = [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]] }\n";
    const GROUND: &str = "[[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\n";

    fn rect(edge_u: &str, edge_v: &str) -> String {
        format!(
            "[[lights]]\ntype = \"rect\"\ncorner = [-0.5, 3.0, -0.5]\nedge_u = {edge_u}\nedge_v = {edge_v}\nradiance = 5.0\n"
        )
    }

    /// Issue 62: a rect light's side is edge_u × edge_v; turned away from
    /// every object it lights nothing, and says so at its line.
    #[test]
    fn an_area_light_facing_away_from_every_object_is_warned_of() {
        let (x, z) = ("[1.0, 0.0, 0.0]", "[0.0, 0.0, 1.0]");
        // x × z is down, towards the floor: lit.
        assert!(unreached(&rect(x, z), FLOOR).is_empty());
        assert!(unreached(&rect(x, z), GROUND).is_empty());
        for objects in [FLOOR, GROUND] {
            let said = unreached(&rect(z, x), objects);
            assert_eq!(said.len(), 1, "{said:?}");
            assert!(
                said[0].starts_with("t.toml: line 1: lights[0]: lights nothing")
                    && said[0].contains("edge_u × edge_v, here [0, 1, 0]")
                    && said[0].contains("swap edge_u and edge_v"),
                "{}",
                said[0]
            );
        }
        // A plane tilted against the light crosses its front.
        let tilted = "[[objects]]\nplane = { normal = [0.0, 1.0, 0.2] }\n";
        assert!(unreached(&rect(z, x), tilted).is_empty());
        // A disk shines where its normal points.
        let disk = |n: &str| {
            format!("[[lights]]\ntype = \"disk\"\ncenter = [0.0, 3.0, 0.0]\nnormal = {n}\nradius = 0.5\nradiance = 5.0\n")
        };
        assert!(unreached(&disk("[0.0, -1.0, 0.0]"), FLOOR).is_empty());
        let said = unreached(&disk("[0.0, 1.0, 0.0]"), FLOOR);
        assert!(
            said.len() == 1 && said[0].contains("negate normal"),
            "{said:?}"
        );
        // Lights that shine everywhere, and a scene with nothing to light.
        let point = "[[lights]]\ntype = \"point\"\nposition = [0.0, -3.0, 0.0]\nintensity = 1.0\n";
        assert!(unreached(point, FLOOR).is_empty());
        assert!(unreached(&rect(z, x), "").is_empty());
    }

    #[test]
    fn a_spot_light_aimed_past_every_object_is_warned_of() {
        let spot = |aim: &str, outer: f32| {
            format!("[[lights]]\ntype = \"spot\"\nposition = [0.0, 3.0, 0.0]\n{aim}\nintensity = 1.0\nouter_angle = {outer}\n")
        };
        assert!(unreached(&spot("direction = [0.0, -1.0, 0.0]", 20.0), FLOOR).is_empty());
        assert!(unreached(&spot("look_at = [0.9, 0.0, -0.9]", 5.0), FLOOR).is_empty());
        // Sideways: a narrow cone passes over the floor, a wide one takes it in.
        assert!(unreached(&spot("direction = [1.0, 0.0, 0.0]", 100.0), FLOOR).is_empty());
        let said = unreached(&spot("direction = [1.0, 0.0, 0.0]", 30.0), FLOOR);
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(
            said[0]
                .contains("lights[0]: lights nothing: its cone (outer_angle 30°) around [1, 0, 0]"),
            "{}",
            said[0]
        );
        // Up, away from a ground plane; any tilt down reaches it.
        assert_eq!(
            unreached(&spot("direction = [0.0, 1.0, 0.0]", 45.0), GROUND).len(),
            1
        );
        assert!(unreached(&spot("direction = [1.0, -0.1, 0.0]", 1.0), GROUND).is_empty());
    }
}

//! The scene file, as serde types. Every field that can have a sensible
//! default has one, and unknown keys are errors.
//!
//! The `[render]` table is [`RenderOverrides`] (see [`super::settings`]).
//!
//! ```toml
//! [camera]
//! type = "perspective"   # "orthographic" | "thin_lens"
//! position = [0.0, 1.0, 6.0]
//! look_at = [0.0, 0.5, 0.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 40.0             # vertical, degrees
//! ```
//! docs/scene-format.md describes every key for users.

use super::settings::RenderOverrides;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

pub type V3 = [f32; 3];

/// A colour as the scene file writes it: three numbers `[r, g, b]`, or one
/// number for a grey (`diffuse = 0.5` is `[0.5, 0.5, 0.5]`, as in MTL
/// files). Every colour of the format is read through it ([`colour`],
/// [`optional_colour`]), so they all accept the same and say the same.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Colour(pub V3);

impl<'de> Deserialize<'de> for Colour {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = d.deserialize_any(OneOrThree("three numbers [r, g, b] or one"))?;
        Ok(Colour(match value {
            Numbers::One(x) => [x; 3],
            Numbers::Three(v) => v,
        }))
    }
}

/// A colour field (`#[serde(deserialize_with = "colour")]`).
pub fn colour<'de, D: Deserializer<'de>>(d: D) -> Result<V3, D::Error> {
    Colour::deserialize(d).map(|c| c.0)
}

/// An optional colour field (with `#[serde(default)]`: absent is `None`).
pub fn optional_colour<'de, D: Deserializer<'de>>(d: D) -> Result<Option<V3>, D::Error> {
    colour(d).map(Some)
}

/// One number or three, as written.
enum Numbers {
    One(f32),
    Three(V3),
}

/// Reads [`Numbers`]; its text is what the error says was expected.
struct OneOrThree(&'static str);

impl<'de> Visitor<'de> for OneOrThree {
    type Value = Numbers;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(self.0)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Numbers, E> {
        Ok(Numbers::One(v as f32))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Numbers, E> {
        Ok(Numbers::One(v as f32))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Numbers, E> {
        Ok(Numbers::One(v as f32))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Numbers, A::Error> {
        let mut v = Vec::with_capacity(3);
        while let Some(x) = seq.next_element::<f32>()? {
            v.push(x);
        }
        match v[..] {
            [x, y, z] => Ok(Numbers::Three([x, y, z])),
            _ => Err(de::Error::invalid_length(v.len(), &self)),
        }
    }
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneDescription {
    #[serde(default)]
    pub render: RenderOverrides,
    #[serde(default)]
    pub camera: Option<CameraDesc>,
    #[serde(default)]
    pub materials: std::collections::BTreeMap<String, MaterialDesc>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Where each key is written, for error messages (empty when the
    /// description was not parsed from text).
    #[serde(skip)]
    pub source: super::source_map::SourceMap,
    /// Key paths that `--set` changed: an error there is the command line's.
    #[serde(skip)]
    pub edited: Vec<String>,
    /// The file's mistakes found while reading it, in file order; the
    /// compiler reports them with its own (see [`super::parse`]). Empty in
    /// every description [`super::parse::parse_description`] returns.
    #[serde(skip)]
    pub mistakes: Vec<crate::error::InputError>,
    /// The parts that did not read whole (`camera`, `lights[1]`,
    /// `objects[0]`), held as defaults so the others keep their indices:
    /// the compiler skips them, so their mistakes are not reported twice.
    #[serde(skip)]
    pub unread: Vec<String>,
}

impl SceneDescription {
    /// Whether the part at key path `key` was left out for its mistakes.
    pub fn is_unread(&self, key: &str) -> bool {
        self.unread.iter().any(|u| u == key)
    }
}

crate::mode::mode_enum! {
    /// `[camera] type`.
    #[derive(Default)]
    pub enum CameraType("camera type") {
        #[default]
        Perspective = "perspective",
        Orthographic = "orthographic",
        ThinLens = "thin_lens",
    }
}

/// `[camera]`. Keys that the chosen type does not use are errors (an
/// `aperture` on a pinhole camera would silently do nothing); the compiler
/// checks them, so these are options here.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraDesc {
    #[serde(rename = "type")]
    pub kind: CameraType,
    pub position: V3,
    pub look_at: V3,
    pub up: V3,
    /// Vertical field of view in degrees (perspective, thin lens); default 40.
    pub fov: Option<f32>,
    /// Lens radius (thin lens); default 0, a pinhole.
    pub aperture: Option<f32>,
    /// Distance to the plane in focus (thin lens); default: distance to `look_at`.
    pub focus_distance: Option<f32>,
    /// World-space height of the view (orthographic); default 4.
    pub height: Option<f32>,
}

impl Default for CameraDesc {
    fn default() -> Self {
        Self {
            kind: CameraType::Perspective,
            position: [0.0, 1.0, 6.0],
            look_at: [0.0, 0.5, 0.0],
            up: [0.0, 1.0, 0.0],
            fov: None,
            aperture: None,
            focus_distance: None,
            height: None,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialDesc {
    #[serde(deserialize_with = "colour")]
    pub diffuse: V3,
    #[serde(deserialize_with = "colour")]
    pub specular: V3,
    pub shininess: f32,
    pub reflectivity: f32,
    pub glossiness: f32,
    pub transparency: f32,
    pub ior: f32,
    pub fresnel: bool,
    #[serde(deserialize_with = "colour")]
    pub emission: V3,
    /// glTF's metallic-roughness model instead of the Phong keys: linear
    /// RGB in [0, 1].
    #[serde(deserialize_with = "optional_colour")]
    pub base_color: Option<V3>,
    /// 0 a dielectric, 1 a metal (metallic-roughness model).
    pub metallic: Option<f32>,
    /// Perceptual roughness in [0, 1] (metallic-roughness model).
    pub roughness: Option<f32>,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        let m = crate::material::Material::default();
        Self {
            diffuse: m.diffuse.into(),
            specular: m.specular.into(),
            shininess: m.shininess,
            reflectivity: m.reflectivity,
            glossiness: m.glossiness,
            transparency: m.transparency,
            ior: m.ior,
            fresnel: m.fresnel,
            emission: m.emission.into(),
            base_color: None,
            metallic: None,
            roughness: None,
        }
    }
}

crate::mode::mode_enum! {
    /// `[[lights]] type`. The file must give one; the default only lets
    /// code build a [`LightDesc`] with `..Default::default()`.
    #[derive(Default)]
    pub enum LightType("light type") {
        /// Intensity I in W/sr: irradiance I cosθ / r².
        #[default]
        Point = "point",
        /// A point light shining into a cone along `direction` (or towards
        /// `look_at`): full `intensity` within `inner_angle` of the axis,
        /// none beyond `outer_angle`, glTF's falloff between (degrees).
        Spot = "spot",
        /// Light travelling along `direction`, with `irradiance` (W/m²) on a
        /// surface facing it.
        Directional = "directional",
        /// One-sided parallelogram emitting `radiance` towards `edge_u × edge_v`.
        Rect = "rect",
        /// One-sided disk emitting `radiance` towards `normal`.
        Disk = "disk",
        /// Sphere emitting `radiance` outwards.
        Sphere = "sphere",
        /// Radiance from every direction at infinity: constant `radiance`,
        /// or a lat-long `map` (EXR or Radiance HDR), times `scale`,
        /// turned by `rotate`.
        Environment = "environment",
    }
}

/// A `[[lights]]` entry: its type and that type's keys. One flat table (not
/// one serde variant per type) so that a bad value is reported at its own
/// key and line; the compiler checks which keys the type takes.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    #[serde(rename = "type")]
    pub kind: LightType,
    pub position: Option<V3>,
    #[serde(default, deserialize_with = "optional_colour")]
    pub intensity: Option<V3>,
    pub direction: Option<V3>,
    #[serde(default, deserialize_with = "optional_colour")]
    pub irradiance: Option<V3>,
    pub corner: Option<V3>,
    pub edge_u: Option<V3>,
    pub edge_v: Option<V3>,
    pub center: Option<V3>,
    pub normal: Option<V3>,
    pub radius: Option<f32>,
    #[serde(default, deserialize_with = "optional_colour")]
    pub radiance: Option<V3>,
    /// A spot light's target, instead of its `direction`.
    pub look_at: Option<V3>,
    /// A spot light's half-angles from its axis, in degrees.
    pub inner_angle: Option<f32>,
    pub outer_angle: Option<f32>,
    /// An environment light's lat-long map, relative to the scene file.
    pub map: Option<String>,
    /// An environment light's multiplier: one number or a colour.
    #[serde(default, deserialize_with = "optional_colour")]
    pub scale: Option<V3>,
    /// An environment light's rotation, axis-angle as transforms write it:
    /// [x, y, z, degrees].
    pub rotate: Option<[f32; 4]>,
}

impl LightDesc {
    /// A `[[lights]]` entry of type `type` with no keys set yet.
    pub fn of_type(kind: LightType) -> Self {
        Self {
            kind,
            ..Self::default()
        }
    }

    /// A constant environment light of `radiance`: what a scene without
    /// lights can be given as a neutral default.
    pub fn constant_environment(radiance: V3) -> Self {
        Self {
            radiance: Some(radiance),
            ..Self::of_type(LightType::Environment)
        }
    }
}

/// An object: exactly one shape key, plus optional material and transform.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub sphere: Option<SphereDesc>,
    pub plane: Option<PlaneDesc>,
    pub cylinder: Option<CylinderDesc>,
    pub triangle: Option<TriangleDesc>,
    pub mesh: Option<String>,
    pub group: Option<Vec<ObjectDesc>>,
    pub csg: Option<Box<CsgDesc>>,
    pub material: Option<String>,
    pub transform: Option<TransformDesc>,
    /// A file of placements (one row-major 3×4 matrix per line), each
    /// applied before `transform`: the object is placed once per line.
    pub instances: Option<String>,
    pub name: Option<String>,
    /// With `mesh`: whether the file's own lights (glTF
    /// `KHR_lights_punctual`) join the scene's; default true.
    pub lights: Option<bool>,
    /// With `mesh`: the file's camera of this index is the scene's camera.
    pub camera: Option<usize>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    #[serde(default)]
    pub center: V3,
    pub radius: f32,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneDesc {
    #[serde(default)]
    pub point: V3,
    pub normal: V3,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderDesc {
    #[serde(default)]
    pub base: V3,
    #[serde(default = "default_axis")]
    pub axis: V3,
    pub radius: f32,
    pub height: f32,
    #[serde(default = "default_true")]
    pub caps: bool,
}

fn default_axis() -> V3 {
    [0.0, 1.0, 0.0]
}

fn default_true() -> bool {
    true
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TriangleDesc {
    pub v: [V3; 3],
}

crate::mode::mode_enum! {
    /// `csg.op`.
    pub enum CsgOp("CSG operation") {
        Union = "union",
        Intersection = "intersection",
        Difference = "difference",
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CsgDesc {
    pub op: CsgOp,
    pub a: ObjectDesc,
    pub b: ObjectDesc,
}

/// Applied as scale, then rotate, then translate (M = T·R·S), or a full
/// row-major 4×4 `matrix` instead.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    pub translate: Option<V3>,
    /// Axis-angle: [x, y, z, degrees].
    pub rotate: Option<[f32; 4]>,
    /// Per-axis scale, or one number for all axes.
    pub scale: Option<ScaleDesc>,
    pub matrix: Option<[[f32; 4]; 4]>,
}

#[derive(Debug, Clone, Copy)]
pub enum ScaleDesc {
    Uniform(f32),
    PerAxis(V3),
}

impl<'de> Deserialize<'de> for ScaleDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match d.deserialize_any(OneOrThree("three numbers [x, y, z] or one"))? {
                Numbers::One(s) => ScaleDesc::Uniform(s),
                Numbers::Three(v) => ScaleDesc::PerAxis(v),
            },
        )
    }
}

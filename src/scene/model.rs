//! A scene made around one model file, for `strata render model.glb`.
//!
//! The scene is written as scene-file text (TOML) and read back like any
//! scene file, so `--set` edits it as it edits a file, and `--save-scene`
//! writes exactly what was rendered:
//!
//! - **`[render]`:** the image size the camera was made for, and every
//!   setting the command line gave, so the saved file renders alike alone.
//! - **`[camera]`:** the file's own camera (glTF; the first, or the one
//!   asked for), its `aspectRatio` sizing the image unless the command
//!   line does; otherwise [`frame`]: a perspective camera looking at the
//!   model from a three-quarter view, as close as keeps every vertex
//!   inside the picture.
//! - **`[[lights]]`:** the file's own lights (glTF `KHR_lights_punctual`),
//!   written out (so the object says `lights = false`), or
//!   [`default_lights`]: a studio of a dim sky, a key light that casts
//!   soft shadows, and a ground under the model that catches them.
//! - **`[[objects]]`:** the model, with its own materials, and the ground.
//! - **The budget:** unless the command line gives `--spp` or `--noise`,
//!   a noise target ([`DEFAULT_NOISE`], at most [`DEFAULT_SPP`] samples),
//!   and the filmic tone curve unless it gives `--tonemap`.

use super::asset::LoadedAsset;
use super::description::{CameraDesc, CameraType, LightDesc, SceneDescription, V3};
use super::edit::{self, Edit};
use super::loaders::load_mesh_file;
use super::settings::{IntegratorKind, RenderOverrides, RenderSettings};
use crate::error::{InputError, InputResult};
use crate::system::steps::Steps;
use glam::Vec3;
use rayon::prelude::*;
use std::fmt::Write;
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

/// The field of view of the framing camera across the image's narrower
/// side, in degrees: a normal lens, little perspective distortion.
pub const FRAMING_FOV: f32 = 40.0;
/// How much of the half-width (or half-height) the framed model reaches
/// at most: a margin of a tenth, so no edge of the model meets the image's.
pub const FRAMING_FILL: f32 = 0.9;
/// The most placed vertices of shared meshes framing reads one by one;
/// past it, each placement's box ([`LoadedAsset::framing_positions`]).
pub const FRAMING_POINTS: usize = 1 << 24;

/// The noise target of a model's first picture when the command line
/// asks for no sample count: little grain at a glance, in seconds. On the
/// bunny it takes the samples the previous measure's 0.05 took (about
/// 26 a pixel) to 11% less RMSE (the timings are in
/// docs/model-pictures.md).
pub const DEFAULT_NOISE: f32 = 0.07;
/// The ceiling of samples per pixel under [`DEFAULT_NOISE`].
pub const DEFAULT_SPP: u32 = 128;
/// The studio's sky: a constant environment of this radiance, the fill
/// light (an upward face of albedo ρ shows 0.35 ρ from it alone).
pub const SKY_RADIANCE: f32 = 0.35;
/// The irradiance the key light gives a face turned to it at the model's
/// centre, over π: such a face of albedo ρ shows 0.8 ρ from it, so white
/// (0.8) lit by key and sky stays below 1.
pub const KEY_IRRADIANCE: f32 = 0.8;
/// The ground's albedo: mid grey, so that shadows read on it.
pub const GROUND_ALBEDO: f32 = 0.5;

/// Which camera `--camera` asks for: one of the file's by number, or
/// `auto`, the framing camera even when the file has cameras.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraChoice {
    Index(usize),
    Auto,
}

impl std::str::FromStr for CameraChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "auto" => Ok(Self::Auto),
            n => match n.parse::<i64>() {
                Ok(i) if i >= 0 => Ok(Self::Index(i as usize)),
                Ok(_) => Err("must be at least 0, or auto".into()),
                Err(_) => Err(format!("'{n}' is not a camera number (0, 1, …) or auto")),
            },
        }
    }
}

/// A model file and the scene made around it.
pub struct ModelScene {
    /// The model, already read: the compiler takes it instead of reading
    /// the file again ([`super::compile::compile_model`]).
    pub asset: LoadedAsset,
    /// The scene as parsed (with the `--set` edits), its mesh named
    /// relative to the model's own directory.
    pub description: SceneDescription,
    /// One line for each thing made up rather than read from the file
    /// (the camera, the lights), for the user.
    pub notes: Vec<String>,
    /// The wall time of reading the model and of framing it.
    pub steps: Steps,
    model: PathBuf,
    parts: Parts,
    edits: Vec<Edit>,
}

/// What the scene text is made of.
struct Parts {
    render: RenderOverrides,
    camera: CameraDesc,
    lights: Vec<LightDesc>,
    /// Whether the file's lights are written out (the object then leaves
    /// them out).
    own_lights: bool,
    /// The height of the studio's ground, where strata lights the model.
    ground: Option<f32>,
}

/// Read `model` and make its scene: `camera` picks one of a glTF file's
/// cameras (`--camera N`), `cli` is the command line's render settings,
/// and `edits` its `--set` edits, applied to the scene text.
pub fn model_scene(
    model: &Path,
    cli: &RenderOverrides,
    edits: &[Edit],
    camera: Option<CameraChoice>,
) -> InputResult<ModelScene> {
    // The command line's values are its own: checked here, they are
    // never blamed on the scene text made from them.
    cli.check().map_err(|bad| bad.on_command_line())?;
    let mut steps = Steps::default();
    let asset = steps.time("read", || load_mesh_file(model))?;
    let frame_start = Instant::now();
    let mut notes = Vec::new();
    let name = model.display();
    let index = match camera {
        Some(CameraChoice::Index(n)) => Some(n),
        _ => None,
    };
    let chosen = match (index, asset.cameras.len()) {
        _ if camera == Some(CameraChoice::Auto) => None,
        (Some(n), count) if n >= count => {
            let has = match count {
                0 => "no cameras".to_string(),
                1 => "one camera, camera 0".to_string(),
                k => format!("{k} cameras, 0 to {}", k - 1),
            };
            return Err(InputError::new(
                "<command line>",
                "--camera",
                format!("{name} has {has}, so there is no camera {n}"),
            ));
        }
        (n, count) if count > 0 => Some(&asset.cameras[n.unwrap_or(0)]),
        _ => None,
    };
    let points = asset.framing_points(FRAMING_POINTS);
    let bounds = bounds(&points);
    let (lights, own_lights) = if asset.lights.is_empty() {
        notes.push(format!(
            "{name} has no lights: lit by strata's studio, a dim sky, a key light from above left casting soft shadows and a grey ground under the model (--save-scene writes it out to edit)"
        ));
        (default_lights(bounds), false)
    } else {
        (asset.lights.iter().map(|l| l.to_desc()).collect(), true)
    };
    let ground = (!own_lights).then(|| ground_height(bounds));
    let mut render = cli.clone();
    if cli.spp.is_none() && cli.noise.is_none() {
        render.noise = Some(DEFAULT_NOISE);
        render.spp = Some(DEFAULT_SPP);
        notes.push(format!(
            "rendering to a noise target of {DEFAULT_NOISE} (at most {DEFAULT_SPP} samples a pixel): --noise E for another, --spp N for a fixed count"
        ));
    }
    render.tonemap = cli
        .tonemap
        .or(Some(crate::output::tonemap::Tonemap::Filmic));
    // A model is rendered as the tools it comes from show it: light that
    // bounces, glowing parts that light, its metallic-roughness materials.
    render.integrator = cli.integrator.or(Some(IntegratorKind::Path));
    if let (Some(b), false) = (cli.background.filter(|b| *b != [0.0; 3]), own_lights) {
        let flag = format!("--background {}", super::settings::rgb_text(b));
        return Err(InputError::flag(flag, made_up_environment(model)));
    }
    let aspect = chosen.and_then(|c| c.aspect_ratio);
    let mut size = image_size(cli, &RenderOverrides::default(), aspect);
    check_aspect(model, index.unwrap_or(0), aspect, size)?;
    let mut parts;
    let mut description;
    // Twice at most: a `--set render.width` changes the size to frame for.
    loop {
        let camera = match chosen {
            Some(c) => c.to_desc(),
            None => frame(&points, bounds, size.0, size.1),
        };
        parts = Parts {
            render: RenderOverrides {
                width: Some(size.0),
                height: Some(size.1),
                ..render.clone()
            },
            camera,
            lights: lights.clone(),
            own_lights,
            ground,
        };
        let file_name = model
            .file_name()
            .ok_or_else(|| InputError::file(model, "is not a file name"))?;
        let text = scene_text(&parts, &file_name.to_string_lossy());
        // The "scene file" is the model itself, so its mesh resolves to it;
        // the text is strata's, so no error points at a line of it.
        description = super::parse::parse_edited(model, &text, edits)?;
        description.source = std::mem::take(&mut description.source).made_up();
        let edited = image_size(cli, &description.render, None);
        if edited == size || edits.is_empty() {
            break;
        }
        size = edited;
    }
    drop(points);
    background_by_edit(model, &description, edits, own_lights)?;
    match (chosen, bounds) {
        (Some(_), _) => {}
        (None, Some((lo, hi))) => notes.push(format!(
            "{name} has no camera: framed its bounds {} to {} from a three-quarter view",
            words(lo.into()),
            words(hi.into())
        )),
        (None, None) => notes.push(format!(
            "{name} has no camera and no triangles to frame: looking at the box from -1 to 1"
        )),
    }
    steps.add("frame", frame_start.elapsed());
    Ok(ModelScene {
        steps,
        asset,
        description,
        notes,
        model: model.to_path_buf(),
        parts,
        edits: edits.to_vec(),
    })
}

impl ModelScene {
    /// The model file, which is also the scene's "file": its mesh
    /// resolves to it, and errors name it.
    pub fn path(&self) -> &Path {
        &self.model
    }

    /// The scene as a file to be saved at `path`: its mesh named relative
    /// to that file's directory, the `--set` edits applied.
    pub fn save_text(&self, path: &Path) -> InputResult<String> {
        let mesh = relative_path(&self.model, path);
        let text = scene_text(&self.parts, &mesh.to_string_lossy());
        if self.edits.is_empty() {
            return Ok(text);
        }
        let edited = edit::apply(&text, &self.edits)?;
        Ok(format!("{}{edited}", header()))
    }
}

/// The light of a model that brings none, made for its `bounds`: a sky
/// (a constant environment of [`SKY_RADIANCE`]) for fill, and a key light,
/// a square rect light above the model to the front left of the framing
/// camera's view (azimuth −20°, 55° up), at four times the model's radius
/// and 1.5 radii across, so the shadows it casts on the ground are soft
/// (a penumbra of about a third of the distance from the shadow's caster).
/// Its radiance L gives a face turned to it irradiance L·A/d² ≈
/// π·[`KEY_IRRADIANCE`] at the centre. Every size of model is lit alike.
pub fn default_lights(bounds: Option<(Vec3, Vec3)>) -> Vec<LightDesc> {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(f32::MIN_POSITIVE.sqrt());
    let (azimuth, elevation) = ((-20f32).to_radians(), 55f32.to_radians());
    let towards = Vec3::new(
        azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    );
    let (distance, side) = (4.0 * radius, 1.5 * radius);
    // Edges u, v with u × v = −towards: the light faces the model.
    let facing = -towards;
    let u = facing.cross(Vec3::Y).normalize() * side;
    let v = facing.cross(u);
    let at = centre + towards * distance - (u + v) * 0.5;
    let radiance = std::f32::consts::PI * KEY_IRRADIANCE * (distance / side).powi(2);
    let key = LightDesc {
        corner: Some(at.into()),
        edge_u: Some(u.into()),
        edge_v: Some(v.into()),
        radiance: Some([radiance; 3]),
        ..LightDesc::of_type(super::description::LightType::Rect)
    };
    vec![LightDesc::constant_environment([SKY_RADIANCE; 3]), key]
}

/// Where the studio's ground lies: a hair below the model's lowest point,
/// so that a flat bottom face is not coplanar with it.
fn ground_height(bounds: Option<(Vec3, Vec3)>) -> f32 {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    lo.y - 1e-4 * (hi - lo).length().max(f32::MIN_POSITIVE)
}

/// The advice for a background given to a model strata lights itself:
/// the light is strata's, so the way out is to colour it, not to drop it.
fn made_up_environment(model: &Path) -> String {
    format!(
        "{} has no lights, so strata lights it with its studio, whose dim sky (a constant environment light) is also what rays that hit nothing see; \
         to change it, colour that light: --set 'lights[0].radiance=[R, G, B]' (it lights the model too), \
         or give the scene lights of your own (--save-scene writes it to edit)",
        model.display()
    )
}

/// A background that a `--set` edit gives a model lit by strata's
/// environment, refused as [`made_up_environment`] says.
fn background_by_edit(
    model: &Path,
    description: &SceneDescription,
    edits: &[Edit],
    own_lights: bool,
) -> InputResult<()> {
    let environment = description
        .lights
        .iter()
        .any(|l| l.kind == super::description::LightType::Environment);
    let given = description.render.background.is_some_and(|b| b != [0.0; 3]);
    if own_lights || !environment || !given {
        return Ok(());
    }
    let key = "render.background";
    let by = edits
        .iter()
        .rev()
        .find(|e| super::parse::within(key, &e.path) || super::parse::within(&e.path, key));
    let place = by.map_or_else(|| "--background".to_string(), |e| e.written());
    Err(InputError::flag(place, made_up_environment(model)))
}

/// A model camera's aspect ratio (`aspectRatio` of glTF) that makes the
/// image too large on one side: named as the file's, not as a `[render]`
/// key strata wrote.
fn check_aspect(
    model: &Path,
    camera: usize,
    aspect: Option<f32>,
    (w, h): (u32, u32),
) -> InputResult<()> {
    match aspect {
        Some(a) if w.max(h) > super::settings::MAX_SIDE => Err(InputError::new(
            model,
            format!("camera {camera}"),
            format!(
                "its aspect ratio {a} makes the image {w}×{h}, larger than {} pixels on a side; give --width and --height",
                super::settings::MAX_SIDE
            ),
        )),
        _ => Ok(()),
    }
}

/// The image size: the command line's, else the scene's `[render]`, else
/// the defaults, a missing side following `aspect` (width / height) when
/// the camera gives one.
fn image_size(cli: &RenderOverrides, file: &RenderOverrides, aspect: Option<f32>) -> (u32, u32) {
    let defaults = RenderSettings::default();
    let width = cli.width.or(file.width);
    let height = cli.height.or(file.height);
    let side = |x: f32| (x.round() as u32).max(1);
    match (width, height, aspect) {
        (Some(w), None, Some(a)) => (w, side(w as f32 / a)),
        (None, Some(h), Some(a)) => (side(h as f32 * a), h),
        (None, None, Some(a)) => (defaults.width, side(defaults.width as f32 / a)),
        (w, h, _) => (w.unwrap_or(defaults.width), h.unwrap_or(defaults.height)),
    }
}

/// The box around every vertex a triangle uses (or, for a file of many
/// shared placements, around their boxes), if there is one.
/// (`points`: [`LoadedAsset::framing_points`]; min and max are exact, so
/// any grouping of the parallel reduction gives the same box).
fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let grow = |b: Option<(Vec3, Vec3)>, c: Option<(Vec3, Vec3)>| match (b, c) {
        (Some((lo, hi)), Some((l, h))) => Some((lo.min(l), hi.max(h))),
        (b, None) => b,
        (None, c) => c,
    };
    points
        .par_iter()
        .with_min_len(1 << 14)
        .map(|&p| Some((p, p)))
        .reduce(|| None, grow)
}

/// A perspective camera looking at the centre of `bounds` from a
/// three-quarter view (45° round from the front, +Z, towards +X, and 25°
/// above), with [`FRAMING_FOV`] across the image's narrower side, as close
/// as keeps every one of `points` inside [`FRAMING_FILL`] of the image's
/// half-width and half-height. A point at offset (x, y, z) from the centre
/// in the camera's frame (z towards the camera, which stands at distance
/// D) lands at x / (D − z) in the image plane, inside t·FILL when
/// D ≥ z + |x| / (t·FILL): the largest such D over the points frames them
/// all, and the one that sets it touches the margin. Every triangle lies
/// within its vertices' projections, so none is cut.
pub fn frame(points: &[Vec3], bounds: Option<(Vec3, Vec3)>, width: u32, height: u32) -> CameraDesc {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length() * 0.5;
    let (azimuth, elevation) = (45f32.to_radians(), 25f32.to_radians());
    let back = Vec3::new(
        azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    );
    let right = Vec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let narrow = (FRAMING_FOV.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let (tx, ty) = if aspect >= 1.0 {
        (narrow * aspect, narrow)
    } else {
        (narrow, narrow / aspect)
    };
    let (fx, fy) = (tx * FRAMING_FILL, ty * FRAMING_FILL);
    // Never closer than a hair in front of the nearest point.
    // The greatest need over the points, in parallel: max is exact, so
    // the camera is the same for any grouping.
    let mut distance = points
        .par_iter()
        .with_min_len(1 << 14)
        .map(|&p| {
            let q = p - centre;
            let z = q.dot(back);
            (z + q.dot(right).abs() / fx)
                .max(z + q.dot(up).abs() / fy)
                .max(z + 1e-3 * radius)
        })
        .reduce(|| f32::MIN_POSITIVE, f32::max);
    if !(distance.is_finite() && distance > f32::MIN_POSITIVE) {
        // No points, or one point: stand back as from a unit box.
        distance = 3.0 * radius.max(1.0);
    }
    CameraDesc {
        kind: CameraType::Perspective,
        position: (centre + back * distance).into(),
        look_at: centre.into(),
        up: [0.0, 1.0, 0.0],
        fov: Some(2.0 * ty.atan().to_degrees()),
        ..CameraDesc::default()
    }
}

/// `model` as a path relative to the directory of the file at `scene`:
/// what a scene file there names it by. Absolute where no relative path
/// leads there (another drive, a directory that cannot be resolved).
fn relative_path(model: &Path, scene: &Path) -> PathBuf {
    let dir = scene.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = dir.map_or_else(|| Path::new(".").canonicalize(), |d| d.canonicalize());
    let (Ok(dir), Ok(target)) = (dir, model.canonicalize()) else {
        return std::path::absolute(model).unwrap_or_else(|_| model.to_path_buf());
    };
    let (from, to): (Vec<Component>, Vec<Component>) =
        (dir.components().collect(), target.components().collect());
    if from.first() != to.first() {
        return target;
    }
    let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..from.len() {
        out.push("..");
    }
    for c in &to[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// The first lines of a saved scene.
fn header() -> String {
    "# A scene made by `strata render MODEL` (--save-scene): edit it and\n\
     # render it with `strata render FILE.toml`.\n\n"
        .to_string()
}

/// The scene text of `parts`, with the model at `mesh`.
fn scene_text(parts: &Parts, mesh: &str) -> String {
    let mut out = header();
    render_table(&mut out, &parts.render);
    camera_table(&mut out, &parts.camera);
    for light in &parts.lights {
        light_table(&mut out, light);
    }
    if let Some(y) = parts.ground {
        out.push_str("[materials.ground]\n");
        line(&mut out, "diffuse", &number(GROUND_ALBEDO));
        out.push_str("\n[[objects]]   # the studio's ground\n");
        line(
            &mut out,
            "plane",
            &format!(
                "{{ point = [0.0, {}, 0.0], normal = [0.0, 1.0, 0.0] }}",
                number(y)
            ),
        );
        line(&mut out, "material", "\"ground\"");
        out.push('\n');
    }
    out.push_str("[[objects]]\n");
    line(
        &mut out,
        "mesh",
        &toml::Value::String(mesh.to_string()).to_string(),
    );
    if parts.own_lights {
        out.push_str("lights = false   # the file's lights, written out above\n");
    }
    out
}

fn line(out: &mut String, key: &str, value: &str) {
    writeln!(out, "{key} = {value}").expect("a String takes any text");
}

/// A number as TOML writes it, read back to the same f32: the shortest
/// decimal that is this f32, unless reading it as f64 first (as the TOML
/// reader does) rounds it elsewhere, then the f64's.
fn number(x: f32) -> String {
    // −0 + 0 is +0: a direction's −0.0 reads as 0.0 to a user, and the
    // text is what is rendered, so nothing differs from what is saved.
    let x = x + 0.0;
    let short = format!("{x:?}");
    if short.parse::<f64>().map(|v| v as f32) == Ok(x) {
        short
    } else {
        format!("{:?}", f64::from(x))
    }
}

fn vector(v: V3) -> String {
    format!("[{}, {}, {}]", number(v[0]), number(v[1]), number(v[2]))
}

/// A vector for messages: three significant digits.
fn words(v: V3) -> String {
    format!("[{:.3}, {:.3}, {:.3}]", v[0], v[1], v[2])
}

/// `[render]`, every setting given. Destructured, so a new setting is a
/// compile error here until it is written too.
fn render_table(out: &mut String, r: &RenderOverrides) {
    let RenderOverrides {
        width,
        height,
        spp,
        shadow_samples,
        reflection_samples,
        max_depth,
        sampler,
        seed,
        background,
        light_sampling,
        glossy_sampling,
        noise,
        exposure,
        tonemap,
        integrator,
    } = r;
    out.push_str("[render]\n");
    let whole = [
        ("width", width),
        ("height", height),
        ("spp", spp),
        ("shadow_samples", shadow_samples),
        ("reflection_samples", reflection_samples),
        ("max_depth", max_depth),
        ("seed", seed),
    ];
    for (key, value) in whole {
        if let Some(v) = value {
            line(out, key, &v.to_string());
        }
    }
    let modes = [
        ("sampler", sampler.map(|m| m.name())),
        ("light_sampling", light_sampling.map(|m| m.name())),
        ("glossy_sampling", glossy_sampling.map(|m| m.name())),
        ("tonemap", tonemap.map(|m| m.name())),
        ("integrator", integrator.map(|m| m.name())),
    ];
    for (key, value) in modes {
        if let Some(v) = value {
            line(out, key, &format!("\"{v}\""));
        }
    }
    for (key, value) in [("noise", noise), ("exposure", exposure)] {
        if let Some(v) = value {
            line(out, key, &number(*v));
        }
    }
    if let Some(b) = background {
        line(out, "background", &vector(*b));
    }
    out.push('\n');
}

fn camera_table(out: &mut String, c: &CameraDesc) {
    let CameraDesc {
        kind,
        position,
        look_at,
        up,
        fov,
        aperture,
        focus_distance,
        height,
    } = c;
    out.push_str("[camera]\n");
    line(out, "type", &format!("\"{}\"", kind.name()));
    line(out, "position", &vector(*position));
    line(out, "look_at", &vector(*look_at));
    line(out, "up", &vector(*up));
    let numbers = [
        ("fov", fov),
        ("aperture", aperture),
        ("focus_distance", focus_distance),
        ("height", height),
    ];
    for (key, value) in numbers {
        if let Some(v) = value {
            line(out, key, &number(*v));
        }
    }
    out.push('\n');
}

/// One `[[lights]]` entry. Destructured, so a new key is a compile error
/// here until it is written too.
fn light_table(out: &mut String, l: &LightDesc) {
    let LightDesc {
        kind,
        position,
        intensity,
        direction,
        irradiance,
        corner,
        edge_u,
        edge_v,
        center,
        normal,
        radius,
        radiance,
        look_at,
        inner_angle,
        outer_angle,
        map,
        scale,
        rotate,
    } = l;
    out.push_str("[[lights]]\n");
    line(out, "type", &format!("\"{}\"", kind.name()));
    if let Some(map) = map {
        line(out, "map", &toml::Value::String(map.clone()).to_string());
    }
    if let Some([x, y, z, deg]) = rotate {
        let [x, y, z, deg] = [x, y, z, deg].map(|v| number(*v));
        line(out, "rotate", &format!("[{x}, {y}, {z}, {deg}]"));
    }
    let vectors = [
        ("position", position),
        ("direction", direction),
        ("look_at", look_at),
        ("intensity", intensity),
        ("irradiance", irradiance),
        ("corner", corner),
        ("edge_u", edge_u),
        ("edge_v", edge_v),
        ("center", center),
        ("normal", normal),
        ("radiance", radiance),
        ("scale", scale),
    ];
    for (key, value) in vectors {
        if let Some(v) = value {
            line(out, key, &vector(*v));
        }
    }
    let numbers = [
        ("radius", radius),
        ("inner_angle", inner_angle),
        ("outer_angle", outer_angle),
    ];
    for (key, value) in numbers {
        if let Some(v) = value {
            line(out, key, &number(*v));
        }
    }
    out.push('\n');
}

/// Why a model file's option (`--camera`, `--save-scene`; the Python
/// package's `camera=`) is refused for a scene.
pub const ONLY_FOR_A_MODEL: &str = "applies to a model file (.glb, .gltf, .obj, .ply, .off, .stl), not to a scene file, which is already a scene (its own [camera], which can name a glTF camera with `camera = N` on its mesh object)";

/// Whether `path` names a model file (one of the mesh formats, by its
/// extension) rather than a scene file: what `strata render PATH` and the
/// Python package's `render(PATH)` render as it comes.
pub fn is_model_path(path: &Path) -> bool {
    super::loaders::check_extension(path).is_ok()
}

/// The scene [`model_scene`] makes around `model` (its own camera, or
/// `camera`, and its lights, or the studio's), with `edits` and
/// `overrides` applied, compiled: what `strata render MODEL` renders, its
/// notes left unsaid.
pub fn load_model_file(
    model: &Path,
    edits: &[Edit],
    overrides: &RenderOverrides,
    quality: super::BuildQuality,
    camera: Option<CameraChoice>,
) -> InputResult<(super::Scene, super::LoadTimings)> {
    let start = Instant::now();
    let made = model_scene(model, overrides, edits, camera)?;
    let progress = super::compile::LoadProgress::default();
    super::compile::compile_model(made, overrides, quality, start, &progress)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every number the writer writes reads back as the same f32.
    #[test]
    fn numbers_read_back_exactly() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = f32::from_bits(state as u32);
            if !x.is_finite() {
                continue;
            }
            let text = format!("x = {}", number(x));
            let back: toml::Table = text.parse().unwrap();
            let read = back["x"].as_float().unwrap() as f32;
            assert_eq!(read.to_bits(), (x + 0.0).to_bits(), "{text}");
        }
    }

    /// The framing camera keeps every point inside the fill margin, and
    /// the tightest one on it, for any aspect, size and place.
    #[test]
    fn framing_keeps_every_point_in_and_one_on_the_margin() {
        use crate::camera::{Camera, Perspective, View};
        for (size, offset, (w, h)) in [
            (1e-3, Vec3::new(0.3, -0.2, 0.1), (640, 480)),
            (1.0, Vec3::ZERO, (480, 640)),
            (1e4, Vec3::new(5e4, 0.0, -2e4), (300, 300)),
        ] {
            let points: Vec<Vec3> = (0..50)
                .map(|i| {
                    let t = i as f32 * 0.7;
                    offset + size * Vec3::new(t.sin(), (t * 1.3).cos() * 0.5, (t * 0.4).sin() * 2.0)
                })
                .collect();
            let b = points.iter().fold((points[0], points[0]), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
            let c = frame(&points, Some(b), w, h);
            let view =
                View::look_at(c.position.into(), c.look_at.into(), c.up.into(), w, h).unwrap();
            let camera = Camera::Perspective(Perspective::new(view, c.fov.unwrap()));
            let ndc = camera.world_to_ndc();
            let mut reach = 0.0f32;
            for p in &points {
                let q = ndc.project_point3(*p);
                // NDC here: [0, 1] across the image (check both ends).
                let (x, y) = (q.x * 2.0 - 1.0, q.y * 2.0 - 1.0);
                assert!(
                    x.abs() <= FRAMING_FILL + 1e-3 && y.abs() <= FRAMING_FILL + 1e-3,
                    "{size}: {x} {y}"
                );
                reach = reach.max(x.abs()).max(y.abs());
            }
            assert!(reach > FRAMING_FILL - 1e-3, "{size}: reaches only {reach}");
        }
    }
}

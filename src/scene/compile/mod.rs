//! Description → [`Scene`]: flatten the object tree into plain arrays,
//! validate every number on the way, and build the BVH.
//!
//! Meshes are baked into world space. Analytic shapes keep their object
//! space unless the transform is a similarity (then a sphere is baked into
//! a new centre and radius, exactly). Infinite planes stay out of the BVH.
//!
//! One `Compiler` walks the description; each part of a scene file has
//! its own file of `impl Compiler`: `material`, `light`, `object`
//! (placement, shapes, groups), `mesh` (mesh files and the leaf blocks),
//! `import` (a mesh file's lights and cameras), `csg`, `camera`; `validate` holds the number checks they share.
//! `progress` is what a load is doing, for a display on another thread.
//! This file holds the entry points and the order of the steps.

use super::asset::{LoadedAsset, LoadedCamera};
use super::description::{CameraDesc, ObjectDesc, SceneDescription};
use super::edit::Edit;
use super::parse::Mistakes;
use super::settings::RenderOverrides;
use super::source_map::SourceMap;
use super::{RenderSettings, Scene};
use crate::accel::prefetch::Prefetch;
use crate::accel::{BuildChoice, BuildQuality, Bvh8};
use crate::error::{InputError, InputResult, COMMAND_LINE};
use crate::geometry::csg::Csg;
use crate::geometry::{AnalyticPrim, Geometry, GeometryParts, Instance, MeshRange, NO_TRANSFORM};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Aabb, Transform};
use crate::shape::plane::Plane;
use crate::system::memory::PeakMeter;
use crate::system::steps::Steps;
use crate::texture::Textures;
use glam::Affine3A;
use mesh::{triangle_at, TriangleSource};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

pub use arrays::{check_extent, mesh_geometry, MeshArraysError, EXTENT};
pub use instance::{read_instances, PLACEMENT_BYTES};
pub use progress::{LoadPhase, LoadProgress};
pub use text::load_edited_text;

mod arrays;
mod camera;
mod csg;
mod emitters;
mod import;
mod instance;
mod light;
mod material;
mod mesh;
mod object;
mod progress;
mod text;
mod validate;

/// Wall time of each loading phase, and how far resident memory rose above
/// its level before loading during each (see [`PeakMeter`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct LoadTimings {
    pub load: Duration,
    pub bvh_build: Duration,
    /// The preset the BVH was built with (what `auto` chose).
    pub bvh_quality: BuildQuality,
    /// Why: asked for, or what `auto` weighed ([`BuildQuality::choose`]).
    pub bvh_choice: BuildChoice,
    pub load_peak_bytes: Option<u64>,
    pub build_peak_bytes: Option<u64>,
    /// The load's steps (a model file's read and framing, the compile)
    /// and the build's (the primitive boxes, each step of the BVH build,
    /// the leaf blocks), each with its wall time.
    pub load_steps: Steps,
    pub build_steps: Steps,
}

impl LoadTimings {
    /// Peak memory of loading and building together, above the level before.
    pub fn peak_bytes(&self) -> Option<u64> {
        self.load_peak_bytes.max(self.build_peak_bytes)
    }
}

/// Read, validate and compile a scene file, with the command line's
/// setting overrides and BVH build effort.
pub fn load_scene(
    path: &Path,
    overrides: &RenderOverrides,
    quality: BuildQuality,
) -> InputResult<(Scene, LoadTimings)> {
    load_edited_scene(path, &[], overrides, quality)
}

/// [`load_scene`] with `--set` edits applied to the file's values first.
pub fn load_edited_scene(
    path: &Path,
    edits: &[Edit],
    overrides: &RenderOverrides,
    quality: BuildQuality,
) -> InputResult<(Scene, LoadTimings)> {
    load_edited_scene_with_progress(path, edits, overrides, quality, &LoadProgress::default())
}

/// [`load_edited_scene`] that says in `progress` what it is doing, for a
/// display on another thread.
pub fn load_edited_scene_with_progress(
    path: &Path,
    edits: &[Edit],
    overrides: &RenderOverrides,
    quality: BuildQuality,
    progress: &LoadProgress,
) -> InputResult<(Scene, LoadTimings)> {
    let start = Instant::now();
    let text = super::loaders::read_scene_file(path)?;
    text::compile_text(&text, path, edits, overrides, quality, start, progress)
}

/// Compile scene text as if read from `path` (meshes resolve relative to
/// it), with the default BVH build effort.
pub fn scene_from_str(text: &str, path: &Path, overrides: &RenderOverrides) -> InputResult<Scene> {
    // Read leniently: the compiler reports the reading's mistakes with its own.
    let desc = super::parse::read_leniently(path, text)?;
    compile(&desc, path, overrides, BuildQuality::Auto, Instant::now()).map(|(scene, _)| scene)
}

/// A scene of one mesh file used as it is (no transform, default camera and
/// materials), compiled exactly as a scene file holding only
/// `[[objects]] mesh = "PATH"` would be, but with the meshes a glTF's
/// nodes share baked ([`LoadedAsset::into_baked`]): triangle `i` of the
/// file is primitive `i`. This is what `strata trace` and `strata rays` intersect,
/// so they exercise the renderer's own code path.
pub fn load_mesh_scene(path: &Path, quality: BuildQuality) -> InputResult<(Scene, LoadTimings)> {
    let file_name = path
        .file_name()
        .ok_or_else(|| InputError::file(path, "is not a file name"))?;
    let desc = SceneDescription {
        objects: vec![ObjectDesc {
            mesh: Some(file_name.to_string_lossy().into_owned()),
            ..ObjectDesc::default()
        }],
        ..SceneDescription::default()
    };
    // The "scene file" is the mesh itself, so the mesh resolves to `path`
    // and every error names it; the made-up scene's key is no place the
    // user wrote, so errors at it name the file alone.
    compile_for(
        &desc,
        path,
        &RenderOverrides::default(),
        quality,
        Purpose::MeshFile,
        Instant::now(),
        &LoadProgress::default(),
        None,
    )
    .map_err(|e| {
        let each = e.into_each().into_iter().map(|mut e| {
            if e.location == "objects[0].mesh" {
                e.location.clear();
            }
            e
        });
        InputError::all(each.collect()).expect("at least the first error")
    })
}

/// A scene file compiled for tracing ray files (`strata trace SCENE.toml`):
/// `auto` BVH effort by primitive count, as for a mesh file.
pub fn load_scene_for_tracing(
    path: &Path,
    quality: BuildQuality,
) -> InputResult<(Scene, LoadTimings)> {
    let start = Instant::now();
    let text = super::loaders::read_scene_file(path)?;
    let desc = super::parse::parse_edited(path, &text, &[])?;
    let overrides = RenderOverrides::default();
    let progress = LoadProgress::default();
    compile_for(
        &desc,
        path,
        &overrides,
        quality,
        Purpose::Tracing,
        start,
        &progress,
        None,
    )
}

/// What a scene is compiled for, which decides what `auto` BVH effort means.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Purpose {
    /// Rendering with its settings: `auto` weighs the build against the
    /// rays the render traces ([`BuildQuality::choose`]).
    Render,
    /// Tracing ray files and benchmarks: `auto` by primitive count alone,
    /// the same tree however many rays are timed.
    Tracing,
    /// Tracing one mesh file as it is: as `Tracing`, with the meshes the
    /// file shares among nodes baked, so triangle `i` of the file is
    /// primitive `i`.
    MeshFile,
}

/// Compile a parsed description for rendering; `path` is the scene file
/// (meshes are relative to it), `overrides` the command line's render settings.
pub fn compile(
    desc: &SceneDescription,
    path: &Path,
    overrides: &RenderOverrides,
    quality: BuildQuality,
    start: Instant,
) -> InputResult<(Scene, LoadTimings)> {
    compile_for(
        desc,
        path,
        overrides,
        quality,
        Purpose::Render,
        start,
        &LoadProgress::default(),
        None,
    )
}

/// Compile the scene made around a model file (see [`super::model`]),
/// with the model as already read instead of reading it again. `start` is
/// when reading the model began, so the load's time includes it.
pub fn compile_model(
    model: super::model::ModelScene,
    overrides: &RenderOverrides,
    quality: BuildQuality,
    start: Instant,
    progress: &LoadProgress,
) -> InputResult<(Scene, LoadTimings)> {
    let path = model.path().to_path_buf();
    let (desc, asset, steps) = (model.description, model.asset, model.steps);
    let compiled = compile_for(
        &desc,
        &path,
        overrides,
        quality,
        Purpose::Render,
        start,
        progress,
        Some((path.clone(), asset)),
    );
    compiled.map(|(scene, mut timings)| {
        // The model's read and framing came before the compile.
        let mut load_steps = steps;
        load_steps.extend(&timings.load_steps);
        timings.load_steps = load_steps;
        (scene, timings)
    })
}

// One argument a step of the load: what, from where, for what, since
// when, told to whom, and what is read already.
#[allow(clippy::too_many_arguments)]
fn compile_for(
    desc: &SceneDescription,
    path: &Path,
    overrides: &RenderOverrides,
    quality: BuildQuality,
    purpose: Purpose,
    start: Instant,
    progress: &LoadProgress,
    preloaded: Option<(PathBuf, LoadedAsset)>,
) -> InputResult<(Scene, LoadTimings)> {
    let mut memory = progress.metered().then(PeakMeter::start);
    let compile_start = Instant::now();
    let mut c = Compiler::new(path, &desc.source, &desc.edited);
    instance::count_mesh_uses(&c.base_dir, &desc.objects, 1, &mut c.mesh_uses);
    c.traced_file = purpose == Purpose::MeshFile;
    c.preloaded = preloaded;
    // Every mistake of the file in one run: each part is compiled after
    // another's mistake too (parts the reading left out are skipped), and
    // the mistakes are given in file order with the reading's.
    let mut mistakes = Mistakes::new(path);
    for e in &desc.mistakes {
        mistakes.push(e.clone(), None);
    }
    for (name, m) in &desc.materials {
        let key = format!("materials.{name}");
        // Defined even with a mistake, so objects naming it are not blamed.
        let material = mistakes.check(c.material(m, &key), desc.source.line_of(&key));
        c.add_material(name.clone(), material.unwrap_or_default());
    }
    for (i, light) in desc.lights.iter().enumerate() {
        let key = format!("lights[{i}]");
        if !desc.is_unread(&key) {
            mistakes.check(c.light(light, &key), desc.source.line_of(&key));
        }
    }
    for (i, obj) in desc.objects.iter().enumerate() {
        let key = format!("objects[{i}]");
        if !desc.is_unread(&key) {
            let placed = c.object(obj, &key, Affine3A::IDENTITY, 0);
            mistakes.check(placed, desc.source.line_of(&key));
        }
    }
    let settings = mistakes.check(c.settings(&desc.render, overrides), None);
    if let Some(settings) = &settings {
        mistakes.check(c.check_background(settings), None);
    }
    // The camera is checked even when the settings have a mistake: with
    // the default ones, whose only part in it is the image's shape.
    let camera = (!desc.is_unread("camera")).then(|| {
        let defaults = RenderSettings::default();
        let s = settings.as_ref().unwrap_or(&defaults);
        mistakes.check(c.scene_camera(desc.camera.as_ref(), s), None)
    });
    if let Some(e) = InputError::all(mistakes.in_file_order()) {
        return Err(e);
    }
    let (Some(settings), Some(Some(camera))) = (settings, camera) else {
        // A part left unchecked always comes with its mistake.
        return Err(InputError::file(path, "the scene could not be read"));
    };
    // Every object holds what it needs from its mesh files by now.
    drop(std::mem::take(&mut c.assets));
    for source in c
        .sources
        .iter_mut()
        .chain(c.prototypes.iter_mut().flat_map(|p| &mut p.sources))
    {
        source.release_file_positions();
    }
    let load = start.elapsed();
    let mut load_steps = Steps::default();
    load_steps.add("compile", compile_start.elapsed());
    let load_peak_bytes = memory.as_mut().and_then(PeakMeter::next_phase);
    let mut build_steps = Steps::default();

    // Area lights were recorded by shape index; make them global primitive ids.
    let n_tris = c.meshes.last().map_or(0, |m| m.first + m.count);
    for light in &mut c.lights {
        if let Light::Rect { prim, .. } | Light::Disk { prim, .. } | Light::Sphere { prim, .. } =
            light
        {
            *prim += n_tris;
        }
    }

    let prototype_tris: u64 = c
        .prototypes
        .iter()
        .map(|p| p.meshes.last().map_or(0, |m| u64::from(m.first + m.count)))
        .sum();
    progress.building(u64::from(n_tris) + prototype_tris);
    let build_start = Instant::now();
    // The render's rays from its whole settings, never a slice's or the
    // thread count: every split of one render builds the same tree.
    let rays = match purpose {
        Purpose::Render => Some(settings.first_hit_rays(&c.lights)),
        Purpose::Tracing | Purpose::MeshFile => None,
    };
    let for_purpose = |quality: BuildQuality, prims: usize| quality.choose(prims, rays);
    // Each prototype's tree first: an instance's box is its root's child
    // boxes moved into world space.
    let mut prototypes = Vec::with_capacity(c.prototypes.len());
    for parts in std::mem::take(&mut c.prototypes) {
        let n = parts
            .meshes
            .last()
            .map_or(0, |m| (m.first + m.count) as usize);
        prototypes.push(instance::build_prototype(
            parts,
            for_purpose(quality, n),
            &c,
        )?);
    }
    let mut boxes = build_steps.time("boxes", || c.primitive_boxes())?;
    for (k, inst) in c.instances.iter_mut().enumerate() {
        let b = inst.bounds(&prototypes[inst.prototype as usize]);
        if !b.is_finite() {
            let message = format!("instance {k} has infinite bounds");
            return Err(InputError::new(path, "objects", message));
        }
        inst.world_bounds = b;
        boxes.push(b);
    }
    let unreached = c.unreached_lights(desc.lights.len(), &boxes);
    c.warnings.extend(unreached);
    let bvh_choice = for_purpose(quality, boxes.len());
    let bvh_quality = bvh_choice.quality;
    let mut bvh = Bvh8::build_timed(boxes, bvh_quality, n_tris, &mut build_steps);
    // The builder reserves room for more nodes than the collapse makes.
    bvh.shrink_to_fit();
    let leaves_start = Instant::now();
    bvh.set_pages(bvh_choice.pages);
    // Store the vertices once, in the order the leaves read them, straight
    // from the (indexed) sources, with the leaf ids beside them: never two
    // copies of the triangles, and the BVH's own ids become redundant.
    let sources = std::mem::take(&mut c.sources);
    let vertices = triangle_at(&c.meshes, &sources);
    let parts = GeometryParts {
        meshes: c.meshes,
        shapes: c.shapes,
        transforms: c.transforms,
        csg: c.csg,
        planes: c.planes,
        instances: c.instances,
        prototypes,
    };
    let mut geometry = Geometry::new(parts, bvh, vertices);
    crate::system::memory::drop_aside(sources);
    build_steps.add("leaves", leaves_start.elapsed());
    let timings = LoadTimings {
        load,
        bvh_build: build_start.elapsed(),
        bvh_quality,
        bvh_choice,
        load_peak_bytes,
        build_peak_bytes: memory.as_ref().and_then(PeakMeter::phase_peak),
        load_steps,
        build_steps,
    };
    geometry.set_prefetch(Prefetch::Auto.enabled(geometry.traversal_bytes()));
    let (emitters, left_out) = emitters::emitters(&geometry, &c.materials, &c.textures, &c.lights);
    c.warnings
        .extend(left_out.map(|note| InputError::new(path, "objects", note)));
    let scene = Scene {
        geometry,
        materials: c.materials,
        textures: c.textures,
        lights: c.lights,
        emitters,
        camera,
        settings,
        warnings: c.warnings,
    };
    Ok((scene, timings))
}

struct Compiler<'d> {
    file: PathBuf,
    base_dir: PathBuf,
    /// Where the scene file writes each key, for errors.
    source: &'d SourceMap,
    /// Key paths the command line's `--set` changed.
    edited: &'d [String],
    /// The triangles of each entry of `meshes`.
    sources: Vec<TriangleSource>,
    meshes: Vec<MeshRange>,
    /// Where each entry of `meshes` was written, for errors.
    mesh_origins: Vec<mesh::MeshOrigin>,
    shapes: Vec<AnalyticPrim>,
    transforms: Vec<Transform>,
    csg: Csg,
    planes: Vec<Plane>,
    materials: Vec<Material>,
    material_ids: HashMap<String, u32>,
    /// The mesh files' images and textures, in the order the files were read.
    textures: Textures,
    lights: Vec<Light>,
    loaded_cameras: Vec<LoadedCamera>,
    /// The mesh file camera an object's `camera` key chose, and that key.
    chosen_camera: Option<(CameraDesc, String)>,
    /// Mesh files already read, with the scene index of their first material.
    assets: HashMap<PathBuf, (Arc<LoadedAsset>, u32)>,
    /// How many times each mesh file is placed: those placed more than
    /// once are stored once, as prototypes.
    mesh_uses: HashMap<PathBuf, u32>,
    /// Prototypes until their trees are built, and each one's file and
    /// shared mesh (`None`: the meshes the file places once).
    prototypes: Vec<instance::PrototypeParts>,
    prototype_ids: HashMap<(PathBuf, Option<usize>), u32>,
    /// One mesh file traced as it is: the meshes it shares among its
    /// placements are baked, not instanced, so its triangles are numbered
    /// as the file's copies, and its faces alone are read
    /// (`loaders::Reading::FACES`: no materials, no textures).
    traced_file: bool,
    instances: Vec<Instance>,
    /// The mesh files' warnings, in the order the files were read.
    warnings: Vec<InputError>,
    /// A mesh file read before the compile began, taken instead of reading
    /// it (the model of `strata render model.glb`).
    preloaded: Option<(PathBuf, LoadedAsset)>,
}

impl<'d> Compiler<'d> {
    fn new(path: &Path, source: &'d SourceMap, edited: &'d [String]) -> Self {
        let mut c = Self {
            file: path.to_path_buf(),
            base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            source,
            edited,
            sources: Vec::new(),
            meshes: Vec::new(),
            mesh_origins: Vec::new(),
            shapes: Vec::new(),
            transforms: Vec::new(),
            csg: Csg::default(),
            planes: Vec::new(),
            materials: Vec::new(),
            material_ids: HashMap::new(),
            textures: Textures::default(),
            lights: Vec::new(),
            loaded_cameras: Vec::new(),
            chosen_camera: None,
            assets: HashMap::new(),
            mesh_uses: HashMap::new(),
            prototypes: Vec::new(),
            prototype_ids: HashMap::new(),
            traced_file: false,
            instances: Vec::new(),
            warnings: Vec::new(),
            preloaded: None,
        };
        // Material 0: what objects get when nothing names one.
        c.materials.push(Material::default());
        c
    }

    /// The file's `[render]` table under the command line's overrides;
    /// a bad value names the layer it came from: the file's line, the
    /// `--set` edit (`--set render.spp=0`) or the flag (`--spp 0`).
    fn settings(
        &self,
        file: &RenderOverrides,
        cli: &RenderOverrides,
    ) -> InputResult<RenderSettings> {
        file.check().map_err(|bad| {
            let e = self.err(&bad.key(), bad.message.clone());
            if e.file == COMMAND_LINE {
                InputError::flag(format!("--set {}", bad.edit()), bad.message)
            } else {
                e
            }
        })?;
        cli.check().map_err(|bad| bad.on_command_line())?;
        let environment = self.lights.iter().any(|l| l.environment().is_some());
        if let (Some(b), true) = (cli.background.filter(|b| *b != [0.0; 3]), environment) {
            let message = format!(
                "rays that hit nothing see {}'s environment light; drop --background or the light",
                self.file.display()
            );
            return Err(InputError::flag(
                format!("--background {}", super::settings::rgb_text(b)),
                message,
            ));
        }
        Ok(RenderSettings::merge(&[file, cli]))
    }

    fn primitive_boxes(&self) -> InputResult<Vec<Aabb>> {
        // Room for the shapes' and the instances' boxes from the start: a
        // huge mesh's boxes grown by one moved 334 MB of pages (on huge
        // pages, split into small ones) for a ground plane's box.
        let room = self.shapes.len() + self.instances.len();
        let mut boxes = mesh::triangle_boxes(&self.meshes, &self.sources, room)
            .map_err(|bad| self.out_of_reach(&bad))?;
        for (i, s) in self.shapes.iter().enumerate() {
            let local = s.shape.bounds(&self.csg);
            let b = if s.transform == NO_TRANSFORM {
                local
            } else {
                let t = &self.transforms[s.transform as usize];
                Aabb::from_points(&local.corners().map(|c| t.point(c)))
            };
            if !b.is_finite() {
                return Err(self.err("objects", format!("shape {i} has infinite bounds")));
            }
            boxes.push(b);
        }
        Ok(boxes)
    }
}

/// Helpers for the compiler's unit tests.
#[cfg(test)]
pub(super) mod test_support {
    use crate::error::InputError;
    use crate::scene::{scene_from_str, RenderOverrides, Scene};
    use std::path::Path;

    pub fn compiled(text: &str) -> Scene {
        scene_from_str(text, Path::new("t.toml"), &RenderOverrides::default())
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// The error compiling `text` gives; panics if it compiles.
    pub fn rejected(text: &str) -> InputError {
        match scene_from_str(text, Path::new("t.toml"), &RenderOverrides::default()) {
            Ok(_) => panic!("compiled:\n{text}"),
            Err(e) => e,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{compiled, rejected};
    use super::*;

    /// A load says what it is doing: loading until its triangles are
    /// counted, then building over all of them (both mesh files' and the
    /// scene file's own), until the caller finishes it.
    #[test]
    fn a_load_reports_its_phases_and_triangles() {
        use crate::scene::loaders::test_files::{temp_dir, write};
        let dir = temp_dir("progress");
        write(
            &dir,
            "quad.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        );
        let scene = write(
            &dir,
            "s.toml",
            b"[[objects]]\nmesh = \"quad.obj\"\n[[objects]]\nmesh = \"quad.obj\"\n\
              [[objects]]\ntriangle = { v = [[0, 0, 5], [1, 0, 5], [0, 1, 5]] }\n",
        );
        let progress = LoadProgress::default();
        assert_eq!(progress.phase(), LoadPhase::Loading);
        let overrides = RenderOverrides::default();
        load_edited_scene_with_progress(&scene, &[], &overrides, BuildQuality::Auto, &progress)
            .unwrap();
        // quad.obj, placed twice, is stored once: its 2 triangles and the
        // scene's own one.
        assert_eq!(progress.phase(), LoadPhase::Building { triangles: 3 });
        progress.finish();
        assert_eq!(progress.phase(), LoadPhase::Done);
    }

    /// An unmetered load measures no memory peak and loads the same
    /// scene; a metered one reports what its meters read.
    #[test]
    fn an_unmetered_load_has_no_memory_peaks() {
        use crate::scene::loaders::test_files::{temp_dir, write};
        let dir = temp_dir("unmetered");
        let scene = write(&dir, "s.toml", b"[[objects]]\nsphere = { radius = 1 }\n");
        let load = |progress: &LoadProgress| {
            let overrides = RenderOverrides::default();
            load_edited_scene_with_progress(&scene, &[], &overrides, BuildQuality::Auto, progress)
                .unwrap()
        };
        let (quiet, quiet_timings) = load(&LoadProgress::unmetered());
        assert_eq!(quiet_timings.load_peak_bytes, None);
        assert_eq!(quiet_timings.build_peak_bytes, None);
        let (metered, _) = load(&LoadProgress::default());
        let shape = |s: &Scene| (s.geometry.primitive_count(), s.geometry.accel_bytes());
        assert_eq!(shape(&quiet), shape(&metered));
    }

    /// A mesh that its transform carries past f32's range is an error
    /// naming the mesh and its first triangle out of range.
    #[test]
    fn a_triangle_past_f32_after_its_transform_is_an_error() {
        let dir = std::env::temp_dir().join(format!("strata-inf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("m.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e30 0 0\nf 1 2 3\nf 1 2 3\nf 1 2 4\n",
        )
        .unwrap();
        let scene = dir.join("s.toml");
        std::fs::write(
            &scene,
            "[[objects]]\nmesh = \"m.obj\"\ntransform = { scale = 1e9 }\n",
        )
        .unwrap();
        let e = load_scene(&scene, &RenderOverrides::default(), BuildQuality::Auto).unwrap_err();
        assert!(e.to_string().contains("triangle 2 is not finite"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A render's `auto` build is the preview tree when the render
    /// traces few rays per triangle and a better one's when it traces
    /// many; tracing a mesh file keeps the default whatever the settings.
    #[test]
    fn auto_bvh_effort_follows_the_renders_rays() {
        let dir = std::env::temp_dir().join(format!("strata-auto-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = dir.join("grid.ply");
        let n = 230u32; // 105,800 triangles
        let mut ply = format!("ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n", (n + 1) * (n + 1), n * n).into_bytes();
        for k in 0..(n + 1) * (n + 1) {
            let (i, j) = ((k % (n + 1)) as f32, (k / (n + 1)) as f32);
            for c in [i, j, (i * 0.37).sin() + (j * 0.21).cos()] {
                ply.extend(c.to_le_bytes());
            }
        }
        for q in 0..n * n {
            let a = (q / n) * (n + 1) + q % n;
            ply.push(4);
            for v in [a, a + 1, a + n + 2, a + n + 1] {
                ply.extend((v as i32).to_le_bytes());
            }
        }
        std::fs::write(&mesh, ply).unwrap();
        let scene = dir.join("s.toml");
        std::fs::write(&scene, "[[lights]]\ntype = \"point\"\nposition = [0, 0, 500]\nintensity = [1, 1, 1]\n[[objects]]\nmesh = \"grid.ply\"\n").unwrap();
        let tree = |spp: u32, quality: BuildQuality| {
            let overrides = RenderOverrides {
                width: Some(64),
                height: Some(64),
                spp: Some(spp),
                ..Default::default()
            };
            let (s, timings) = load_scene(&scene, &overrides, quality).unwrap();
            (s.geometry.bvh.stats(), timings.bvh_quality)
        };
        let (preview, medium) = (
            tree(1, BuildQuality::Preview),
            tree(1, BuildQuality::Medium),
        );
        assert_ne!(
            preview.0, medium.0,
            "the presets must differ for the test to mean anything"
        );
        assert_eq!(
            (preview.1, medium.1),
            (BuildQuality::Preview, BuildQuality::Medium)
        );
        // 64·64·1·2 rays, 0.08 a triangle; 64·64·4096·2, 317 a triangle,
        // pay for a better tree (`accel::choice`). The timings name the
        // preset used.
        assert_eq!(tree(1, BuildQuality::Auto), preview);
        let many = BuildQuality::Auto.choose(105_800, Some(64 * 64 * 4096 * 2));
        assert_ne!(many.quality, BuildQuality::Preview);
        assert_eq!(tree(4096, BuildQuality::Auto), tree(1, many.quality));
        let (traced, timings) = load_mesh_scene(&mesh, BuildQuality::Auto).unwrap();
        assert_eq!((traced.geometry.bvh.stats(), timings.bvh_quality), medium);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn file_settings_then_command_line_and_each_error_names_its_layer() {
        let text = "[render]\nwidth = 32\nheight = 16\nspp = 8\n";
        let cli = RenderOverrides {
            spp: Some(2),
            ..Default::default()
        };
        let s = scene_from_str(text, Path::new("t.toml"), &cli).unwrap();
        assert_eq!(
            (s.settings.width, s.settings.height, s.settings.spp),
            (32, 16, 2)
        );
        let e = rejected("[render]\nspp = 0\n");
        assert_eq!(
            (e.file.as_str(), e.location.as_str()),
            ("t.toml", "render.spp")
        );
        let zero = RenderOverrides {
            reflection_samples: Some(0),
            ..Default::default()
        };
        let e = scene_from_str("", Path::new("t.toml"), &zero).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.location.as_str()),
            ("<command line>", "--reflection-samples 0")
        );
    }

    #[test]
    fn primitives_are_numbered_triangles_first_and_planes_stay_outside_the_bvh() {
        let s = compiled(
            r#"
[[objects]]
sphere = { radius = 1.0 }
[[objects]]
plane = { normal = [0.0, 1.0, 0.0] }
[[objects]]
triangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }
"#,
        );
        let g = &s.geometry;
        assert_eq!(
            (g.triangle_count, g.shapes.len(), g.planes.len()),
            (1, 1, 1)
        );
        assert_eq!(g.primitive_count(), 2, "the plane is not a BVH primitive");
        let mut ids: Vec<u32> = g
            .leaf_slots()
            .filter(|&id| id != crate::accel::NO_PRIM)
            .collect();
        ids.sort();
        assert_eq!(ids, [0, 1], "triangle 0, then the sphere");
    }

    #[test]
    fn an_empty_scene_compiles_to_an_empty_tree_with_the_default_camera() {
        let s = compiled("");
        assert_eq!(s.geometry.primitive_count(), 0);
        assert!(s
            .geometry
            .intersect(&crate::math::Ray::new(glam::Vec3::ZERO, glam::Vec3::X))
            .is_none());
        assert_eq!(s.materials.len(), 1, "material 0, the default grey");
        assert!(matches!(s.camera, crate::camera::Camera::Perspective(_)));
    }
}

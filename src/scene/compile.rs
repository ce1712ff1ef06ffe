//! Description → [`Scene`]: flatten the object tree into plain arrays,
//! validate every number on the way, and build the BVH.
//!
//! Meshes are baked into world space. Analytic shapes keep their object
//! space unless the transform is a similarity (then a sphere is baked into
//! a new centre and radius, exactly). Infinite planes stay out of the BVH.

use super::asset::{LoadedAsset, LoadedCamera};
use super::description::*;
use super::loaders::load_mesh_file;
use super::settings::RenderOverrides;
use super::{RenderSettings, Scene};
use crate::accel::prefetch::Prefetch;
use crate::accel::{BuildQuality, Bvh8};
use crate::camera::{Camera, Orthographic, Perspective, ThinLens, View};
use crate::error::{InputError, InputResult};
use crate::geometry::csg::Csg;
use crate::geometry::{AnalyticPrim, Geometry, MeshNormals, MeshRange, Shape, NO_TRANSFORM};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Aabb, Frame, Transform};
use crate::shape::cylinder::Cylinder;
use crate::shape::disk::Disk;
use crate::shape::plane::Plane;
use crate::shape::rect::Rect;
use crate::shape::sphere::Sphere;
use crate::shape::triangle8::{TriangleBlock, LANES};
use crate::system::memory::PeakMeter;
use glam::{Affine3A, Mat3, Mat4, Quat, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

mod csg;

/// Wall time of each loading phase, and how far resident memory rose above
/// its level before loading during each (see [`PeakMeter`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct LoadTimings {
    pub load: Duration,
    pub bvh_build: Duration,
    pub load_peak_bytes: Option<u64>,
    pub build_peak_bytes: Option<u64>,
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
    let start = Instant::now();
    let desc = super::parse::read_description(path)?;
    compile(&desc, path, overrides, quality, start)
}

/// Compile scene text as if read from `path` (meshes resolve relative to
/// it), with the default BVH build effort.
pub fn scene_from_str(text: &str, path: &Path, overrides: &RenderOverrides) -> InputResult<Scene> {
    let desc = super::parse::parse_description(path, text)?;
    compile(&desc, path, overrides, BuildQuality::Auto, Instant::now()).map(|(scene, _)| scene)
}

/// A scene of one mesh file used as it is (no transform, default camera and
/// materials), compiled exactly as a scene file holding only
/// `[[objects]] mesh = "PATH"` would be. Triangle `i` of the file is
/// primitive `i`. This is what `strata trace` and `strata rays` intersect,
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
    // and every error names it.
    compile(
        &desc,
        path,
        &RenderOverrides::default(),
        quality,
        Instant::now(),
    )
}

/// Compile a parsed description; `path` is the scene file (meshes are
/// relative to it), `overrides` the command line's render settings.
pub fn compile(
    desc: &SceneDescription,
    path: &Path,
    overrides: &RenderOverrides,
    quality: BuildQuality,
    start: Instant,
) -> InputResult<(Scene, LoadTimings)> {
    let mut memory = PeakMeter::start();
    let mut c = Compiler::new(path);
    for (name, m) in &desc.materials {
        let key = format!("materials.{name}");
        let material = c.material(m, &key)?;
        c.add_material(name.clone(), material);
    }
    for (i, light) in desc.lights.iter().enumerate() {
        c.light(light, &format!("lights[{i}]"))?;
    }
    for (i, obj) in desc.objects.iter().enumerate() {
        c.object(obj, &format!("objects[{i}]"), Affine3A::IDENTITY, 0)?;
    }
    let settings = c.settings(&desc.render, overrides)?;
    let camera = c.camera(desc.camera.as_ref(), &settings)?;
    // Every object holds what it needs from its mesh files by now.
    drop(std::mem::take(&mut c.assets));
    let load = start.elapsed();
    let load_peak_bytes = memory.next_phase();

    // Area lights were recorded by shape index; make them global primitive ids.
    let n_tris = c.meshes.last().map_or(0, |m| m.first + m.count);
    for light in &mut c.lights {
        if let Light::Rect { prim, .. } | Light::Disk { prim, .. } | Light::Sphere { prim, .. } =
            light
        {
            *prim += n_tris;
        }
    }

    let build_start = Instant::now();
    let boxes = c.primitive_boxes()?;
    let mut bvh = Bvh8::build_from(boxes, quality);
    // The builder reserves room for more nodes than the collapse makes.
    bvh.nodes.shrink_to_fit();
    // Store the vertices once, in the order the leaves read them, straight
    // from the (indexed) sources, with the leaf ids beside them: never two
    // copies of the triangles, and the BVH's own ids become redundant.
    let leaf_blocks = leaf_blocks(&c.meshes, &c.sources, &bvh.prim_ids);
    bvh.prim_ids = Vec::new();
    drop(std::mem::take(&mut c.sources));
    let timings = LoadTimings {
        load,
        bvh_build: build_start.elapsed(),
        load_peak_bytes,
        build_peak_bytes: memory.phase_peak(),
    };
    let mut geometry = Geometry {
        leaf_blocks,
        triangle_count: n_tris,
        meshes: c.meshes,
        shapes: c.shapes,
        transforms: c.transforms,
        csg: c.csg,
        planes: c.planes,
        bvh,
    };
    geometry.bvh.prefetch = Prefetch::Auto.enabled(geometry.traversal_bytes());
    let scene = Scene {
        geometry,
        materials: c.materials,
        lights: c.lights,
        camera,
        settings,
    };
    Ok((scene, timings))
}

struct Compiler {
    file: PathBuf,
    base_dir: PathBuf,
    /// The triangles of each entry of `meshes`.
    sources: Vec<TriangleSource>,
    meshes: Vec<MeshRange>,
    shapes: Vec<AnalyticPrim>,
    transforms: Vec<Transform>,
    csg: Csg,
    planes: Vec<Plane>,
    materials: Vec<Material>,
    material_ids: HashMap<String, u32>,
    lights: Vec<Light>,
    loaded_cameras: Vec<LoadedCamera>,
    /// Mesh files already read, with the scene index of their first material.
    assets: HashMap<PathBuf, (Rc<LoadedAsset>, u32)>,
}

/// The triangles of one [`MeshRange`] until the BVH is built. A mesh file's
/// meshes stay indexed (world-space positions and the file's indices, about
/// 18 bytes per triangle instead of 36), so the build runs beside half the
/// memory and the triangles are expanded once, in leaf order, afterwards.
enum TriangleSource {
    Soup(Vec<[Vec3; 3]>),
    Indexed {
        positions: Vec<Vec3>,
        /// Checked against `positions` when made.
        indices: Vec<[u32; 3]>,
    },
}

impl TriangleSource {
    fn len(&self) -> usize {
        match self {
            Self::Soup(t) => t.len(),
            Self::Indexed { indices, .. } => indices.len(),
        }
    }

    #[inline]
    fn get(&self, i: usize) -> [Vec3; 3] {
        match self {
            Self::Soup(t) => t[i],
            Self::Indexed { positions, indices } => indices[i].map(|k| positions[k as usize]),
        }
    }
}

/// The BVH's leaf slots as 8-wide triangle blocks (see
/// [`Geometry::leaf_blocks`]), read from the indexed sources.
fn leaf_blocks(
    meshes: &[MeshRange],
    sources: &[TriangleSource],
    prim_ids: &[u32],
) -> Vec<TriangleBlock> {
    use rayon::prelude::*;
    prim_ids
        .par_chunks(LANES)
        .map(|ids| {
            let mut block = TriangleBlock::EMPTY;
            for (lane, &id) in ids.iter().enumerate() {
                let k = meshes.partition_point(|m| m.first + m.count <= id);
                match (meshes.get(k), sources.get(k)) {
                    (Some(m), Some(src)) if id >= m.first => {
                        block.set(lane, &src.get((id - m.first) as usize), id)
                    }
                    _ => block.id[lane] = id,
                }
            }
            block
        })
        .collect()
}

fn finite3(v: V3, key: &str, file: &Path) -> InputResult<Vec3> {
    let v = Vec3::from(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(InputError::new(
            file,
            key,
            format!("must be finite, got {v:?}"),
        ))
    }
}

/// An object's transform and material, after [`Compiler::placement`].
struct Placement {
    /// Object to world, including every enclosing transform.
    m: Affine3A,
    /// Its own material, or the inherited one.
    material: u32,
    /// Its own `material` key, if it has one.
    explicit_material: Option<u32>,
}

impl Compiler {
    fn new(path: &Path) -> Self {
        let mut c = Self {
            file: path.to_path_buf(),
            base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            sources: Vec::new(),
            meshes: Vec::new(),
            shapes: Vec::new(),
            transforms: Vec::new(),
            csg: Csg::default(),
            planes: Vec::new(),
            materials: Vec::new(),
            material_ids: HashMap::new(),
            lights: Vec::new(),
            loaded_cameras: Vec::new(),
            assets: HashMap::new(),
        };
        // Material 0: what objects get when nothing names one.
        c.materials.push(Material::default());
        c
    }

    fn err(&self, key: &str, message: impl Into<String>) -> InputError {
        InputError::new(&self.file, key, message)
    }

    fn v3(&self, v: V3, key: &str) -> InputResult<Vec3> {
        finite3(v, key, &self.file)
    }

    fn finite(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be finite, got {x}")))
        }
    }

    fn positive(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a positive finite number, got {x}")))
        }
    }

    fn non_negative(&self, x: f32, key: &str) -> InputResult<f32> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number ≥ 0, got {x}")))
        }
    }

    fn colour(&self, v: V3, key: &str) -> InputResult<Vec3> {
        let c = self.v3(v, key)?;
        if c.min_element() < 0.0 {
            return Err(self.err(key, format!("must not be negative, got {c:?}")));
        }
        Ok(c)
    }

    fn direction(&self, v: V3, key: &str) -> InputResult<Vec3> {
        let d = self.v3(v, key)?;
        d.try_normalize()
            .ok_or_else(|| self.err(key, "must be a non-zero vector"))
    }

    fn add_material(&mut self, name: String, m: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.materials.push(m);
        self.material_ids.insert(name, id);
        id
    }

    fn material(&self, m: &MaterialDesc, key: &str) -> InputResult<Material> {
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
        })
    }

    /// Validate a light and add it; area lights also become visible,
    /// one-sided emitting primitives.
    fn light(&mut self, l: &LightDesc, key: &str) -> InputResult<()> {
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
    fn emitter(&mut self, shape: Shape, radiance: Vec3, one_sided: bool) -> u32 {
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

    fn transform(&self, t: &TransformDesc, key: &str) -> InputResult<Affine3A> {
        if let Some(m) = t.matrix {
            if t.translate.is_some() || t.rotate.is_some() || t.scale.is_some() {
                return Err(self.err(
                    key,
                    "give either `matrix` or translate/rotate/scale, not both",
                ));
            }
            let mk = format!("{key}.matrix");
            if m.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(&mk, "must be finite"));
            }
            if m[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err(self.err(
                    &mk,
                    "last row must be [0, 0, 0, 1] (affine transforms only)",
                ));
            }
            // Row-major in the file; glam is column-major.
            return Ok(Affine3A::from_mat4(
                Mat4::from_cols_array_2d(&m).transpose(),
            ));
        }
        let translate = match t.translate {
            Some(v) => self.v3(v, &format!("{key}.translate"))?,
            None => Vec3::ZERO,
        };
        let rotate = match t.rotate {
            Some([x, y, z, deg]) => {
                let rk = format!("{key}.rotate");
                let axis = self.direction([x, y, z], &rk)?;
                Quat::from_axis_angle(axis, self.finite(deg, &rk)?.to_radians())
            }
            None => Quat::IDENTITY,
        };
        let scale = match t.scale {
            Some(ScaleDesc::Uniform(s)) => Vec3::splat(s),
            Some(ScaleDesc::PerAxis(v)) => Vec3::from(v),
            None => Vec3::ONE,
        };
        if !scale.is_finite() || scale.abs().min_element() == 0.0 {
            return Err(self.err(
                &format!("{key}.scale"),
                format!("must be finite and non-zero, got {scale:?}"),
            ));
        }
        Ok(Affine3A::from_scale_rotation_translation(
            scale, rotate, translate,
        ))
    }

    fn push_transform(&mut self, m: Affine3A, key: &str) -> InputResult<u32> {
        let t = Transform::new(m)
            .ok_or_else(|| self.err(key, "transform is singular or not finite"))?;
        self.transforms.push(t);
        Ok(self.transforms.len() as u32 - 1)
    }

    /// What every object has besides its shape: exactly one shape key, a
    /// known material (or the inherited one) and an invertible transform.
    fn placement(
        &self,
        obj: &ObjectDesc,
        key: &str,
        parent: Affine3A,
        inherited: u32,
    ) -> InputResult<Placement> {
        let shapes = [
            obj.sphere.is_some(),
            obj.plane.is_some(),
            obj.cylinder.is_some(),
            obj.triangle.is_some(),
            obj.mesh.is_some(),
            obj.group.is_some(),
            obj.csg.is_some(),
        ];
        match shapes.iter().filter(|&&s| s).count() {
            1 => {}
            0 => {
                return Err(self.err(
                    key,
                    "needs one of sphere, plane, cylinder, triangle, mesh, group or csg",
                ));
            }
            _ => return Err(self.err(key, "has more than one shape key; use a group for several")),
        }
        let explicit_material = match &obj.material {
            Some(name) => Some(*self.material_ids.get(name).ok_or_else(|| {
                self.err(
                    &format!("{key}.material"),
                    format!("unknown material '{name}'"),
                )
            })?),
            None => None,
        };
        let m = match &obj.transform {
            Some(t) => parent * self.transform(t, &format!("{key}.transform"))?,
            None => parent,
        };
        if Transform::new(m).is_none() {
            return Err(self.err(
                &format!("{key}.transform"),
                "transform is singular or not finite",
            ));
        }
        Ok(Placement {
            m,
            material: explicit_material.unwrap_or(inherited),
            explicit_material,
        })
    }

    fn object(
        &mut self,
        obj: &ObjectDesc,
        key: &str,
        parent: Affine3A,
        inherited: u32,
    ) -> InputResult<()> {
        let Placement {
            m,
            material,
            explicit_material,
        } = self.placement(obj, key, parent, inherited)?;

        if let Some(s) = &obj.sphere {
            let sphere = self.sphere_desc(s, key)?;
            self.sphere(sphere, m, material, key)?;
        } else if let Some(p) = &obj.plane {
            let point = self.v3(p.point, &format!("{key}.plane.point"))?;
            let normal = self.direction(p.normal, &format!("{key}.plane.normal"))?;
            let t = Transform::new(m).expect("checked above");
            self.planes.push(Plane {
                point: t.point(point),
                normal: t.normal(normal),
                material,
            });
        } else if let Some(cyl) = &obj.cylinder {
            let (cylinder, place) = self.cylinder_desc(cyl, key)?;
            let t = self.push_transform(m * place, &format!("{key}.transform"))?;
            self.shapes.push(AnalyticPrim {
                shape: Shape::Cylinder(cylinder),
                transform: t,
                material,
            });
        } else if let Some(tri) = &obj.triangle {
            let mut v = [Vec3::ZERO; 3];
            for (i, p) in tri.v.iter().enumerate() {
                v[i] = m.transform_point3(self.v3(*p, &format!("{key}.triangle.v[{i}]"))?);
            }
            self.push_mesh(
                key.to_string(),
                TriangleSource::Soup(vec![v]),
                material,
                None,
            );
        } else if let Some(file) = &obj.mesh {
            self.mesh_file(file, key, m, explicit_material, inherited)?;
        } else if let Some(children) = &obj.group {
            for (i, child) in children.iter().enumerate() {
                self.object(child, &format!("{key}.group[{i}]"), m, material)?;
            }
        } else if let Some(c) = &obj.csg {
            self.csg_object(c, key, m, material, explicit_material)?;
        }
        Ok(())
    }

    fn sphere_desc(&self, s: &SphereDesc, key: &str) -> InputResult<Sphere> {
        Ok(Sphere {
            center: self.v3(s.center, &format!("{key}.sphere.center"))?,
            radius: self.positive(s.radius, &format!("{key}.sphere.radius"))?,
        })
    }

    /// The canonical cylinder (along +z from the origin) and the frame that
    /// places it at `base` along `axis`.
    fn cylinder_desc(&self, cyl: &CylinderDesc, key: &str) -> InputResult<(Cylinder, Affine3A)> {
        let k = |f: &str| format!("{key}.cylinder.{f}");
        let base = self.v3(cyl.base, &k("base"))?;
        let axis = self.direction(cyl.axis, &k("axis"))?;
        let radius = self.positive(cyl.radius, &k("radius"))?;
        let height = self.positive(cyl.height, &k("height"))?;
        let f = Frame::from_z(axis);
        let place = Affine3A::from_mat3_translation(Mat3::from_cols(f.x, f.y, f.z), base);
        let cylinder = Cylinder {
            radius,
            height,
            caps: cyl.caps,
        };
        Ok((cylinder, place))
    }

    /// A sphere under `m`: baked into a new centre and radius when `m` is a
    /// similarity, else kept in object space with `m` returned.
    fn placed_sphere(
        &self,
        s: Sphere,
        m: Affine3A,
        key: &str,
    ) -> InputResult<(Sphere, Option<Affine3A>)> {
        let Some(scale) = similarity_scale(&m) else {
            return Ok((s, Some(m)));
        };
        // Rotation, uniform scale and translation map a sphere to a sphere exactly.
        let baked = Sphere {
            center: m.transform_point3(s.center),
            radius: s.radius * scale,
        };
        if !(baked.center.is_finite() && baked.radius.is_finite() && baked.radius > 0.0) {
            return Err(self.err(key, "sphere is not finite after its transform"));
        }
        Ok((baked, None))
    }

    fn sphere(&mut self, s: Sphere, m: Affine3A, material: u32, key: &str) -> InputResult<()> {
        let (sphere, transform) = self.placed_sphere(s, m, key)?;
        let transform = match transform {
            Some(m) => self.push_transform(m, &format!("{key}.transform"))?,
            None => NO_TRANSFORM,
        };
        self.shapes.push(AnalyticPrim {
            shape: Shape::Sphere(sphere),
            transform,
            material,
        });
        Ok(())
    }

    fn push_mesh(
        &mut self,
        name: String,
        tris: TriangleSource,
        material: u32,
        normals: Option<MeshNormals>,
    ) {
        if tris.len() == 0 {
            return;
        }
        let first = self.meshes.last().map_or(0, |m| m.first + m.count);
        let count = tris.len() as u32;
        self.sources.push(tris);
        self.meshes.push(MeshRange {
            name,
            first,
            count,
            material,
            normals,
        });
    }

    /// A mesh file's contents and the scene index of its first material,
    /// read (and its materials registered) once per file.
    fn asset(&mut self, file: &str, key: &str) -> InputResult<(Rc<LoadedAsset>, u32, PathBuf)> {
        let path = self.base_dir.join(file);
        if !self.assets.contains_key(&path) {
            let asset = load_mesh_file(&path).map_err(|e| {
                // Say which object pulled the file in, keeping the mesh file's own location.
                if e.file == path.display().to_string() {
                    e
                } else {
                    e.within(&format!("{key}.mesh"))
                }
            })?;
            let first_material = self.materials.len() as u32;
            for (name, mat) in &asset.materials {
                self.materials.push(*mat);
                self.material_ids
                    .entry(format!("{file}:{name}"))
                    .or_insert(self.materials.len() as u32 - 1);
            }
            self.assets
                .insert(path.clone(), (Rc::new(asset), first_material));
        }
        let (asset, first_material) = self.assets.get(&path).expect("inserted above").clone();
        Ok((asset, first_material, path))
    }

    fn mesh_file(
        &mut self,
        file: &str,
        key: &str,
        m: Affine3A,
        explicit_material: Option<u32>,
        inherited: u32,
    ) -> InputResult<()> {
        let (asset, first_material, path) = self.asset(file, key)?;
        let t = Transform::new(m).expect("checked by the caller");
        for mesh in &asset.meshes {
            check_indices(mesh, &path)?;
            let tris = TriangleSource::Indexed {
                positions: mesh.positions.iter().map(|&p| t.point(p)).collect(),
                indices: mesh.indices.clone(),
            };
            let normals = mesh.normals.as_ref().map(|n| MeshNormals {
                values: n.values.iter().map(|&v| t.normal_to_world * v).collect(),
                indices: n.indices.clone(),
            });
            let material = explicit_material
                .or(mesh.material.map(|i| first_material + i as u32))
                .unwrap_or(inherited);
            let name = if mesh.name.is_empty() {
                key.to_string()
            } else {
                mesh.name.clone()
            };
            self.push_mesh(name, tris, material, normals);
        }
        for light in &asset.point_lights {
            self.lights.push(Light::Point {
                position: t.point(light.position),
                intensity: light.intensity,
            });
        }
        for cam in &asset.cameras {
            self.loaded_cameras.push(LoadedCamera {
                position: t.point(cam.position),
                forward: t.vector(cam.forward),
                up: t.vector(cam.up),
                ..cam.clone()
            });
        }
        Ok(())
    }

    /// The file's `[render]` table under the command line's overrides;
    /// a bad value names the layer it came from.
    fn settings(
        &self,
        file: &RenderOverrides,
        cli: &RenderOverrides,
    ) -> InputResult<RenderSettings> {
        file.check()
            .map_err(|(field, message)| self.err(&format!("render.{field}"), message))?;
        cli.check().map_err(|(field, message)| {
            InputError::new(
                "<command line>",
                format!("--{}", field.replace('_', "-")),
                message,
            )
        })?;
        Ok(RenderSettings::merge(&[file, cli]))
    }

    fn camera(&self, desc: Option<&CameraDesc>, s: &RenderSettings) -> InputResult<Camera> {
        let (w, h) = (s.width, s.height);
        let Some(d) = desc else {
            if let Some(cam) = self.loaded_cameras.first() {
                let view =
                    View::looking(cam.position, cam.forward, cam.up, w, h).ok_or_else(|| {
                        self.err(
                            "camera",
                            "the mesh file's camera has a degenerate orientation",
                        )
                    })?;
                return Ok(match (cam.yfov_degrees, cam.ortho_height) {
                    (_, Some(height)) => Camera::Orthographic(Orthographic::new(view, height)),
                    (fov, None) => Camera::Perspective(Perspective::new(view, fov.unwrap_or(40.0))),
                });
            }
            return self.camera(Some(&CameraDesc::default()), s);
        };
        let position = self.v3(d.position, "camera.position")?;
        let look_at = self.v3(d.look_at, "camera.look_at")?;
        let up = self.v3(d.up, "camera.up")?;
        if position == look_at {
            return Err(self.err(
                "camera.look_at",
                "equals camera.position, so there is no view direction",
            ));
        }
        let view = View::look_at(position, look_at, up, w, h)
            .ok_or_else(|| self.err("camera.up", "is zero or parallel to the view direction"))?;
        let fov = |c: &Self| -> InputResult<f32> {
            let f = c.finite(d.fov, "camera.fov")?;
            if f > 0.0 && f < 180.0 {
                Ok(f)
            } else {
                Err(c.err(
                    "camera.fov",
                    format!("must be between 0 and 180 degrees, got {f}"),
                ))
            }
        };
        Ok(match d.kind {
            CameraType::Perspective => Camera::Perspective(Perspective::new(view, fov(self)?)),
            CameraType::Orthographic => Camera::Orthographic(Orthographic::new(
                view,
                self.positive(d.height, "camera.height")?,
            )),
            CameraType::ThinLens => {
                let focus_distance = match d.focus_distance {
                    Some(f) => self.positive(f, "camera.focus_distance")?,
                    None => (look_at - position).length(),
                };
                Camera::ThinLens(ThinLens {
                    pinhole: Perspective::new(view, fov(self)?),
                    aperture: self.non_negative(d.aperture, "camera.aperture")?,
                    focus_distance,
                })
            }
        })
    }

    fn primitive_boxes(&self) -> InputResult<Vec<Aabb>> {
        let n_tris = self
            .meshes
            .last()
            .map_or(0, |m| (m.first + m.count) as usize);
        let mut boxes = Vec::with_capacity(n_tris + self.shapes.len());
        for (mesh, source) in self.meshes.iter().zip(&self.sources) {
            for i in 0..source.len() {
                let b = Aabb::from_points(&source.get(i));
                if !b.is_finite() {
                    return Err(self.err(&mesh.name, format!("triangle {i} is not finite")));
                }
                boxes.push(b);
            }
        }
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

/// Every vertex index of a loaded mesh is in range.
fn check_indices(mesh: &super::asset::LoadedMesh, path: &Path) -> InputResult<()> {
    let n_vertices = mesh.positions.len();
    match mesh
        .indices
        .iter()
        .position(|idx| idx.iter().any(|&i| i as usize >= n_vertices))
    {
        Some(f) => Err(InputError::new(
            path,
            format!("face {f}"),
            "vertex index out of range",
        )),
        None => Ok(()),
    }
}

/// A loaded mesh's triangles in file space, with every index checked.
fn mesh_triangles(mesh: &super::asset::LoadedMesh, path: &Path) -> InputResult<Vec<[Vec3; 3]>> {
    check_indices(mesh, path)?;
    Ok(mesh
        .indices
        .iter()
        .map(|idx| idx.map(|i| mesh.positions[i as usize]))
        .collect())
}

/// The uniform scale factor if `m`'s linear part is a similarity (rotation
/// times uniform scale, no shear, no reflection issue for spheres).
fn similarity_scale(m: &Affine3A) -> Option<f32> {
    let c = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let l = [c[0].length(), c[1].length(), c[2].length()];
    let s = l[0];
    let tol = 1e-6 * s;
    let equal = (l[1] - s).abs() <= tol && (l[2] - s).abs() <= tol;
    let orthogonal = c[0].dot(c[1]).abs() <= tol * s
        && c[1].dot(c[2]).abs() <= tol * s
        && c[0].dot(c[2]).abs() <= tol * s;
    (equal && orthogonal && s > 0.0).then_some(s)
}

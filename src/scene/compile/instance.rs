//! Instancing in the scene file: a mesh file placed more than once is read
//! and stored once, as a prototype with its own tree, and each placement
//! becomes an [`Instance`]; `instances = "FILE.csv"` gives an object many
//! placements at once, one row-major 3×4 object-to-world matrix per line.

use super::mesh::{check_attribute, check_indices, triangle_geometry, MeshOrigin, TriangleSource};
use super::Compiler;
use crate::accel::BuildChoice;
use crate::error::{io_message, InputError, InputResult};
use crate::geometry::{Geometry, Instance, MeshRange, NO_MATERIAL};
use crate::math::Transform;
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use crate::scene::description::ObjectDesc;
use crate::system::budget::{bytes_text, check_against, Budget};
use glam::{Affine3A, Mat3, Vec3};
use std::collections::HashMap;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A prototype's meshes until its tree is built, in file space.
pub(super) struct PrototypeParts {
    pub(super) meshes: Vec<MeshRange>,
    pub(super) sources: Vec<TriangleSource>,
    /// Where each mesh was first placed, for errors about its triangles.
    pub(super) origins: Vec<MeshOrigin>,
}

/// How many times each mesh file (by resolved path) is placed, counting
/// an object with `instances` (or inside a group that has them) as many:
/// the files placed more than once become prototypes.
pub(super) fn count_mesh_uses(
    base_dir: &Path,
    objects: &[ObjectDesc],
    times: u32,
    uses: &mut HashMap<PathBuf, u32>,
) {
    for obj in objects {
        let n = if obj.instances.is_some() {
            times.saturating_mul(2)
        } else {
            times
        };
        if let Some(file) = &obj.mesh {
            let count = uses.entry(base_dir.join(file)).or_insert(0);
            *count = count.saturating_add(n);
        }
        if let Some(children) = &obj.group {
            count_mesh_uses(base_dir, children, n, uses);
        }
    }
}

/// What one placement holds at the peak of a load, for weighing an
/// instances file before it is read: its matrix as read and as placed,
/// its [`Instance`], its box in the scene's tree, and its share of the
/// tree and of the build's scratch (held above the measured peak by
/// tests/suite/sizes.rs).
pub const PLACEMENT_BYTES: u64 =
    (2 * size_of::<Affine3A>() + size_of::<Instance>() + size_of::<crate::math::Aabb>()) as u64
        + 64;

/// The longest line an instances file may have: twelve numbers of any
/// sensible precision fit many times over, and a file that is one endless
/// line is refused instead of read whole.
const MAX_LINE_BYTES: usize = 4096;

/// How much of an instances file is read to estimate its rows before
/// the rest is: enough lines for a fair mean length, in no time.
const SAMPLE_BYTES: usize = 64 * 1024;

/// The placements of an instances file: one row-major 3×4 object-to-world
/// matrix per line (twelve numbers separated by commas, spaces or tabs);
/// blank lines and lines starting with `#` (numpy's `savetxt` header) are
/// skipped. Each is finite and invertible, or the error names the line.
/// The file is weighed against the machine's memory before it is read
/// (its length over its first lines' mean length), and again as it is.
pub fn read_instances(path: &Path) -> InputResult<Vec<Affine3A>> {
    let budget = Budget::of_this_process();
    weigh_instances(path, budget, 0).map_err(|m| InputError::file(path, m))?;
    read_instances_within(path, budget, 0)
}

/// Whether the placements an instances file holds, estimated from its
/// length and its first lines, fit in `budget` with `placed` placements
/// made already: the error's message if not. A file that cannot be read
/// passes: reading it says why.
pub(super) fn weigh_instances(
    path: &Path,
    budget: Option<Budget>,
    placed: u64,
) -> Result<(), String> {
    let Ok(file) = std::fs::File::open(path) else {
        return Ok(());
    };
    let length = file.metadata().map_or(0, |m| m.len());
    let Ok(estimate) = estimated_rows(file, length) else {
        return Ok(());
    };
    let need = u128::from(placed + estimate) * u128::from(PLACEMENT_BYTES);
    let before = if placed > 0 {
        format!(", with the {placed} placed before")
    } else {
        String::new()
    };
    let what = format_args!(
        "a file of {} and about {estimate} placements ({PLACEMENT_BYTES} bytes each{before})",
        bytes_text(u128::from(length)),
    );
    check_against(budget, need, what)
}

/// The rows of an instances file, weighed again against `budget` (with
/// `placed` placements made already) as they pass what was estimated.
pub(super) fn read_instances_within(
    path: &Path,
    budget: Option<Budget>,
    placed: u64,
) -> InputResult<Vec<Affine3A>> {
    let cannot_read =
        |e: std::io::Error| InputError::file(path, format!("cannot read: {}", io_message(&e)));
    let file = std::fs::File::open(path).map_err(cannot_read)?;
    let mut reader = std::io::BufReader::new(file);
    let weigh = |rows: u64, what: std::fmt::Arguments| {
        let need = u128::from(placed + rows) * u128::from(PLACEMENT_BYTES);
        check_against(budget, need, what).map_err(|m| InputError::file(path, m))
    };
    let mut out: Vec<Affine3A> = Vec::new();
    let mut line = String::new();
    for i in 0.. {
        line.clear();
        let at = |message: String| InputError::new(path, "", message).on_line(Some(i + 1));
        let read = std::io::Read::take(&mut reader, MAX_LINE_BYTES as u64 + 1)
            .read_line(&mut line)
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::InvalidData => at("is not UTF-8 text".to_string()),
                _ => cannot_read(e),
            })?;
        if read == 0 {
            break;
        }
        if line.len() > MAX_LINE_BYTES {
            return Err(at(format!("is longer than {MAX_LINE_BYTES} bytes")));
        }
        let Some(affine) = parse_row(&line).map_err(at)? else {
            continue;
        };
        if out.len() == out.capacity() {
            // Weighed again as the rows pass the estimate.
            let rows = (out.capacity() as u64 * 2).max(64);
            let what = format_args!("reading more than {} placements", out.len());
            weigh(rows, what).map_err(|e| e.on_line(Some(i + 1)))?;
            out.try_reserve(rows as usize - out.len())
                .map_err(|_| at(format!("cannot allocate {rows} placements")))?;
        }
        out.push(affine);
    }
    Ok(out)
}

/// The rows of a file of `length` bytes, estimated from its first
/// [`SAMPLE_BYTES`]: their lines' mean length.
fn estimated_rows(file: std::fs::File, length: u64) -> std::io::Result<u64> {
    let mut head = Vec::new();
    file.take(SAMPLE_BYTES as u64).read_to_end(&mut head)?;
    let lines = head.iter().filter(|&&b| b == b'\n').count().max(1) as u64;
    Ok(if !head.is_empty() && (head.len() as u64) < length {
        length.div_ceil(head.len() as u64) * lines
    } else {
        lines
    })
}

/// One line of an instances file: `None` for a blank line or a comment,
/// else its matrix, or what is wrong with it.
fn parse_row(line: &str) -> Result<Option<Affine3A>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let fields: Vec<&str> = line
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|f| !f.is_empty())
        .collect();
    if fields.len() != 12 {
        return Err(format!(
            "expected 12 numbers (a row-major 3x4 object-to-world matrix), found {}",
            fields.len()
        ));
    }
    let mut m = [0.0f32; 12];
    for (k, f) in fields.iter().enumerate() {
        m[k] = match f.parse::<f32>() {
            Ok(x) if x.is_finite() => x,
            Ok(_) => return Err(format!("number {} ('{f}') is not finite", k + 1)),
            Err(_) => return Err(format!("number {} ('{f}') is not a number", k + 1)),
        };
    }
    let affine = Affine3A::from_mat3_translation(
        Mat3::from_cols(
            Vec3::new(m[0], m[4], m[8]),
            Vec3::new(m[1], m[5], m[9]),
            Vec3::new(m[2], m[6], m[10]),
        ),
        Vec3::new(m[3], m[7], m[11]),
    );
    if Transform::new(affine).is_none() {
        return Err("the matrix is singular (it has no inverse)".to_string());
    }
    Ok(Some(affine))
}

impl Compiler<'_> {
    /// The placements of an object: its own transform `m` alone, or `m`
    /// after each matrix of its `instances` file.
    pub(super) fn placements(
        &self,
        obj: &ObjectDesc,
        key: &str,
        m: Affine3A,
    ) -> InputResult<Vec<Affine3A>> {
        let Some(file) = &obj.instances else {
            return Ok(vec![m]);
        };
        let path = self.base_dir.join(file);
        if let Err(e) = std::fs::metadata(&path) {
            let message = format!("cannot read '{}': {}", path.display(), io_message(&e));
            return Err(self.err(&format!("{key}.instances"), message));
        }
        // Every placement made so far, the objects' and their instances'.
        let placed = (self.instances.len() + self.shapes.len()) as u64;
        let budget = Budget::of_this_process();
        weigh_instances(&path, budget, placed).map_err(|m| {
            self.err(
                &format!("{key}.instances"),
                format!("'{}': {m}", path.display()),
            )
        })?;
        let rows = read_instances_within(&path, budget, placed)?;
        let mut out = Vec::new();
        out.try_reserve_exact(rows.len()).map_err(|_| {
            let message = format!("cannot allocate {} placements", rows.len());
            self.err(&format!("{key}.instances"), message)
        })?;
        for a in rows {
            let placed = m * a;
            if Transform::new(placed).is_none() {
                let message = format!(
                    "an instance of '{}' is singular or not finite under the object's transform",
                    path.display()
                );
                return Err(self.err(&format!("{key}.transform"), message));
            }
            out.push(placed);
        }
        Ok(out)
    }

    /// A mesh file, as [`Compiler::asset`] gives it (its contents, the
    /// scene index of its first material, its path), placed by `m` as an
    /// instance of its prototype, made on its first placement.
    pub(super) fn mesh_instance(
        &mut self,
        file: &(Arc<LoadedAsset>, u32, PathBuf),
        (key, written): (&str, &str),
        m: Affine3A,
        explicit_material: Option<u32>,
        inherited: u32,
    ) -> InputResult<()> {
        let (asset, first_material, path) = file;
        let (first_material, path) = (*first_material, path.as_path());
        let prototype = self.prototype((path.to_path_buf(), None), || {
            let sources = asset.meshes.iter().enumerate().map(|(k, mesh)| {
                let source = TriangleSource::FileSpace {
                    asset: asset.clone(),
                    mesh: k,
                };
                (source, mesh)
            });
            prototype_parts(sources, first_material, path, (key, written))
        })?;
        let material = explicit_material.unwrap_or(NO_MATERIAL);
        let instance = Instance::new(m, prototype, material, inherited).ok_or_else(|| {
            self.err(
                &format!("{key}.transform"),
                "transform is singular or not finite",
            )
        })?;
        self.instances.push(instance);
        Ok(())
    }

    /// The index of the prototype of `id` (a mesh file, and which of its
    /// shared meshes: `None` for the meshes it places once), made by
    /// `parts` the first time.
    fn prototype(
        &mut self,
        id: (PathBuf, Option<usize>),
        parts: impl FnOnce() -> InputResult<PrototypeParts>,
    ) -> InputResult<u32> {
        if let Some(&p) = self.prototype_ids.get(&id) {
            return Ok(p);
        }
        self.prototypes.push(parts()?);
        let p = self.prototypes.len() as u32 - 1;
        self.prototype_ids.insert(id, p);
        Ok(p)
    }

    /// The meshes mesh file `file` itself places more than once (a glTF
    /// mesh several nodes use), each stored once as a prototype (made on
    /// the first placement of the file) and placed by one instance per
    /// placement in the file, after the object's placement `m`: one level
    /// of instances, the file's placements and the mesh's flattened.
    pub(super) fn shared_instances(
        &mut self,
        file: &(Arc<LoadedAsset>, u32, PathBuf),
        (key, written): (&str, &str),
        m: Affine3A,
        explicit_material: Option<u32>,
        inherited: u32,
    ) -> InputResult<()> {
        let (asset, first_material, path) = file;
        for (s, shared) in asset.shared.iter().enumerate() {
            let prototype = self.prototype((path.clone(), Some(s)), || {
                let sources = shared.parts.iter().enumerate().map(|(k, part)| {
                    let source = TriangleSource::Shared {
                        asset: asset.clone(),
                        shared: s,
                        part: k,
                    };
                    (source, part)
                });
                prototype_parts(sources, *first_material, path, (key, written))
            })?;
            let material = explicit_material.unwrap_or(NO_MATERIAL);
            for placement in &shared.placements {
                let to_world = m * placement.to_file;
                let instance = Instance::new(to_world, prototype, material, inherited);
                let instance = instance.ok_or_else(|| {
                    let message = format!(
                        "a placement of mesh '{}' in '{}' is singular or not finite \
                         under the object's transform",
                        shared.parts.first().map_or("", |p| p.name.as_str()),
                        path.display()
                    );
                    self.err(&format!("{key}.transform"), message)
                })?;
                self.instances.push(instance);
            }
        }
        Ok(())
    }
}

/// Meshes of a mesh file in the space a prototype keeps them in, each with
/// its triangles' source, with the materials the file gives them
/// ([`NO_MATERIAL`] where it gives none) and all their attributes.
fn prototype_parts<'a>(
    meshes: impl Iterator<Item = (TriangleSource, &'a LoadedMesh)>,
    first_material: u32,
    path: &Path,
    (key, written): (&str, &str),
) -> InputResult<PrototypeParts> {
    let mut parts = PrototypeParts {
        meshes: Vec::new(),
        sources: Vec::new(),
        origins: Vec::new(),
    };
    for (source, mesh) in meshes {
        check_indices(mesh, path)?;
        if let Some(normals) = &mesh.normals {
            check_attribute(normals, mesh, path, "normals")?;
        }
        if let Some(uvs) = &mesh.uvs {
            check_attribute(uvs, mesh, path, "texture coordinates")?;
        }
        if let Some(tangents) = &mesh.tangents {
            check_attribute(tangents, mesh, path, "tangents")?;
        }
        if mesh.indices.is_empty() {
            continue;
        }
        let first = parts.meshes.last().map_or(0, |m| m.first + m.count);
        parts.sources.push(source);
        parts.origins.push(MeshOrigin {
            key: format!("{key}.mesh"),
            file: Some((path.to_path_buf(), written.to_string(), mesh.name.clone())),
        });
        parts.meshes.push(MeshRange {
            name: if mesh.name.is_empty() {
                key.to_string()
            } else {
                mesh.name.clone()
            },
            first,
            count: mesh.indices.len() as u32,
            material: mesh
                .material
                .map_or(NO_MATERIAL, |i| first_material + i as u32),
            mirrored: mesh.mirrored,
            normals: mesh.normals.clone(),
            uvs: mesh.uvs.clone(),
            tangents: mesh.tangents.clone(),
        });
    }
    Ok(parts)
}

/// A prototype's tree over its triangles, and the prototype; a triangle
/// out of reach is named where its mesh was placed first.
pub(super) fn build_prototype(
    parts: PrototypeParts,
    choice: BuildChoice,
    compiler: &Compiler,
) -> InputResult<Geometry> {
    let PrototypeParts {
        meshes,
        sources,
        origins,
    } = parts;
    triangle_geometry(meshes, sources, choice)
        .map_err(|bad| compiler.out_of_reach_at(&origins[bad.index], &bad))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROW: &str = "1,0,0,0, 0,1,0,0, 0,0,1,0\n";

    fn file(name: &str, text: &str) -> (crate::scene::loaders::test_files::TempDir, PathBuf) {
        let dir = crate::scene::loaders::test_files::temp_dir(name);
        let path = dir.join("i.csv");
        std::fs::write(&path, text).unwrap();
        (dir, path)
    }

    /// A file is estimated from its length and first lines before it is
    /// read: rows past the budget are refused with the figures.
    #[test]
    fn an_instances_file_past_the_budget_is_refused_before_it_is_read() {
        let (_dir, path) = file("inst-weigh", &ROW.repeat(100));
        let fits = Some(Budget::given(100 * PLACEMENT_BYTES));
        assert!(weigh_instances(&path, fits, 0).is_ok());
        let e = weigh_instances(&path, fits, 1).unwrap_err();
        assert!(
            e.contains("about 100 placements") && e.contains("with the 1 placed before"),
            "{e}"
        );
        // A file far longer than its first lines (a sparse one here):
        // estimated from their mean length, not read.
        std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(1 << 40)
            .unwrap();
        let e = weigh_instances(&path, Some(Budget::given(1 << 30)), 0).unwrap_err();
        assert!(e.starts_with("a file of 1.0 TiB and about "), "{e}");
    }

    /// Rows past the estimate (long comment lines first, short rows
    /// after) are weighed again as they are read, at their line; a line
    /// past the longest a row may be is refused, not read whole.
    #[test]
    fn rows_past_the_estimate_are_weighed_as_they_are_read() {
        let comment = format!("# {}\n", "x".repeat(4000));
        let text = comment.repeat(17) + &ROW.repeat(20_000);
        let (_dir, path) = file("inst-stream", &text);
        let budget = Some(Budget::given(1000 * PLACEMENT_BYTES));
        assert!(weigh_instances(&path, budget, 0).is_ok());
        let e = read_instances_within(&path, budget, 0).unwrap_err();
        assert_eq!(e.line, Some(17 + 513), "{e}");
        assert!(
            e.message.starts_with("reading more than 512 placements"),
            "{e}"
        );
        assert_eq!(read_instances_within(&path, None, 0).unwrap().len(), 20_000);
        let (_dir, path) = file("inst-long", &"1".repeat(MAX_LINE_BYTES + 1));
        let e = read_instances_within(&path, None, 0).unwrap_err();
        assert!(
            e.to_string().contains("line 1: is longer than 4096 bytes"),
            "{e}"
        );
    }
}

//! `Mesh`: a triangle mesh with its BVH, and the queries on it.

use crate::args;
use crate::convert::{self, BadRays, RaySource, RaySpec};
use crate::mesh_objects;
use crate::results::{ClosestPoints, Crossings, Hits, HITS_KEYS};
use crate::run::{self, Threads, CHUNK, TASK};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyNotImplementedError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;
use strata::raycast::{self, BuildQuality, FirstHitColumns, PlaceError};

/// A triangle mesh and its BVH, built once (on every core) and asked any
/// number of queries.
///
/// ``Mesh(vertices, faces)`` takes an (n, 3) array of vertex positions
/// (any float dtype; strata computes in float32) and an (m, 3) array of
/// vertex indices (any integer dtype); face i is triangle i in every
/// answer. Lists and non-contiguous arrays are accepted. Degenerate faces
/// are kept (no ray hits them), so face ids stay yours.
///
/// Queries take (n, 3) ``origins`` and ``directions``, or (..., 3) of any
/// leading shape, whose answers come back in that shape (one ray given as
/// (3,) answers 0-d; one origin or one direction goes with every row of
/// the other, as numpy broadcasts it; any float dtype;
/// a direction need not be unit length, and ``t`` is measured in its
/// lengths), ``t_max`` (a number or one per ray) and ``t_min`` (a number):
/// a ray reports what lies in (t_min, t_max], (0, inf] by default. Every
/// query releases the GIL and runs on every core, or on at most
/// ``threads`` threads (an int; never more threads than it has tasks of
/// 256 rays or points, so a small query, or ``threads=1``, runs on the
/// calling thread); Ctrl-C stops it between chunks of 65,536 rays. Bad input
/// raises ``ValueError`` naming the argument; ``bad_rays="miss"`` makes a
/// ray with a NaN or infinite coordinate or a zero direction a miss
/// instead, as Open3D's and trimesh's engines answer it.
///
/// A mesh whose box lies farther from the origin than its size (UTM
/// coordinates) is traced relative to a centre near its middle, in float32
/// numbers of its own size; rays and points are moved there in float64.
/// Hit points and closest points are float64, computed on the triangle
/// the walk found as given, so they lie on its plane to float64's
/// precision wherever the mesh lies.
#[pyclass(frozen, module = "strata_rt._native")]
pub struct Mesh(
    raycast::Mesh,
    /// How many placements a placed mesh has (`Mesh.place`'s maps); 0 for
    /// a mesh that is not placed. For the repr: the library gives the maps
    /// only with a copy of the placed mesh's triangles.
    usize,
);

/// Rows `rows` of `column` (`width` values a row) cut into one piece per
/// task of `TASK` rows; an empty column (not asked for) into empty pieces.
fn task_pieces<T>(column: &mut [T], width: usize, rows: std::ops::Range<usize>) -> Vec<&mut [T]> {
    if column.is_empty() {
        let tasks = rows.len().div_ceil(TASK);
        return (0..tasks).map(|_| <&mut [T]>::default()).collect();
    }
    column[width * rows.start..width * rows.end]
        .chunks_mut(width * TASK)
        .collect()
}

/// A zeroed column of `len` values where `wanted`, else an empty one.
fn column<T: Clone + Default>(wanted: bool, len: usize) -> Vec<T> {
    if wanted {
        vec![T::default(); len]
    } else {
        Vec::new()
    }
}

/// Which of `Hits`' arrays a query was asked for (``fields``).
struct Fields([bool; 6]);

impl Fields {
    /// The arrays `fields` names: a sequence of names, or None for all.
    /// A str alone is refused in words (pyo3 would say it "can't extract
    /// `str` to `Vec`"), not read as a list of its letters.
    fn new(fields: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(fields) = fields.filter(|f| !f.is_none()) else {
            return Ok(Self([true; 6]));
        };
        if fields.cast::<pyo3::types::PyString>().is_ok() {
            let name = fields.repr()?;
            return Err(PyTypeError::new_err(format!(
                "fields must be a sequence of names such as (\"t\", \"prim\"); got the str {name}: write ({name},) for that one"
            )));
        }
        let names: Vec<String> = fields.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "fields must be a sequence of names from {}; got {}",
                HITS_KEYS.join(", "),
                fields
                    .repr()
                    .map_or_else(|_| "an object".to_string(), |r| r.to_string())
            ))
        })?;
        let mut wanted = [false; 6];
        for name in names {
            let Some(k) = HITS_KEYS.iter().position(|&key| key == name) else {
                return Err(PyValueError::new_err(format!(
                    "fields names {name:?}, which Hits does not have; it has {}",
                    HITS_KEYS.join(", ")
                )));
            };
            wanted[k] = true;
        }
        Ok(Self(wanted))
    }

    fn has(&self, key: &str) -> bool {
        HITS_KEYS
            .iter()
            .position(|&k| k == key)
            .is_some_and(|k| self.0[k])
    }
}

/// `values` (`n` items of `tail` values each) as an array of shape
/// `lead + tail`, the query's input's leading shape (`()` for one row
/// given as (3,)), or `(n,) + tail` without one.
fn shaped<T: numpy::Element>(
    py: Python<'_>,
    values: Vec<T>,
    lead: Option<&[usize]>,
    n: usize,
    tail: &[usize],
) -> PyResult<Py<PyArrayDyn<T>>> {
    let mut dims = match lead {
        None => vec![n],
        Some(lead) => lead.to_vec(),
    };
    dims.extend_from_slice(tail);
    Ok(PyArray1::from_vec(py, values).reshape(dims)?.unbind())
}

/// [`shaped`] where `wanted.0` (tail `wanted.1`), else None.
fn maybe<T: numpy::Element>(
    py: Python<'_>,
    wanted: (bool, &[usize]),
    values: Vec<T>,
    lead: Option<&[usize]>,
    n: usize,
) -> PyResult<Option<Py<PyArrayDyn<T>>>> {
    let (wanted, tail) = wanted;
    wanted
        .then(|| shaped(py, values, lead, n, tail))
        .transpose()
}

/// A flat vector of rows as an (n, 3) array.
pub fn rows<'py>(py: Python<'py>, rows: Vec<[f32; 3]>) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let n = rows.len();
    let flat: Vec<f32> = rows.into_iter().flatten().collect();
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

type CornerArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<i64>>);

/// Every corner's x, y, z of `tris`, in face order.
fn corner_coordinates(tris: Vec<[glam::Vec3; 3]>) -> Vec<f32> {
    tris.into_iter()
        .flat_map(|t| t.into_iter().flat_map(|p| p.to_array()))
        .collect()
}

/// `tris` as ``vertices`` (3m, 3) float32, one row per corner, and
/// ``faces`` (m, 3) int64 indexing them in order.
fn corner_arrays(py: Python<'_>, tris: Vec<[glam::Vec3; 3]>) -> PyResult<CornerArrays<'_>> {
    let m = tris.len();
    let vertices = PyArray1::from_vec(py, corner_coordinates(tris)).reshape([3 * m, 3])?;
    let faces = PyArray1::from_vec(py, (0..3 * m as i64).collect()).reshape([m, 3])?;
    Ok((vertices, faces))
}

impl Mesh {
    /// Vertices and faces: as given, or the faces' float64 corners merged
    /// by exact position (a loaded, placed or far mesh).
    fn indexed(&self) -> (Vec<glam::DVec3>, Vec<[u32; 3]>) {
        if let Some((vertices, faces)) = self.0.given() {
            return (vertices.to_vec(), faces.to_vec());
        }
        let mut index = std::collections::HashMap::new();
        let mut vertices = Vec::new();
        let faces = self
            .0
            .corner_positions()
            .iter()
            .map(|tri| {
                tri.map(|p| {
                    *index
                        .entry(p.to_array().map(f64::to_bits))
                        .or_insert_with(|| {
                            vertices.push(p);
                            vertices.len() as u32 - 1
                        })
                })
            })
            .collect();
        (vertices, faces)
    }

    /// A ray query's rays: its arguments checked (``ValueError`` naming
    /// the argument), to be read a chunk at a time, origins relative to
    /// the mesh's centre; and their leading shape.
    fn rays<'py>(
        &self,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        t_max: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
        bad_rays: &str,
    ) -> PyResult<(RaySource<'py>, Option<Vec<usize>>)> {
        let what = "a number >= 0, the same for every ray (None for 0)";
        let t_min = args::optional(t_min, |t| args::real(t, "t_min", what))?;
        let spec = RaySpec {
            t_min,
            t_max,
            bad: BadRays::new(bad_rays)?,
        };
        let (o, lead) = convert::rows3(origins)?;
        let (d, lead_d) = convert::rows3(directions)?;
        // One ray's worth of either, (3,) or (1, 3), goes with every row of
        // the other: the answers take the other's shape.
        let one = |lead: &[usize]| lead.iter().product::<usize>() == 1;
        let lead = match (lead, lead_d) {
            (Some(a), Some(b)) if a == b || one(&a) => Some(b),
            (Some(a), Some(b)) if one(&b) => Some(a),
            (Some(a), Some(b)) => {
                return Err(PyValueError::new_err(format!(
                    "origins and directions must have the same shape, or one of them a single row; got {a:?} and {b:?} before the last axis"
                )));
            }
            // An (n, 3) array with one row as (3,): the answers are (n,).
            (None, Some(one_row)) | (Some(one_row), None) if one(&one_row) => None,
            (a, b) => a.or(b),
        };
        // One t_max per ray of an (..., 3) array: in its leading shape.
        let flat_t_max = match (t_max, &lead) {
            (Some(t), Some(lead)) if !lead.is_empty() && t.hasattr("shape")? => {
                let shape: Vec<usize> = t.getattr("shape")?.extract()?;
                (&shape == lead)
                    .then(|| t.call_method1("reshape", (-1i64,)))
                    .transpose()?
            }
            _ => None,
        };
        let spec = RaySpec {
            t_max: flat_t_max.as_ref().or(spec.t_max),
            ..spec
        };
        let rays = convert::ray_source(&o, &d, &spec, self.0.centre())?;
        Ok((rays, lead))
    }
}

#[pymethods]
impl Mesh {
    /// Build the mesh and its BVH from ``vertices`` ((n, 3) floats) and
    /// ``faces`` ((m, 3) integer indices into ``vertices``), or from one
    /// mesh object that has them: a ``trimesh.Trimesh`` (``vertices``,
    /// ``faces``: ``Mesh(tm)``), an Open3D ``o3d.geometry.TriangleMesh``
    /// (``vertices``, ``triangles``) or ``o3d.t.geometry.TriangleMesh``
    /// (``vertex.positions``, ``triangle.indices``), read by what they
    /// have (neither library is imported).
    ///
    /// A vertex no face uses is never traced and may be anything (NaN,
    /// as a depth image's mesh keeps its missing pixels).
    ///
    /// Raises ValueError naming what is wrong: a shape or dtype, a
    /// vertex that a face uses and is NaN or infinite (``vertices[i]``,
    /// and the face), an index out of
    /// range (``faces[i][k]``); TypeError for one object without them
    /// (a ``trimesh.Scene``'s says how to get one mesh of it).
    #[new]
    #[pyo3(signature = (vertices, faces=None))]
    fn new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let (vertices, faces) = match faces {
            Some(faces) => (vertices.clone(), faces.clone()),
            None => mesh_objects::vertices_and_faces_of(vertices)?,
        };
        let vertices = convert::dvec3s(&vertices, "vertices")?;
        let faces = convert::faces(&faces, vertices.len())?;
        let mesh = py
            .detach(|| raycast::Mesh::new_exact(vertices, faces, BuildQuality::Auto))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Self(mesh, 0))
    }

    /// Load a mesh file (OBJ, PLY, glTF, GLB, OFF or STL) with strata's own
    /// loaders, used as it is: triangle i of the file is face i. ``path``
    /// is a str, an ``os.PathLike`` (``pathlib.Path``) or bytes, as
    /// ``os.fspath`` takes them; anything else raises TypeError. What the
    /// format can write in float64 is kept so, as trimesh reads it (OBJ,
    /// OFF and ASCII STL decimals, PLY ``double`` properties) and held as a
    /// mesh from those arrays is; PLY ``float``, binary STL and glTF
    /// coordinates are read as float32. Only the faces are read: no
    /// material library or texture, so a missing image is no error.
    ///
    /// A file strata cannot read raises ``strata_rt.InputError`` (a
    /// ValueError; FileNotFoundError if it does not exist) with strata's
    /// one-line message naming the file and the line or key. What it reads
    /// leniently, as other tools do (a file without faces), warns
    /// (``UserWarning``) in the same words.
    #[staticmethod]
    fn load(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let path = args::path(path, "path")?;
        let loaded = py.detach(|| raycast::Mesh::load(&path, BuildQuality::Auto));
        match loaded {
            Ok((mesh, warnings)) => {
                crate::render::warn_input(py, &warnings)?;
                Ok(Self(mesh, 0))
            }
            Err(e) if !path.exists() => Err(PyFileNotFoundError::new_err(e.to_string())),
            Err(e) => Err(crate::InputError::new_err(e.to_string())),
        }
    }

    /// Pickling: as ``Mesh(vertices, faces)`` of its triangles, one float32
    /// vertex row per corner, which answers every query bit for bit as
    /// this one does (hits depend on the triangles' corners alone, never
    /// on shared indices or on the tree); a mesh whose float64 vertices
    /// float32 does not hold exactly (most float64 arrays; hit points are
    /// computed on them) as ``Mesh(vertices, faces)`` of them as given,
    /// float64 and int64; a mesh far from the origin that float32 holds
    /// exactly relative to its centre as ``Mesh(vertices, faces)`` of its
    /// float64 ``vertices`` and ``faces``; a placed mesh as ``Mesh._placed(vertices, faces,
    /// transforms)``: the mesh it places, so, placed again by the same maps
    /// (float64 (n, 3, 4)).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let mesh = &slf.borrow().0;
        if let Some((vertices, faces)) = mesh.given() {
            // As given, in float64: the same centre, tree and answers.
            let n = vertices.len();
            let flat: Vec<f64> = vertices.iter().flat_map(|v| v.to_array()).collect();
            let vertices = PyArray1::from_vec(py, flat).reshape([n, 3])?;
            let idx: Vec<i64> = faces.iter().flatten().map(|&k| i64::from(k)).collect();
            let faces = PyArray1::from_vec(py, idx).reshape([faces.len(), 3])?;
            let args = (vertices, faces).into_pyobject(py)?.into_any();
            return Ok((slf.get_type().into_any(), args));
        }
        if mesh.centre() != glam::DVec3::ZERO {
            // Its corners in float64 (float32 would move them): the same
            // box, so the same centre, and the same numbers traced.
            let this = slf.borrow();
            let args = (this.vertices(py)?, this.faces(py)?).into_pyobject(py)?;
            return Ok((slf.get_type().into_any(), args.into_any()));
        }
        let Some((prototype, maps)) = mesh.placement() else {
            let (vertices, faces) = corner_arrays(py, mesh.triangles())?;
            let args = (vertices, faces).into_pyobject(py)?.into_any();
            return Ok((slf.get_type().into_any(), args));
        };
        let (vertices, faces) = corner_arrays(py, prototype)?;
        // Row-major 3 x 4, in f64 (each f32 exactly), as `place` reads them.
        let rows: Vec<f64> = maps
            .iter()
            .flat_map(|m| {
                let (c, t) = (m.matrix3, m.translation);
                (0..3).flat_map(move |r| [c.x_axis[r], c.y_axis[r], c.z_axis[r], t[r]])
            })
            .map(f64::from)
            .collect();
        let transforms = PyArray1::from_vec(py, rows).reshape([maps.len(), 3, 4])?;
        let args = (vertices, faces, transforms).into_pyobject(py)?.into_any();
        Ok((slf.get_type().getattr("_placed")?, args))
    }

    /// Unpickling a placed mesh: ``Mesh(vertices, faces).place(transforms)``.
    #[staticmethod]
    fn _placed(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        transforms: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        Self::new(py, vertices, Some(faces))?.place(py, transforms)
    }

    /// The number of triangles (faces); of a placed mesh, every copy's.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.0.triangle_count() as usize
    }

    /// The number of triangles (faces); of a placed mesh, every copy's.
    fn __len__(&self) -> usize {
        self.triangle_count()
    }

    /// This mesh placed once by each of ``transforms``: an (n, 3, 4) or
    /// (n, 4, 4) array of object-to-world matrices (row-major; a 4x4's last
    /// row must be [0, 0, 0, 1]). The mesh is stored once, each placement
    /// costs about 170 bytes, and rays enter it in its own space, as
    /// Embree's instances do. Every query answers as a mesh of every copy
    /// would (``Mesh(placed.triangles.reshape(-1, 3), ...)``), face
    /// ``k * triangle_count + j`` being face ``j`` of copy ``k``: each
    /// candidate triangle is moved to world space as that mesh holds it, so
    /// crossings (their t, ties at shared edges, counts, ``contains``) and
    /// nearest points and distances (world distances, under any map) are
    /// the copies', bit for bit. A placed mesh cannot be placed again.
    ///
    /// Raises ValueError naming ``transforms[i]`` for a matrix that is not
    /// finite or not invertible.
    fn place(&self, py: Python<'_>, transforms: &Bound<'_, PyAny>) -> PyResult<Self> {
        if self.0.is_placed() {
            return Err(PyNotImplementedError::new_err(
                "Mesh.place of a placed mesh: place the mesh itself, with each map \
                 composed with its placement",
            ));
        }
        let maps = convert::affine_maps(transforms, "transforms")?;
        match py.detach(|| self.0.place(&maps, BuildQuality::Auto)) {
            Ok(placed) => Ok(Self(placed, maps.len())),
            Err(PlaceError::Map(k)) => Err(PyValueError::new_err(format!(
                "transforms[{k}] is not invertible, or places the mesh beyond float32's range"
            ))),
            Err(e @ PlaceError::AlreadyPlaced) => {
                Err(PyNotImplementedError::new_err(e.to_string()))
            }
        }
    }

    /// float32 (2, 3): the [min, max] corners of the bounding box (inf and
    /// -inf for a mesh without triangles).
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        rows(py, self.0.bounds().map(|p| p.to_array()).to_vec())
    }

    /// float64 (n, 3): the faces' corners, each position once, in order of
    /// first use (``faces`` indexes them): a loaded file's vertices, less
    /// any that no face uses. A mesh from arrays far from the origin (held
    /// as given, in float64) gives its arrays back exactly.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (vertices, _) = self.indexed();
        let n = vertices.len();
        let flat: Vec<f64> = vertices.iter().flat_map(|v| v.to_array()).collect();
        PyArray1::from_vec(py, flat).reshape([n, 3])
    }

    /// int64 (m, 3): each face's vertex indices into ``vertices``, in face order.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let (_, faces) = self.indexed();
        let m = faces.len();
        let flat: Vec<i64> = faces.iter().flatten().map(|&k| i64::from(k)).collect();
        PyArray1::from_vec(py, flat).reshape([m, 3])
    }

    /// float32 (m, 3, 3): each face's three vertices, in face order (a copy
    /// of what the BVH stores).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let tris = self.0.triangles();
        let m = tris.len();
        PyArray1::from_vec(py, corner_coordinates(tris)).reshape([m, 3, 3])
    }

    fn __repr__(&self) -> String {
        let n = self.triangle_count();
        let counted = |n: usize, noun: &str| format!("{n} {noun}{}", if n == 1 { "" } else { "s" });
        // A placed mesh: its placements of the mesh it places, whose
        // triangles each placement repeats (len() counts them all).
        let what = match self.1 {
            0 => counted(n, "triangle"),
            copies => format!(
                "{} of {}",
                counted(copies, "placement"),
                counted(n / copies, "triangle")
            ),
        };
        if n == 0 {
            // Its bounds are the empty box's inf and -inf: nothing to show.
            return format!("Mesh({what})");
        }
        let [lo, hi] = self.0.bounds();
        format!(
            "Mesh({what}, bounds {:?} to {:?})",
            lo.to_array(),
            hi.to_array()
        )
    }

    /// The first hit of each ray in (t_min, t_max] (t_min 0 and t_max inf
    /// by default): a ``Hits`` with ``t`` (inf
    /// on a miss), ``prim`` (-1), barycentric ``u`` and ``v``, the unit
    /// geometric ``normal`` and the hit ``point``.
    ///
    /// Watertight: a ray through a shared edge or vertex of a closed mesh
    /// hits one of the triangles there, never none.
    ///
    /// ``fields``: the names of the arrays to compute (default all); the
    /// others are None and cost nothing (``fields=("t", "prim")`` skips
    /// the second look at each hit face that ``normal`` and ``point`` take).
    /// ``zero_misses=True``: a miss's u, v, normal and point are 0, as
    /// Open3D answers, not NaN.
    #[pyo3(signature = (origins, directions, t_max=None, threads=None, t_min=None, bad_rays="raise", fields=None, zero_misses=false))]
    #[allow(clippy::too_many_arguments)]
    fn intersect(
        &self,
        py: Python<'_>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        t_max: Option<&Bound<'_, PyAny>>,
        threads: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::bad_rays)] bad_rays: &str,
        fields: Option<&Bound<'_, PyAny>>,
        zero_misses: bool,
    ) -> PyResult<Hits> {
        let threads = Threads::new(threads)?;
        let (rays, lead) = self.rays(origins, directions, t_max, t_min, bad_rays)?;
        let n = rays.len();
        let fields = Fields::new(fields)?;
        let miss = match zero_misses {
            true => raycast::FirstHit::ZEROED_MISS,
            false => raycast::FirstHit::MISS,
        };
        let mut chunk = Vec::with_capacity(n.min(CHUNK));
        let mut t = column::<f32>(fields.has("t"), n);
        let mut prim = column::<i64>(fields.has("prim"), n);
        let mut u = column::<f32>(fields.has("u"), n);
        let mut v = column::<f32>(fields.has("v"), n);
        let mut normal = column::<f32>(fields.has("normal"), 3 * n);
        let mut point = column::<f64>(fields.has("point"), 3 * n);
        for start in (0..n).step_by(CHUNK) {
            let r = start..(start + CHUNK).min(n);
            rays.read(r.clone(), &threads, &mut chunk)?;
            let pieces = task_pieces(&mut t, 1, r.clone())
                .into_iter()
                .zip(task_pieces(&mut prim, 1, r.clone()))
                .zip(task_pieces(&mut u, 1, r.clone()))
                .zip(task_pieces(&mut v, 1, r.clone()))
                .zip(task_pieces(&mut normal, 3, r.clone()))
                .zip(task_pieces(&mut point, 3, r.clone()))
                .map(|(((((t, face), u), v), normal), point)| FirstHitColumns {
                    t,
                    face,
                    u,
                    v,
                    normal,
                    point,
                    miss,
                })
                .collect::<Vec<_>>();
            let tasks = pieces.len();
            py.detach(|| {
                threads.run(tasks, |min_len| {
                    chunk
                        .par_chunks(TASK)
                        .zip(pieces)
                        .with_min_len(min_len)
                        .for_each(|(rays, out)| self.0.first_hits_into(rays, out))
                })
            })?;
            py.check_signals()?;
        }
        let to = |key: &str, tail: &'static [usize]| (fields.has(key), tail);
        Ok(Hits {
            t: maybe(py, to("t", &[]), t, lead.as_deref(), n)?,
            prim: maybe(py, to("prim", &[]), prim, lead.as_deref(), n)?,
            u: maybe(py, to("u", &[]), u, lead.as_deref(), n)?,
            v: maybe(py, to("v", &[]), v, lead.as_deref(), n)?,
            normal: maybe(py, to("normal", &[3]), normal, lead.as_deref(), n)?,
            point: maybe(py, to("point", &[3]), point, lead.as_deref(), n)?,
            shape: lead.unwrap_or_else(|| vec![n]),
        })
    }

    /// Whether anything blocks each ray in (t_min, t_max] (t_min 0 and
    /// t_max inf by default): bool (n,).
    #[pyo3(signature = (origins, directions, t_max=None, threads=None, t_min=None, bad_rays="raise"))]
    #[allow(clippy::too_many_arguments)] // Python's keywords, one each
    fn occluded<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        t_max: Option<&Bound<'_, PyAny>>,
        threads: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::bad_rays)] bad_rays: &str,
    ) -> PyResult<Py<PyArrayDyn<bool>>> {
        let threads = Threads::new(threads)?;
        let (rays, lead) = self.rays(origins, directions, t_max, t_min, bad_rays)?;
        let mut out = vec![false; rays.len()];
        run::each_ray(py, &threads, &rays, &mut out, |rays, out| {
            self.0.occluded(rays, out)
        })?;
        let n = out.len();
        shaped(py, out, lead.as_deref(), n, &[])
    }

    /// Every surface crossing along each ray in (t_min, t_max] (t_min 0 and
    /// t_max inf by default), nearest first: a ``Crossings`` with
    /// ``splits`` (int64 (n+1,), Open3D's layout: ray i's crossings are
    /// ``splits[i]:splits[i+1]``), ``t`` (float32), ``prim`` (int64),
    /// ``ray`` (int64, the ray of each) and, with ``uv=True``, the
    /// barycentrics ``u`` and ``v`` (float64, where the ray meets the
    /// face's plane). It unpacks as ``splits, t, prim``.
    ///
    /// One traversal per ray, not a re-cast from each hit: a ray through a
    /// shared edge or vertex of a closed mesh crosses the surface there
    /// once and is reported once, never zero times or twice, at any scale.
    #[pyo3(signature = (origins, directions, t_max=None, threads=None, t_min=None, bad_rays="raise", uv=false))]
    #[allow(clippy::too_many_arguments)]
    fn all_hits(
        &self,
        py: Python<'_>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        t_max: Option<&Bound<'_, PyAny>>,
        threads: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::bad_rays)] bad_rays: &str,
        #[pyo3(from_py_with = args::uv)] uv: bool,
    ) -> PyResult<Crossings> {
        let threads = Threads::new(threads)?;
        let (rays, _) = self.rays(origins, directions, t_max, t_min, bad_rays)?;
        let parts = run::flat(py, &threads, &rays, |rays, part| {
            self.0.all_hits(rays, part, uv)
        })?;
        Crossings::from_parts(py, &threads, &parts, uv)
    }

    /// The number of surface crossings along each ray in (t_min, t_max]
    /// (t_min 0 and t_max inf by default): int64 (n,), as ``all_hits``
    /// would list them.
    #[pyo3(signature = (origins, directions, t_max=None, threads=None, t_min=None, bad_rays="raise"))]
    #[allow(clippy::too_many_arguments)] // Python's keywords, one each
    fn count_hits<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        t_max: Option<&Bound<'_, PyAny>>,
        threads: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::bad_rays)] bad_rays: &str,
    ) -> PyResult<Py<PyArrayDyn<i64>>> {
        let threads = Threads::new(threads)?;
        let (rays, lead) = self.rays(origins, directions, t_max, t_min, bad_rays)?;
        let mut out = vec![0i64; rays.len()];
        run::each_ray(py, &threads, &rays, &mut out, |rays, out| {
            let mut counts = [0u32; TASK];
            let counts = &mut counts[..rays.len()];
            self.0.count_hits(rays, counts);
            for (o, &n) in out.iter_mut().zip(counts.iter()) {
                *o = i64::from(n);
            }
        })?;
        let n = out.len();
        shaped(py, out, lead.as_deref(), n, &[])
    }

    /// Whether each point ((n, 3) floats) is inside the mesh: bool (n,), by
    /// the parity of the surface crossings along a ray from it (the
    /// watertight test makes that exact on shared edges and vertices).
    ///
    /// Meant for closed meshes. On an open mesh the answer is the parity
    /// along that one ray, which a hole can flip: a point is reported
    /// inside if that ray crosses the surface an odd number of times.
    #[pyo3(signature = (points, threads=None))]
    fn contains<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'_, PyAny>,
        threads: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Py<PyArrayDyn<bool>>> {
        let threads = Threads::new(threads)?;
        let (points, lead) = convert::rows3(points)?;
        let points = convert::points(&points, "points", self.0.centre(), &threads)?;
        let mut out = vec![false; points.len()];
        run::each(py, &threads, &points, &mut out, |points, out| {
            let near: [glam::Vec3; TASK] =
                std::array::from_fn(|i| points.get(i).map_or(glam::Vec3::ZERO, |p| p.1));
            self.0.contains(&near[..points.len()], out);
        })?;
        let n = out.len();
        shaped(py, out, lead.as_deref(), n, &[])
    }

    /// The nearest point on the surface to each point ((n, 3) floats),
    /// found by a best-first walk of the BVH: a ``ClosestPoints`` with
    /// ``point`` (n, 3), ``distance`` (n,) and the triangle ``prim`` (n,).
    ///
    /// ``max_distance``: look no farther (a number; points with nothing
    /// that near get NaN, inf and -1). ``signed=True`` makes the distance
    /// negative inside the mesh (by ``contains``; meant for closed meshes).
    #[pyo3(signature = (points, max_distance=None, signed=false, threads=None))]
    fn closest_point(
        &self,
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        max_distance: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::signed)] signed: bool,
        threads: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<ClosestPoints> {
        let threads = Threads::new(threads)?;
        let (points, lead) = convert::rows3(points)?;
        let points = convert::points(&points, "points", self.0.centre(), &threads)?;
        let what = "a number >= 0 (None for no limit)";
        let max_distance = args::optional(max_distance, |d| args::real(d, "max_distance", what))?;
        let max_distance = match max_distance {
            None => f32::INFINITY,
            Some(d) if d >= 0.0 => d as f32,
            Some(d) => {
                return Err(PyValueError::new_err(format!(
                    "max_distance must be >= 0 (None for no limit); got {d}"
                )))
            }
        };
        let mut near = vec![raycast::ClosestPoint::MISS; points.len()];
        run::each(py, &threads, &points, &mut near, |points, out| {
            for (o, &(p, near)) in out.iter_mut().zip(points) {
                *o = self.0.closest_point(p, near, max_distance, signed);
            }
        })?;
        let n = near.len();
        let mut point = Vec::with_capacity(3 * n);
        let mut distance = Vec::with_capacity(n);
        let mut prim = Vec::with_capacity(n);
        let (mut u, mut v) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for c in near {
            point.extend(c.point.to_array());
            distance.push(c.distance);
            prim.push(c.face);
            u.push(c.u);
            v.push(c.v);
        }
        Ok(ClosestPoints {
            point: shaped(py, point, lead.as_deref(), n, &[3])?,
            distance: shaped(py, distance, lead.as_deref(), n, &[])?,
            prim: shaped(py, prim, lead.as_deref(), n, &[])?,
            u: shaped(py, u, lead.as_deref(), n, &[])?,
            v: shaped(py, v, lead.as_deref(), n, &[])?,
            shape: lead.unwrap_or_else(|| vec![n]),
        })
    }
}

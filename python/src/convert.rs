//! numpy in: arrays of any float (or integer) dtype, lists and
//! non-contiguous views, read into strata's types. float32 and float64
//! arrays (and int32, int64 and uint32 faces) are read where they lie, in
//! place; anything else goes through one `numpy.asarray(...).astype(...)`.
//! Every refusal is a `ValueError` that names the argument and what it
//! wanted.

use glam::{DVec3, Vec3};
use numpy::ndarray::ArrayView2;
use numpy::{Element, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use strata::math::Ray;

use crate::run::{gather, gather_into, Threads};

fn error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// A shape as Python prints it: `(4, 2)`, `(5,)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The rows of an (n, 3) array of `T`, each element mapped by `f`.
fn rows_of<T: Element + Copy, U>(
    array: &PyReadonlyArray2<'_, T>,
    name: &str,
    what: &str,
    f: impl Fn(T) -> U,
) -> PyResult<Vec<[U; 3]>> {
    rows_with(array, name, what, |_, row| Ok(row.map(&f)))
}

/// Each row `i` of an (n, 3) array of `T` made into one value by `f(i,
/// row)`, which may refuse it, into one array of exactly n values: no
/// copy of the rows in between.
fn rows_with<T: Element + Copy, R>(
    array: &PyReadonlyArray2<'_, T>,
    name: &str,
    what: &str,
    mut f: impl FnMut(usize, [T; 3]) -> PyResult<R>,
) -> PyResult<Vec<R>> {
    let shape = array.shape();
    if shape[0] == 0 {
        return Ok(Vec::new());
    }
    if shape[1] != 3 {
        return Err(error(format!(
            "{name} must be an (n, 3) array of {what}; got shape {}",
            shape_text(shape)
        )));
    }
    let mut out = Vec::with_capacity(shape[0]);
    // as_slice also takes Fortran order (contiguous, but by columns).
    let flat = array
        .is_c_contiguous()
        .then(|| array.as_slice().ok())
        .flatten();
    match flat {
        Some(flat) => {
            for (i, r) in flat.chunks_exact(3).enumerate() {
                out.push(f(i, [r[0], r[1], r[2]])?);
            }
        }
        // Not row-major (a column slice, Fortran order): read by strides.
        None => {
            for (i, r) in array.as_array().rows().into_iter().enumerate() {
                out.push(f(i, [r[0], r[1], r[2]])?);
            }
        }
    }
    Ok(out)
}

/// `obj` through `numpy.asarray(obj)`, checked to hold numbers of a dtype
/// kind in `kinds` ("f": float, "i"/"u": integers) with shape `(n, 3)` (or
/// empty), then converted to `dtype`. `None` for an empty array.
fn as_numpy<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    kinds: &str,
    what: &str,
    dtype: &str,
    ndim: usize,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let py = obj.py();
    let wanted = if ndim == 2 {
        "an (n, 3) array"
    } else {
        "an (n,) array"
    };
    let array = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| error(format!("{name} must be {wanted} of {what}: {e}")))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.iter().product::<usize>() == 0 && shape.first() == Some(&0) {
        return Ok(None);
    }
    if !kinds.contains(kind.as_str()) {
        let dtype_name = array.getattr("dtype")?.str()?.to_string();
        return Err(error(format!(
            "{name} must be {wanted} of {what}; got dtype {dtype_name}"
        )));
    }
    let shape_ok = shape.len() == ndim && (ndim == 1 || shape[1] == 3);
    if !shape_ok {
        return Err(error(format!(
            "{name} must be {wanted} of {what}; got shape {}",
            shape_text(&shape)
        )));
    }
    Ok(Some(array.call_method1("astype", (dtype,))?))
}

/// An (n, 3) array held for reading: float32 or float64 where it lies,
/// row-major or by its strides (a column slice of an (n, 6) array of rays,
/// Fortran order), or a float64 copy of anything else (other dtypes, lists).
pub enum Vec3Array<'py> {
    F32(PyReadonlyArray2<'py, f32>),
    F64(PyReadonlyArray2<'py, f64>),
    StridedF32(PyReadonlyArray2<'py, f32>),
    StridedF64(PyReadonlyArray2<'py, f64>),
    Copied(Vec<DVec3>),
}

/// The rows of a [`Vec3Array`], shareable by threads.
#[derive(Clone, Copy)]
pub enum Vec3Rows<'a> {
    F32(&'a [f32]),
    F64(&'a [f64]),
    StridedF32(ArrayView2<'a, f32>),
    StridedF64(ArrayView2<'a, f64>),
    Copied(&'a [DVec3]),
}

impl Vec3Rows<'_> {
    pub fn len(&self) -> usize {
        match self {
            Self::F32(flat) => flat.len() / 3,
            Self::F64(flat) => flat.len() / 3,
            Self::StridedF32(rows) => rows.nrows(),
            Self::StridedF64(rows) => rows.nrows(),
            Self::Copied(rows) => rows.len(),
        }
    }
}

/// Row `i` of an (n, 3) array, as float32: one implementation per layout,
/// so that a loop over rows is compiled once for each (the [`with_rows`]
/// dispatch), not matched on each row.
trait Row: Sync {
    fn row(&self, i: usize) -> Vec3;
    /// The row as given, in float64 (a float32 row exactly).
    fn row64(&self, i: usize) -> DVec3;
}

struct Flat<'a, T>(&'a [T]);

impl Row for Flat<'_, f32> {
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        Vec3::from_slice(&self.0[3 * i..3 * i + 3])
    }
    #[inline(always)]
    fn row64(&self, i: usize) -> DVec3 {
        self.row(i).as_dvec3()
    }
}

impl Row for Flat<'_, f64> {
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        let r = &self.0[3 * i..3 * i + 3];
        Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32)
    }
    #[inline(always)]
    fn row64(&self, i: usize) -> DVec3 {
        DVec3::from_slice(&self.0[3 * i..3 * i + 3])
    }
}

/// A row read by the view's strides: each of its three values where it
/// lies, so a column slice of a wider array is read on the query's threads
/// as a row-major one is, not first copied row by row on one thread.
impl Row for ArrayView2<'_, f32> {
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        Vec3::new(self[[i, 0]], self[[i, 1]], self[[i, 2]])
    }
    #[inline(always)]
    fn row64(&self, i: usize) -> DVec3 {
        self.row(i).as_dvec3()
    }
}

impl Row for ArrayView2<'_, f64> {
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        self.row64(i).as_vec3()
    }
    #[inline(always)]
    fn row64(&self, i: usize) -> DVec3 {
        DVec3::new(self[[i, 0]], self[[i, 1]], self[[i, 2]])
    }
}

impl Row for &[DVec3] {
    #[inline(always)]
    fn row(&self, i: usize) -> Vec3 {
        self[i].as_vec3()
    }
    #[inline(always)]
    fn row64(&self, i: usize) -> DVec3 {
        self[i]
    }
}

/// `$body` with `$r` bound to `$rows` as a [`Row`] of its own type.
macro_rules! with_rows {
    ($rows:expr, |$r:ident| $body:expr) => {
        match $rows {
            Vec3Rows::F32(flat) => {
                let $r = Flat(flat);
                $body
            }
            Vec3Rows::F64(flat) => {
                let $r = Flat(flat);
                $body
            }
            Vec3Rows::StridedF32(view) => {
                let $r = view;
                $body
            }
            Vec3Rows::StridedF64(view) => {
                let $r = view;
                $body
            }
            Vec3Rows::Copied(rows) => {
                let $r = rows;
                $body
            }
        }
    };
}

impl Vec3Array<'_> {
    pub fn rows(&self) -> PyResult<Vec3Rows<'_>> {
        let flat = |e: numpy::AsSliceError| error(e.to_string());
        Ok(match self {
            Self::F32(a) => Vec3Rows::F32(a.as_slice().map_err(flat)?),
            Self::F64(a) => Vec3Rows::F64(a.as_slice().map_err(flat)?),
            Self::StridedF32(a) => Vec3Rows::StridedF32(a.as_array()),
            Self::StridedF64(a) => Vec3Rows::StridedF64(a.as_array()),
            Self::Copied(rows) => Vec3Rows::Copied(rows),
        })
    }
}

/// Whether an (n, 3) array can be read in place: row-major, and of the
/// right shape (else [`rows_of`] says what is wrong, or copies it).
fn in_place<T: Element>(a: &PyReadonlyArray2<'_, T>) -> bool {
    a.is_c_contiguous() && a.shape()[1] == 3
}

/// Whether an (n, 3) array that is not row-major can be read by its
/// strides: any (n, 3) one with rows (else [`rows_of`] says what is wrong).
fn strided<T: Element>(a: &PyReadonlyArray2<'_, T>) -> bool {
    a.shape()[0] > 0 && a.shape()[1] == 3
}

/// An (n, 3) array of any float or integer dtype, held for reading.
pub fn read_vec3s<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Vec3Array<'py>> {
    const WHAT: &str = "floats";
    let copied =
        |rows: Vec<[f64; 3]>| Vec3Array::Copied(rows.into_iter().map(DVec3::from).collect());
    if let Ok(a) = obj.extract::<PyReadonlyArray2<f32>>() {
        return Ok(match (in_place(&a), strided(&a)) {
            (true, _) => Vec3Array::F32(a),
            (false, true) => Vec3Array::StridedF32(a),
            (false, false) => copied(rows_of(&a, name, WHAT, f64::from)?),
        });
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<f64>>() {
        return Ok(match (in_place(&a), strided(&a)) {
            (true, _) => Vec3Array::F64(a),
            (false, true) => Vec3Array::StridedF64(a),
            (false, false) => copied(rows_of(&a, name, WHAT, |x| x)?),
        });
    }
    match as_numpy(obj, name, "fiu", WHAT, "float64", 2)? {
        None => Ok(Vec3Array::Copied(Vec::new())),
        Some(a) => {
            let a = a.extract::<PyReadonlyArray2<f64>>()?;
            if in_place(&a) {
                Ok(Vec3Array::F64(a))
            } else {
                Ok(copied(rows_of(&a, name, WHAT, |x| x)?))
            }
        }
    }
}

/// An (n, 3) array of any float or integer dtype, as float64 triples (a
/// float32 array's values exactly).
pub fn dvec3s(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<DVec3>> {
    let array = read_vec3s(obj, name)?;
    let rows = array.rows()?;
    let n = rows.len();
    Ok(with_rows!(rows, |r| (0..n).map(|i| r.row64(i)).collect()))
}

/// An (n, 3) array of any float or integer dtype, as float32 triples.
#[allow(dead_code)]
pub fn vec3s(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Vec3>> {
    let array = read_vec3s(obj, name)?;
    let rows = array.rows()?;
    let n = rows.len();
    Ok(with_rows!(rows, |r| (0..n).map(|i| r.row(i)).collect()))
}

fn not_finite(name: &str, i: usize, v: Vec3) -> PyErr {
    error(format!(
        "{name}[{i}] is not finite (as float32): {:?}",
        v.to_array()
    ))
}

/// Points: an (n, 3) array of finite values (after rounding to float32),
/// read on `threads` (with the GIL held, so that no Python code changes the
/// array meanwhile), each as given in float64 and as strata traces it:
/// relative to `centre`, rounded to float32.
pub fn points(
    obj: &Bound<'_, PyAny>,
    name: &str,
    centre: DVec3,
    threads: &Threads,
) -> PyResult<Vec<(DVec3, Vec3)>> {
    let array = read_vec3s(obj, name)?;
    let rows = array.rows()?;
    let fill = (DVec3::ZERO, Vec3::ZERO);
    let (points, bad) = with_rows!(rows, |r| gather(threads, rows.len(), fill, |i| {
        let p = r.row64(i);
        let near = (p - centre).as_vec3();
        ((p, near), !p.as_vec3().is_finite() || !near.is_finite())
    }))?;
    match bad {
        Some(i) => Err(not_finite(name, i, points[i].0.as_vec3())),
        None => Ok(points),
    }
}

/// An (m, 3) array of any integer dtype, as vertex indices: each in
/// `0..vertices` (which strata's own check repeats, naming the same face).
pub fn faces(obj: &Bound<'_, PyAny>, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    const NAME: &str = "faces";
    const WHAT: &str = "integers";
    // Each row checked as it is read, straight into the u32 rows: a copy
    // in i64 first (21 MB for the dragon) was, once freed, the block
    // whose size glibc took as its mmap threshold, so that the build's
    // temporaries below it came from the heap and stayed resident after
    // it (docs/python.md, "Building the dragon: time and memory").
    let check = |face: usize, row: [i64; 3]| match row
        .iter()
        .position(|&k| k < 0 || k as u64 >= vertices as u64)
    {
        Some(corner) => Err(error(format!(
            "faces[{face}][{corner}] = {} is out of range for {vertices} vertices",
            row[corner]
        ))),
        None => Ok(row.map(|k| k as u32)),
    };
    if let Ok(a) = obj.extract::<PyReadonlyArray2<i64>>() {
        rows_with(&a, NAME, WHAT, check)
    } else if let Ok(a) = obj.extract::<PyReadonlyArray2<i32>>() {
        rows_with(&a, NAME, WHAT, |i, r| check(i, r.map(i64::from)))
    } else if let Ok(a) = obj.extract::<PyReadonlyArray2<u32>>() {
        rows_with(&a, NAME, WHAT, |i, r| check(i, r.map(i64::from)))
    } else if let Ok(a) = obj.extract::<PyReadonlyArray2<u64>>() {
        let wide = |x: u64| i64::try_from(x).unwrap_or(i64::MAX);
        rows_with(&a, NAME, WHAT, |i, r| check(i, r.map(wide)))
    } else {
        match as_numpy(obj, NAME, "iu", WHAT, "int64", 2)? {
            None => Ok(Vec::new()),
            Some(a) => rows_with(&a.extract::<PyReadonlyArray2<i64>>()?, NAME, WHAT, check),
        }
    }
}

/// A 1-D array of numbers (any float or integer dtype) as float64.
fn column(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let read = |a: PyReadonlyArray1<f64>| a.as_array().to_vec();
    if let Ok(a) = obj.extract::<PyReadonlyArray1<f64>>() {
        return Ok(read(a));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray1<f32>>() {
        return Ok(a.as_array().iter().map(|&x| x as f64).collect());
    }
    match as_numpy(obj, name, "fiu", "numbers", "float64", 1)? {
        None => Ok(Vec::new()),
        Some(a) => Ok(read(a.extract()?)),
    }
}

/// An array of shape (..., 3) other than (n, 3) as its (n, 3) rows (a
/// numpy reshape, a view where it can be) and its leading shape: `()` for
/// one row given as (3,) (a list or tuple as numpy reads it), whose answers
/// are 0-d; `None` for anything else, taken as it is (answers stay (n,),
/// and a wrong shape is refused by name where the rows are read).
pub fn rows3<'py>(obj: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Option<Vec<usize>>)> {
    let array = if obj.hasattr("ndim")? {
        obj.clone()
    } else if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        match obj.py().import("numpy")?.call_method1("asarray", (obj,)) {
            Ok(a) => a,
            Err(_) => return Ok((obj.clone(), None)),
        }
    } else {
        return Ok((obj.clone(), None));
    };
    let ndim = array.getattr("ndim")?.extract::<usize>().unwrap_or(0);
    if ndim == 0 || ndim == 2 {
        return Ok((array, None));
    }
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape[ndim - 1] != 3 {
        return Ok((array, None));
    }
    let rows = array.call_method1("reshape", ((-1i64, 3i64),))?;
    Ok((rows, Some(shape[..ndim - 1].to_vec())))
}

/// Whether `obj` is an array (or a list or tuple) rather than a number.
fn is_sequence(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        return Ok(true);
    }
    Ok(obj.hasattr("ndim")? && obj.getattr("ndim")?.extract::<usize>().unwrap_or(0) > 0)
}

fn check_t_max(t: f64, name: &str) -> PyResult<f32> {
    if t.is_nan() || t < 0.0 {
        return Err(error(format!(
            "{name} must be >= 0 (inf for no limit); got {t}"
        )));
    }
    Ok(t as f32)
}

/// Where rays end: one t for all, or one each.
pub enum TMax {
    All(f32),
    Each(Vec<f32>),
}

impl TMax {
    #[inline]
    fn get(&self, i: usize) -> f32 {
        match self {
            Self::All(t) => *t,
            Self::Each(ts) => ts[i],
        }
    }
}

/// `t_max` (a number, or one per ray; `None`: no limit), checked, for `n`
/// rays.
fn t_maxes(t_max: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<TMax> {
    let Some(obj) = t_max else {
        return Ok(TMax::All(f32::INFINITY));
    };
    if !is_sequence(obj)? {
        let what = "a number or an (n,) array with one per ray (None for no limit)";
        let t = crate::args::real(obj, "t_max", what)?;
        return Ok(TMax::All(check_t_max(t, "t_max")?));
    }
    let ts = column(obj, "t_max")?;
    if ts.len() != n {
        return Err(error(format!(
            "t_max must be a number or an (n,) array with one per ray; got {} values for {n} rays",
            ts.len()
        )));
    }
    let ts: PyResult<Vec<f32>> = ts
        .iter()
        .enumerate()
        .map(|(i, &t)| check_t_max(t, &format!("t_max[{i}]")))
        .collect();
    Ok(TMax::Each(ts?))
}

/// What a ray query does with a ray that cannot hit anything: a NaN or
/// infinite coordinate, or a zero direction.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum BadRays {
    /// `ValueError` naming the first such row (`Mesh`'s own queries).
    Raise,
    /// A miss, as Open3D and trimesh's engines answer it (the adapters).
    Miss,
}

impl BadRays {
    /// The `bad_rays` keyword: "raise" or "miss".
    pub fn new(name: &str) -> PyResult<Self> {
        match name {
            "raise" => Ok(Self::Raise),
            "miss" => Ok(Self::Miss),
            _ => Err(error(format!(
                "bad_rays must be \"raise\" or \"miss\"; got {name:?}"
            ))),
        }
    }
}

/// A ray that hits nothing: its interval (0, 0] is empty. What a bad ray
/// becomes under [`BadRays::Miss`].
const NO_RAY: Ray = Ray {
    origin: Vec3::ZERO,
    direction: Vec3::X,
    tmin: 0.0,
    tmax: 0.0,
};

/// `t_min`: where rays start (>= 0, finite; `None`: 0).
fn t_min_of(t_min: Option<f64>) -> PyResult<f32> {
    match t_min {
        None => Ok(0.0),
        Some(t) if t >= 0.0 && t.is_finite() => Ok(t as f32),
        Some(t) => Err(error(format!(
            "t_min must be a finite number >= 0; got {t}"
        ))),
    }
}

/// How a query reads its rays: where they start and end, and what a ray
/// that cannot hit anything is.
pub struct RaySpec<'a, 'py> {
    pub t_min: Option<f64>,
    pub t_max: Option<&'a Bound<'py, PyAny>>,
    pub bad: BadRays,
}

/// The rays of a query, read from `origins` and `directions` a chunk at a
/// time ([`RaySource::read`]) into one buffer the chunk's walks then take:
/// not a vector of every ray first (32 bytes a ray, a million rays' worth
/// of memory touched once more and out of the caches again before the
/// walks read it).
pub struct RaySource<'py> {
    origins: Vec3Array<'py>,
    directions: Vec3Array<'py>,
    t_max: TMax,
    t_min: f32,
    bad: BadRays,
    centre: DVec3,
    n: usize,
    /// Whether every ray shares the one origin, or the one direction,
    /// given (a row broadcast over the other array's rows, as numpy does).
    one_origin: bool,
    one_direction: bool,
}

/// Rays from `origins` and `directions` ((n, 3) each, finite, no zero
/// direction, else per `spec.bad`), on `(t_min, t_max]`: their shapes,
/// lengths and intervals checked here, each ray when it is read.
/// Origins are made relative to `centre` (in float64, then rounded) where
/// the mesh is held relative to it.
pub fn ray_source<'py>(
    origins: &Bound<'py, PyAny>,
    directions: &Bound<'py, PyAny>,
    spec: &RaySpec<'_, '_>,
    centre: DVec3,
) -> PyResult<RaySource<'py>> {
    let origins = read_vec3s(origins, "origins")?;
    let directions = read_vec3s(directions, "directions")?;
    let (no, nd) = (origins.rows()?.len(), directions.rows()?.len());
    // One row of either goes with every row of the other (numpy's
    // broadcasting): one direction from many origins, or many from one.
    let n = match (no, nd) {
        _ if no == nd => no,
        (1, n) | (n, 1) => n,
        _ => {
            return Err(error(format!(
                "origins and directions must have the same length, or one of them one row; got {no} and {nd}"
            )))
        }
    };
    Ok(RaySource {
        t_max: t_maxes(spec.t_max, n)?,
        t_min: t_min_of(spec.t_min)?,
        bad: spec.bad,
        centre,
        n,
        one_origin: no == 1 && n != 1,
        one_direction: nd == 1 && n != 1,
        origins,
        directions,
    })
}

impl RaySource<'_> {
    /// The number of rays.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Rays `range` into `out` (its old rays dropped), read on `threads`
    /// with the GIL held, so that no Python code changes the arrays
    /// meanwhile. A bad ray raises `ValueError` naming its row (the first
    /// of the range; chunks are read in order, so the first of all), or
    /// becomes a miss under [`BadRays::Miss`].
    pub fn read(
        &self,
        range: std::ops::Range<usize>,
        threads: &Threads,
        out: &mut Vec<Ray>,
    ) -> PyResult<()> {
        let (o, d) = (self.origins.rows()?, self.directions.rows()?);
        let bad = |r: &Ray| {
            !r.origin.is_finite() || !r.direction.is_finite() || r.direction == Vec3::ZERO
        };
        let miss = self.bad == BadRays::Miss;
        let centred = self.centre != DVec3::ZERO;
        let (centre, t, t_min) = (self.centre, &self.t_max, self.t_min);
        let (one_origin, one_direction) = (self.one_origin, self.one_direction);
        let first = range.start;
        let bad = with_rows!(o, |ro| with_rows!(d, |rd| gather_into(
            threads,
            range.clone(),
            out,
            NO_RAY,
            |i| {
                let (oi, di) = (
                    if one_origin { 0 } else { i },
                    if one_direction { 0 } else { i },
                );
                // Without a centre, the row rounded once, as (row - 0) would be.
                let origin = match centred {
                    true => (ro.row64(oi) - centre).as_vec3(),
                    false => ro.row(oi),
                };
                let ray = Ray {
                    origin,
                    direction: rd.row(di),
                    tmin: t_min,
                    tmax: t.get(i),
                };
                match bad(&ray) {
                    true if miss => (NO_RAY, false),
                    b => (ray, b),
                }
            }
        )))?;
        let Some(i) = bad else {
            return Ok(());
        };
        let r = out[i - first];
        let (oi, di) = (
            if one_origin { 0 } else { i },
            if one_direction { 0 } else { i },
        );
        if !r.origin.is_finite() {
            // Quoted as given, not as traced (relative to the centre).
            let given = with_rows!(o, |ro| ro.row64(oi));
            return Err(not_finite("origins", oi, given.as_vec3()));
        }
        let what = if r.direction.is_finite() {
            "is zero"
        } else {
            "is not finite (as float32)"
        };
        Err(error(format!(
            "directions[{di}] {what}: {:?}; a direction must be a finite, non-zero vector",
            r.direction.to_array()
        )))
    }
}

/// An (n, 3, 4) or (n, 4, 4) array of row-major object-to-world matrices
/// (any float or integer dtype, or nested lists) as affine maps; a 4x4's
/// last row must be [0, 0, 0, 1]. A value that is not finite names its
/// entry; whether a map is invertible is the caller's check.
pub fn affine_maps(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<glam::Affine3A>> {
    let np = obj.py().import("numpy")?;
    let array = np
        .call_method1("asarray", (obj, "float64"))
        .map_err(|_| error(format!("{name} must be an array of numbers")))?;
    let a: PyReadonlyArray3<f64> = array.extract().map_err(|_| {
        let shape: Vec<usize> = array
            .getattr("shape")
            .and_then(|s| s.extract())
            .unwrap_or_default();
        error(format!(
            "{name} must have shape (n, 3, 4) or (n, 4, 4), got {}",
            shape_text(&shape)
        ))
    })?;
    let a = a.as_array();
    let [n, rows, cols] = [a.shape()[0], a.shape()[1], a.shape()[2]];
    if !(cols == 4 && (rows == 3 || rows == 4)) {
        return Err(error(format!(
            "{name} must have shape (n, 3, 4) or (n, 4, 4), got {}",
            shape_text(&[n, rows, cols])
        )));
    }
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let m = |i: usize, j: usize| a[[k, i, j]];
        for i in 0..rows {
            for j in 0..4 {
                if !m(i, j).is_finite() {
                    return Err(error(format!(
                        "{name}[{k}][{i}][{j}] = {} is not finite",
                        m(i, j)
                    )));
                }
            }
        }
        if rows == 4 && [m(3, 0), m(3, 1), m(3, 2), m(3, 3)] != [0.0, 0.0, 0.0, 1.0] {
            return Err(error(format!(
                "{name}[{k}]'s last row must be [0, 0, 0, 1] (affine maps only)"
            )));
        }
        let col = |j: usize| glam::Vec3::new(m(0, j) as f32, m(1, j) as f32, m(2, j) as f32);
        out.push(glam::Affine3A::from_mat3_translation(
            glam::Mat3::from_cols(col(0), col(1), col(2)),
            col(3),
        ));
    }
    Ok(out)
}

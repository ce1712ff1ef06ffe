//! The named results of `Mesh`'s queries: arrays as attributes or keys.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::{PyIndexError, PyKeyError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyString, PyTuple};
use rayon::prelude::*;
use strata::raycast;

use crate::run::{self, Threads};

/// The first hit of each ray (``Mesh.intersect``): arrays of one entry (or
/// row) per ray, as attributes or as keys (``hits.t`` or ``hits["t"]``).
/// A mapping of names to arrays (``keys()``, ``items()``, ``get()``,
/// ``dict(hits)``), indexed by name, not by ray: ``hits.t[0]`` is ray 0's
/// distance. It pickles (a ``multiprocessing`` worker can return one).
#[pyclass(frozen, module = "strata_rt._native")]
pub struct Hits {
    /// float32 (n,): distance along the ray, in direction lengths; inf on a miss (None unless asked for in ``fields``, as every array here).
    #[pyo3(get)]
    pub(crate) t: Option<Py<PyArrayDyn<f32>>>,
    /// int64 (n,): the triangle (face index) hit; -1 on a miss.
    #[pyo3(get)]
    pub(crate) prim: Option<Py<PyArrayDyn<i64>>>,
    /// float32 (n,): barycentric coordinate of the face's second vertex; NaN on a miss.
    #[pyo3(get)]
    pub(crate) u: Option<Py<PyArrayDyn<f32>>>,
    /// float32 (n,): barycentric coordinate of the face's third vertex; NaN on a miss.
    #[pyo3(get)]
    pub(crate) v: Option<Py<PyArrayDyn<f32>>>,
    /// float32 (n, 3): unit geometric normal of the triangle hit, by the
    /// right-hand rule over its vertex order (trimesh's face normal); NaN on a miss.
    #[pyo3(get)]
    pub(crate) normal: Option<Py<PyArrayDyn<f32>>>,
    /// float64 (n, 3): where the ray meets the triangle's plane, computed
    /// in float64 on the triangle as given (on its plane to float64's
    /// precision, wherever the mesh lies); NaN on a miss.
    #[pyo3(get)]
    pub(crate) point: Option<Py<PyArrayDyn<f64>>>,
    /// The rays' leading shape (`[n]` for an (n, 3) input, `[]` for one
    /// ray given as (3,)): what `len` and the repr count, with or without
    /// any array computed.
    pub(crate) shape: Vec<usize>,
}

/// `len()` of a result over a leading shape: its first axis, as numpy's
/// `len`; a TypeError for one `noun` (ray or point) given alone, whose
/// arrays are 0-d (numpy's "len() of unsized object").
fn first_axis(shape: &[usize], what: &str, noun: &str) -> PyResult<usize> {
    shape.first().copied().ok_or_else(|| {
        PyTypeError::new_err(format!(
            "len() of {what} of one {noun} given alone: its arrays are 0-d"
        ))
    })
}

/// "1 ray", "5 rays", or "10 rays in shape (2, 5)": how many queries a
/// result answers, and their shape where it is not a plain list.
fn counted(shape: &[usize], noun: &str) -> String {
    let n: usize = shape.iter().product();
    let plural = if n == 1 { "" } else { "s" };
    if shape.len() <= 1 {
        format!("{n} {noun}{plural}")
    } else {
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        format!("{n} {noun}{plural} in shape ({})", dims.join(", "))
    }
}

pub const HITS_KEYS: [&str; 6] = ["t", "prim", "u", "v", "normal", "point"];

/// The TypeError of a result indexed by anything but a name: an int
/// (``hits[0]``, and so ``tuple(hits)`` and ``for x in hits``) or a slice.
fn not_a_name(what: &str, example: &str, noun: &str, key: &Bound<'_, PyAny>) -> PyErr {
    let (var, name) = example.split_once('.').unwrap_or((example, ""));
    PyTypeError::new_err(format!(
        "{what} is a mapping of names to arrays: index it by name ({var}[\"{name}\"]; \
         {var}.keys() lists them), and an array by {noun} ({example}[0]); got {}",
        crate::args::described(key)
    ))
}

/// `key` as a name, if it is a str.
fn name_of(key: &Bound<'_, PyAny>) -> Option<String> {
    if !key.is_instance_of::<PyString>() {
        return None;
    }
    key.extract::<String>().ok()
}

/// `(name, array)` of each of `keys` that `named` finds, in order.
fn items_of(
    keys: &[&'static str],
    named: impl Fn(&str) -> PyResult<Py<PyAny>>,
) -> Vec<(&'static str, Py<PyAny>)> {
    keys.iter()
        .filter_map(|&k| named(k).ok().map(|a| (k, a)))
        .collect()
}

/// An optional array, for pickling: itself, or None.
fn maybe_clone<T>(py: Python<'_>, a: &Option<Py<T>>) -> Option<Py<T>> {
    a.as_ref().map(|a| a.clone_ref(py))
}

#[pymethods]
impl Hits {
    /// The array named ``key``: one of ``keys()``. Hits is indexed by name,
    /// not by ray: an int raises TypeError (``hits.t[0]`` is ray 0's t).
    fn __getitem__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        match name_of(key) {
            Some(name) => self.named(py, &name),
            None => Err(not_a_name("Hits", "hits.t", "ray", key)),
        }
    }

    /// The names of the arrays computed (``fields``; by default t, prim,
    /// u, v, normal, point).
    fn keys(&self, py: Python<'_>) -> Vec<&'static str> {
        HITS_KEYS
            .into_iter()
            .filter(|k| self.named(py, k).is_ok())
            .collect()
    }

    /// ``(name, array)`` of each array computed, in the order of ``keys()``.
    fn items(&self, py: Python<'_>) -> Vec<(&'static str, Py<PyAny>)> {
        items_of(&HITS_KEYS, |k| self.named(py, k))
    }

    /// The arrays computed, in the order of ``keys()``.
    fn values(&self, py: Python<'_>) -> Vec<Py<PyAny>> {
        self.items(py).into_iter().map(|(_, a)| a).collect()
    }

    /// The array named ``key`` if it was computed, else ``default``.
    #[pyo3(signature = (key, default=None))]
    fn get(&self, py: Python<'_>, key: &Bound<'_, PyAny>, default: Option<Py<PyAny>>) -> Py<PyAny> {
        name_of(key)
            .and_then(|name| self.named(py, &name).ok())
            .unwrap_or_else(|| default.unwrap_or_else(|| py.None()))
    }

    /// Whether ``key`` names one of the arrays computed.
    fn __contains__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> bool {
        name_of(key).is_some_and(|name| self.named(py, &name).is_ok())
    }

    /// Pickling: ``Hits._unpickle`` of its arrays (None where not
    /// computed) and the rays' leading shape.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let h = slf.get();
        let state = (
            maybe_clone(py, &h.t),
            maybe_clone(py, &h.prim),
            maybe_clone(py, &h.u),
            maybe_clone(py, &h.v),
            maybe_clone(py, &h.normal),
            maybe_clone(py, &h.point),
            h.shape.clone(),
        );
        Ok((
            slf.get_type().getattr("_unpickle")?,
            state.into_pyobject(py)?,
        ))
    }

    /// Unpickling: the Hits of these arrays and leading shape.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)] // the arrays, one each
    fn _unpickle(
        t: Option<Py<PyArrayDyn<f32>>>,
        prim: Option<Py<PyArrayDyn<i64>>>,
        u: Option<Py<PyArrayDyn<f32>>>,
        v: Option<Py<PyArrayDyn<f32>>>,
        normal: Option<Py<PyArrayDyn<f32>>>,
        point: Option<Py<PyArrayDyn<f64>>>,
        shape: Vec<usize>,
    ) -> Self {
        Self {
            t,
            prim,
            u,
            v,
            normal,
            point,
            shape,
        }
    }
    /// The length of the rays' first axis (the number of rays for an
    /// (n, 3) input), as numpy's ``len``; a TypeError for one ray given as (3,).
    fn __len__(&self) -> PyResult<usize> {
        first_axis(&self.shape, "Hits", "ray")
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        // Counted from whichever of prim and t was computed.
        let hits = match (&self.prim, &self.t) {
            (Some(p), _) => p
                .bind(py)
                .to_vec()
                .ok()
                .map(|p| p.iter().filter(|&&p| p >= 0).count()),
            (None, Some(t)) => t
                .bind(py)
                .to_vec()
                .ok()
                .map(|t| t.iter().filter(|t| t.is_finite()).count()),
            (None, None) => None,
        };
        let hits = match hits {
            Some(1) => ", 1 hit".to_string(),
            Some(h) => format!(", {h} hits"),
            None => String::new(),
        };
        format!(
            "Hits({}{hits}; keys {})",
            counted(&self.shape, "ray"),
            self.keys(py).join(", ")
        )
    }
}

impl Hits {
    /// The array named `name`, if it was computed.
    fn named(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        let found = match name {
            "t" => self.t.as_ref().map(|a| a.clone_ref(py).into_any()),
            "prim" => self.prim.as_ref().map(|a| a.clone_ref(py).into_any()),
            "u" => self.u.as_ref().map(|a| a.clone_ref(py).into_any()),
            "v" => self.v.as_ref().map(|a| a.clone_ref(py).into_any()),
            "normal" => self.normal.as_ref().map(|a| a.clone_ref(py).into_any()),
            "point" => self.point.as_ref().map(|a| a.clone_ref(py).into_any()),
            _ => None,
        };
        found.ok_or_else(|| PyKeyError::new_err(name.to_string()))
    }
}

/// The nearest surface point to each query point (``Mesh.closest_point``),
/// as attributes or keys (``near.distance`` or ``near["distance"]``): a
/// mapping of names to arrays, as ``Hits`` is. It pickles.
#[pyclass(frozen, module = "strata_rt._native")]
pub struct ClosestPoints {
    /// float64 (n, 3): the nearest point on the surface, computed in
    /// float64 on the triangle as given; NaN where none lies within max_distance.
    #[pyo3(get)]
    pub(crate) point: Py<PyArrayDyn<f64>>,
    /// float64 (n,): its distance (negative inside with ``signed=True``); inf where none.
    #[pyo3(get)]
    pub(crate) distance: Py<PyArrayDyn<f64>>,
    /// int64 (n,): the triangle (face index) it lies on; -1 where none.
    #[pyo3(get)]
    pub(crate) prim: Py<PyArrayDyn<i64>>,
    /// float64 (n,): barycentric coordinate of the face's second vertex at the point; NaN where none.
    #[pyo3(get)]
    pub(crate) u: Py<PyArrayDyn<f64>>,
    /// float64 (n,): barycentric coordinate of the face's third vertex at the point; NaN where none.
    #[pyo3(get)]
    pub(crate) v: Py<PyArrayDyn<f64>>,
    /// The points' leading shape, as [`Hits::shape`].
    pub(crate) shape: Vec<usize>,
}

const CLOSEST_KEYS: [&str; 5] = ["point", "distance", "prim", "u", "v"];

impl ClosestPoints {
    /// The array named `name`.
    fn named(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        Ok(match name {
            "point" => self.point.clone_ref(py).into_any(),
            "distance" => self.distance.clone_ref(py).into_any(),
            "prim" => self.prim.clone_ref(py).into_any(),
            "u" => self.u.clone_ref(py).into_any(),
            "v" => self.v.clone_ref(py).into_any(),
            _ => return Err(PyKeyError::new_err(name.to_string())),
        })
    }
}

#[pymethods]
impl ClosestPoints {
    /// The array named ``key``: one of ``keys()``. Indexed by name, not by
    /// point: an int raises TypeError (``near.distance[0]`` is point 0's).
    fn __getitem__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        match name_of(key) {
            Some(name) => self.named(py, &name),
            None => Err(not_a_name("ClosestPoints", "near.distance", "point", key)),
        }
    }

    /// The names of the arrays: point, distance, prim, u, v.
    fn keys(&self) -> Vec<&'static str> {
        CLOSEST_KEYS.to_vec()
    }

    /// ``(name, array)`` of each array, in the order of ``keys()``.
    fn items(&self, py: Python<'_>) -> Vec<(&'static str, Py<PyAny>)> {
        items_of(&CLOSEST_KEYS, |k| self.named(py, k))
    }

    /// The arrays, in the order of ``keys()``.
    fn values(&self, py: Python<'_>) -> Vec<Py<PyAny>> {
        self.items(py).into_iter().map(|(_, a)| a).collect()
    }

    /// The array named ``key``, else ``default``.
    #[pyo3(signature = (key, default=None))]
    fn get(&self, py: Python<'_>, key: &Bound<'_, PyAny>, default: Option<Py<PyAny>>) -> Py<PyAny> {
        name_of(key)
            .and_then(|name| self.named(py, &name).ok())
            .unwrap_or_else(|| default.unwrap_or_else(|| py.None()))
    }

    /// Whether ``key`` names one of the arrays.
    fn __contains__(&self, key: &Bound<'_, PyAny>) -> bool {
        name_of(key).is_some_and(|name| CLOSEST_KEYS.contains(&name.as_str()))
    }

    /// Pickling: ``ClosestPoints._unpickle`` of its arrays and the points'
    /// leading shape.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let c = slf.get();
        let state = (
            c.point.clone_ref(py),
            c.distance.clone_ref(py),
            c.prim.clone_ref(py),
            c.u.clone_ref(py),
            c.v.clone_ref(py),
            c.shape.clone(),
        );
        Ok((
            slf.get_type().getattr("_unpickle")?,
            state.into_pyobject(py)?,
        ))
    }

    /// Unpickling: the ClosestPoints of these arrays and leading shape.
    #[staticmethod]
    fn _unpickle(
        point: Py<PyArrayDyn<f64>>,
        distance: Py<PyArrayDyn<f64>>,
        prim: Py<PyArrayDyn<i64>>,
        u: Py<PyArrayDyn<f64>>,
        v: Py<PyArrayDyn<f64>>,
        shape: Vec<usize>,
    ) -> Self {
        Self {
            point,
            distance,
            prim,
            u,
            v,
            shape,
        }
    }

    /// The length of the points' first axis (the number of points for an
    /// (n, 3) input), as numpy's ``len``; a TypeError for one point given as (3,).
    fn __len__(&self) -> PyResult<usize> {
        first_axis(&self.shape, "ClosestPoints", "point")
    }

    fn __repr__(&self) -> String {
        format!(
            "ClosestPoints({}; keys point, distance, prim, u, v)",
            counted(&self.shape, "point")
        )
    }
}

/// Every crossing of each ray (``Mesh.all_hits``), ray after ray, each
/// ray's nearest first, as attributes or keys; it also unpacks as
/// ``splits, t, prim = mesh.all_hits(...)``. It pickles.
#[pyclass(frozen, module = "strata_rt._native")]
pub struct Crossings {
    /// int64 (n + 1,): ray i's crossings are ``splits[i]:splits[i+1]`` (Open3D's ray_splits).
    #[pyo3(get)]
    pub(crate) splits: Py<PyArray1<i64>>,
    /// float32 (h,): each crossing's distance along its ray, in direction lengths.
    #[pyo3(get)]
    pub(crate) t: Py<PyArray1<f32>>,
    /// int64 (h,): the triangle (face index) crossed.
    #[pyo3(get)]
    pub(crate) prim: Py<PyArray1<i64>>,
    /// int64 (h,): the ray each crossing is on (Open3D's ray_ids, trimesh's index_ray).
    #[pyo3(get)]
    pub(crate) ray: Py<PyArray1<i64>>,
    /// float64 (h,): barycentric coordinate of the face's second vertex where
    /// the ray meets its plane; None unless ``uv=True``.
    #[pyo3(get)]
    pub(crate) u: Option<Py<PyArray1<f64>>>,
    /// float64 (h,): barycentric coordinate of the face's third vertex; None unless ``uv=True``.
    #[pyo3(get)]
    pub(crate) v: Option<Py<PyArray1<f64>>>,
}

const CROSSINGS_KEYS: [&str; 6] = ["splits", "t", "prim", "ray", "u", "v"];

#[pymethods]
impl Crossings {
    /// The array named ``key`` (one of ``keys()``), or ``splits``, ``t``,
    /// ``prim`` by their place 0, 1, 2 in the tuple ``all_hits`` returned.
    fn __getitem__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        if let Some(name) = name_of(key) {
            return self.named(py, &name);
        }
        let Ok(i) = key.extract::<isize>() else {
            return Err(PyTypeError::new_err(format!(
                "Crossings is indexed by name (found[\"t\"]; found.keys() lists them) or by \
                 0, 1, 2 as the tuple splits, t, prim; got {}",
                crate::args::described(key)
            )));
        };
        let name = match i {
            0 | -3 => "splits",
            1 | -2 => "t",
            2 | -1 => "prim",
            _ => {
                return Err(PyIndexError::new_err(format!(
                    "Crossings index {i} is out of range: it unpacks as splits, t, prim"
                )))
            }
        };
        self.named(py, name)
    }

    /// The names of the arrays computed: splits, t, prim, ray (and u, v with ``uv=True``).
    fn keys(&self, py: Python<'_>) -> Vec<&'static str> {
        CROSSINGS_KEYS
            .into_iter()
            .filter(|k| self.named(py, k).is_ok())
            .collect()
    }

    /// ``(name, array)`` of each array computed, in the order of ``keys()``.
    fn items(&self, py: Python<'_>) -> Vec<(&'static str, Py<PyAny>)> {
        items_of(&CROSSINGS_KEYS, |k| self.named(py, k))
    }

    /// The arrays computed, in the order of ``keys()``.
    fn values(&self, py: Python<'_>) -> Vec<Py<PyAny>> {
        self.items(py).into_iter().map(|(_, a)| a).collect()
    }

    /// The array named ``key`` if it was computed, else ``default``.
    #[pyo3(signature = (key, default=None))]
    fn get(&self, py: Python<'_>, key: &Bound<'_, PyAny>, default: Option<Py<PyAny>>) -> Py<PyAny> {
        name_of(key)
            .and_then(|name| self.named(py, &name).ok())
            .unwrap_or_else(|| default.unwrap_or_else(|| py.None()))
    }

    /// Whether ``key`` names one of the arrays computed.
    fn __contains__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> bool {
        name_of(key).is_some_and(|name| self.named(py, &name).is_ok())
    }

    /// ``splits, t, prim``: what ``all_hits`` returned as a tuple before.
    fn __iter__(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let parts = (
            self.splits.clone_ref(py),
            self.t.clone_ref(py),
            self.prim.clone_ref(py),
        );
        Ok(parts.into_pyobject(py)?.try_iter()?.into_any().unbind())
    }

    /// Pickling: ``Crossings._unpickle`` of its arrays (u and v None
    /// unless computed).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let c = slf.get();
        let state = (
            c.splits.clone_ref(py),
            c.t.clone_ref(py),
            c.prim.clone_ref(py),
            c.ray.clone_ref(py),
            maybe_clone(py, &c.u),
            maybe_clone(py, &c.v),
        );
        Ok((
            slf.get_type().getattr("_unpickle")?,
            state.into_pyobject(py)?,
        ))
    }

    /// Unpickling: the Crossings of these arrays.
    #[staticmethod]
    fn _unpickle(
        splits: Py<PyArray1<i64>>,
        t: Py<PyArray1<f32>>,
        prim: Py<PyArray1<i64>>,
        ray: Py<PyArray1<i64>>,
        u: Option<Py<PyArray1<f64>>>,
        v: Option<Py<PyArray1<f64>>>,
    ) -> Self {
        Self {
            splits,
            t,
            prim,
            ray,
            u,
            v,
        }
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let rays = self.splits.bind(py).len().unwrap_or(1).saturating_sub(1);
        let h = self.t.bind(py).len().unwrap_or(0);
        format!(
            "Crossings({}, {}; keys {})",
            counted(&[rays], "ray"),
            counted(&[h], "crossing"),
            self.keys(py).join(", ")
        )
    }
}

/// One task's share of [`Crossings`]' columns (`u` and `v` empty unless
/// asked for), and where its rays and crossings start in them.
struct CrossingsPiece<'a> {
    first_ray: usize,
    first_crossing: usize,
    splits: &'a mut [i64],
    ray: &'a mut [i64],
    t: &'a mut [f32],
    prim: &'a mut [i64],
    u: &'a mut [f64],
    v: &'a mut [f64],
}

impl Crossings {
    /// The crossings `Mesh.all_hits` found, one part per task
    /// ([`run::flat`]), each part copied into its share of the columns on
    /// `threads` (on the calling thread alone, one part after another,
    /// the copies and columns took about 3 of `all_hits`' 38 ms on two
    /// threads while the other waited; docs/python.md).
    pub(crate) fn from_parts(
        py: Python<'_>,
        threads: &Threads,
        parts: &[raycast::Crossings],
        uv: bool,
    ) -> PyResult<Self> {
        let rays: usize = parts.iter().map(|p| p.counts.len()).sum();
        let crossings: usize = parts.iter().map(|p| p.t.len()).sum();
        let mut splits = vec![0i64; rays + 1];
        let (mut ray, mut prim) = (vec![0i64; crossings], vec![0i64; crossings]);
        let mut t = vec![0f32; crossings];
        let uv_len = if uv { crossings } else { 0 };
        let (mut u, mut v) = (vec![0f64; uv_len], vec![0f64; uv_len]);
        let counts = || parts.iter().map(|p| p.counts.len());
        let lengths = || parts.iter().map(|p| p.t.len());
        let uv_lengths = || lengths().map(|n| if uv { n } else { 0 });
        let (mut first_ray, mut first_crossing) = (0, 0);
        let pieces: Vec<CrossingsPiece<'_>> = run::cut(&mut splits[1..], counts())
            .into_iter()
            .zip(run::cut(&mut ray, lengths()))
            .zip(run::cut(&mut t, lengths()))
            .zip(run::cut(&mut prim, lengths()))
            .zip(run::cut(&mut u, uv_lengths()))
            .zip(run::cut(&mut v, uv_lengths()))
            .map(|(((((splits, ray), t), prim), u), v)| {
                let piece = CrossingsPiece {
                    first_ray,
                    first_crossing,
                    splits,
                    ray,
                    t,
                    prim,
                    u,
                    v,
                };
                first_ray += piece.splits.len();
                first_crossing += piece.t.len();
                piece
            })
            .collect();
        py.detach(|| {
            threads.run(parts.len(), |min_len| {
                (parts, pieces)
                    .into_par_iter()
                    .with_min_len(min_len)
                    .for_each(|(part, piece)| piece.fill(part))
            })
        })?;
        Ok(Self {
            splits: PyArray1::from_vec(py, splits).unbind(),
            t: PyArray1::from_vec(py, t).unbind(),
            prim: PyArray1::from_vec(py, prim).unbind(),
            ray: PyArray1::from_vec(py, ray).unbind(),
            u: uv.then(|| PyArray1::from_vec(py, u).unbind()),
            v: uv.then(|| PyArray1::from_vec(py, v).unbind()),
        })
    }

    /// The array named `name`, if it was computed.
    fn named(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        let found = match name {
            "splits" => Some(self.splits.clone_ref(py).into_any()),
            "t" => Some(self.t.clone_ref(py).into_any()),
            "prim" => Some(self.prim.clone_ref(py).into_any()),
            "ray" => Some(self.ray.clone_ref(py).into_any()),
            "u" => self.u.as_ref().map(|a| a.clone_ref(py).into_any()),
            "v" => self.v.as_ref().map(|a| a.clone_ref(py).into_any()),
            _ => None,
        };
        found.ok_or_else(|| PyKeyError::new_err(name.to_string()))
    }
}

impl CrossingsPiece<'_> {
    /// This share of the columns, from its task's part.
    fn fill(self, part: &raycast::Crossings) {
        let mut end = self.first_crossing;
        for (i, (&n, split)) in part.counts.iter().zip(self.splits).enumerate() {
            let start = end - self.first_crossing;
            end += n as usize;
            *split = end as i64;
            self.ray[start..end - self.first_crossing].fill((self.first_ray + i) as i64);
        }
        self.t.copy_from_slice(&part.t);
        self.prim.copy_from_slice(&part.face);
        self.u.copy_from_slice(&part.u);
        self.v.copy_from_slice(&part.v);
    }
}

//! The named results of `Mesh`'s queries: arrays as attributes or keys.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::{PyKeyError, PyTypeError};
use pyo3::prelude::*;

/// The first hit of each ray (``Mesh.intersect``): arrays of one entry (or
/// row) per ray, as attributes or as keys (``hits.t`` or ``hits["t"]``).
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

#[pymethods]
impl Hits {
    /// The array named ``key``: one of ``keys()``.
    fn __getitem__(&self, py: Python<'_>, key: &str) -> PyResult<Py<PyAny>> {
        let found = match key {
            "t" => self.t.as_ref().map(|a| a.clone_ref(py).into_any()),
            "prim" => self.prim.as_ref().map(|a| a.clone_ref(py).into_any()),
            "u" => self.u.as_ref().map(|a| a.clone_ref(py).into_any()),
            "v" => self.v.as_ref().map(|a| a.clone_ref(py).into_any()),
            "normal" => self.normal.as_ref().map(|a| a.clone_ref(py).into_any()),
            "point" => self.point.as_ref().map(|a| a.clone_ref(py).into_any()),
            _ => None,
        };
        found.ok_or_else(|| PyKeyError::new_err(key.to_string()))
    }

    /// The names of the arrays computed (``fields``; by default t, prim,
    /// u, v, normal, point).
    fn keys(&self, py: Python<'_>) -> Vec<&'static str> {
        HITS_KEYS
            .into_iter()
            .filter(|k| self.__getitem__(py, k).is_ok())
            .collect()
    }

    /// Whether ``key`` names one of the arrays computed.
    fn __contains__(&self, py: Python<'_>, key: &str) -> bool {
        self.__getitem__(py, key).is_ok()
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

/// The nearest surface point to each query point (``Mesh.closest_point``),
/// as attributes or keys (``near.distance`` or ``near["distance"]``).
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

#[pymethods]
impl ClosestPoints {
    /// The array named ``key``: one of ``keys()``.
    fn __getitem__(&self, py: Python<'_>, key: &str) -> PyResult<Py<PyAny>> {
        Ok(match key {
            "point" => self.point.clone_ref(py).into_any(),
            "distance" => self.distance.clone_ref(py).into_any(),
            "prim" => self.prim.clone_ref(py).into_any(),
            "u" => self.u.clone_ref(py).into_any(),
            "v" => self.v.clone_ref(py).into_any(),
            _ => return Err(PyKeyError::new_err(key.to_string())),
        })
    }

    /// The names of the arrays: point, distance, prim, u, v.
    fn keys(&self) -> Vec<&'static str> {
        CLOSEST_KEYS.to_vec()
    }

    /// Whether ``key`` names one of the arrays.
    fn __contains__(&self, key: &str) -> bool {
        CLOSEST_KEYS.contains(&key)
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
/// ``splits, t, prim = mesh.all_hits(...)``.
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
        if let Ok(i) = key.extract::<isize>() {
            let name = match i {
                0 | -3 => "splits",
                1 | -2 => "t",
                2 | -1 => "prim",
                _ => return Err(pyo3::exceptions::PyIndexError::new_err(format!("{i}"))),
            };
            return self.named(py, name);
        }
        self.named(py, &key.extract::<String>()?)
    }

    /// The names of the arrays computed: splits, t, prim, ray (and u, v with ``uv=True``).
    fn keys(&self, py: Python<'_>) -> Vec<&'static str> {
        CROSSINGS_KEYS
            .into_iter()
            .filter(|k| self.named(py, k).is_ok())
            .collect()
    }

    /// Whether ``key`` names one of the arrays computed.
    fn __contains__(&self, py: Python<'_>, key: &str) -> bool {
        self.named(py, key).is_ok()
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

    fn __repr__(&self, py: Python<'_>) -> String {
        let rays = self.splits.bind(py).len().unwrap_or(1).saturating_sub(1);
        let h = self.t.bind(py).len().unwrap_or(0);
        format!(
            "Crossings({rays} rays, {h} crossings; keys {})",
            self.keys(py).join(", ")
        )
    }
}

impl Crossings {
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

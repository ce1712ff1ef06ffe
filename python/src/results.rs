//! The named results of `Mesh`'s queries: arrays as attributes or keys.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::PyKeyError;
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

    /// The number of rays.
    fn __len__(&self, py: Python<'_>) -> usize {
        HITS_KEYS
            .into_iter()
            .find_map(|k| self.__getitem__(py, k).ok())
            .and_then(|a| a.bind(py).len().ok())
            .unwrap_or(0)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self.__len__(py);
        let hits = match &self.prim {
            Some(p) => p
                .bind(py)
                .to_vec()
                .map_or(0, |p| p.iter().filter(|&&p| p >= 0).count()),
            None => 0,
        };
        format!(
            "Hits({n} rays, {hits} hit; keys {})",
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

    /// The number of query points.
    fn __len__(&self, py: Python<'_>) -> usize {
        self.distance.bind(py).len().unwrap_or(0)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self.distance.bind(py).len().unwrap_or(0);
        format!("ClosestPoints({n} points; keys point, distance, prim, u, v)")
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

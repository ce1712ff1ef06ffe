//! Python arguments read by name: a value of the wrong type raises a
//! `TypeError` that names the argument, says what it wanted and quotes
//! what it got (`threads must be a whole number …; got float 1.5`), where
//! pyo3's own conversions say only "'float' object cannot be interpreted
//! as an integer" (the argument's name goes to a note that `str(e)` does
//! not show). A bool is not a number here: `threads=True` and
//! `t_min=True` are refused, not read as 1.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyInt, PyString};
use std::path::PathBuf;

/// What `obj` is, for a message: its type and value (`float 1.5`, `str
/// 'yes'`, `list [0, 0, 0, 0]`), or the shape of an array.
pub fn described(obj: &Bound<'_, PyAny>) -> String {
    let kind = obj
        .get_type()
        .name()
        .map_or_else(|_| "object".to_string(), |n| n.to_string());
    if let Some(shape) = array_shape(obj) {
        let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
        let trailing = if dims.len() == 1 { "," } else { "" };
        return format!("{kind} of shape ({}{trailing})", dims.join(", "));
    }
    let repr = obj.repr().map_or_else(|_| String::new(), |r| r.to_string());
    const LONGEST: usize = 60;
    let repr = if repr.chars().count() > LONGEST {
        let cut: String = repr.chars().take(LONGEST - 1).collect();
        format!("{cut}…")
    } else {
        repr
    };
    format!("{kind} {repr}")
}

/// The shape of an array of one axis or more (numpy's, or any object with
/// `ndim` and `shape`); `None` for anything else, a 0-d array included.
fn array_shape(obj: &Bound<'_, PyAny>) -> Option<Vec<usize>> {
    let ndim: usize = obj.getattr("ndim").ok()?.extract().ok()?;
    if ndim == 0 {
        return None;
    }
    obj.getattr("shape").ok()?.extract().ok()
}

/// Python's bool or numpy's, which convert to numbers but mean none.
fn is_bool(obj: &Bound<'_, PyAny>) -> bool {
    if obj.is_instance_of::<PyBool>() {
        return true;
    }
    let ty = obj.get_type();
    ty.module().is_ok_and(|m| m == "numpy") && ty.name().is_ok_and(|n| n == "bool_" || n == "bool")
}

fn wrong_type(name: &str, what: &str, obj: &Bound<'_, PyAny>) -> PyErr {
    PyTypeError::new_err(format!("{name} must be {what}; got {}", described(obj)))
}

/// A whole number: a Python or numpy int, not a bool, a float or a str.
/// `what` is what the argument wants, for the message ("a whole number
/// from 1 to 4096"); an int past 64 bits is a `ValueError` in those words.
pub fn whole(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<i64> {
    if is_bool(obj) {
        return Err(wrong_type(name, what, obj));
    }
    match obj.extract::<i64>() {
        Ok(v) => Ok(v),
        Err(_) if obj.is_instance_of::<PyInt>() || obj.hasattr("__index__")? => Err(
            PyValueError::new_err(format!("{name} must be {what}; got {obj}")),
        ),
        Err(_) => Err(wrong_type(name, what, obj)),
    }
}

/// A real number: an int or a float (Python's or numpy's, or anything
/// with `__float__`), not a bool, a str or an array of one axis or more.
pub fn real(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<f64> {
    let text = obj.is_instance_of::<PyString>()
        || obj.is_instance_of::<PyBytes>()
        || obj.is_instance_of::<PyByteArray>();
    if is_bool(obj) || text || array_shape(obj).is_some() {
        return Err(wrong_type(name, what, obj));
    }
    obj.extract::<f64>()
        .map_err(|_| wrong_type(name, what, obj))
}

/// `True` or `False` (Python's or numpy's), not a str or a number.
pub fn flag(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<bool> {
    if !is_bool(obj) {
        return Err(wrong_type(name, "True or False", obj));
    }
    obj.extract::<bool>()
        .map_err(|_| wrong_type(name, "True or False", obj))
}

/// A str (a name such as "sobol"); `what` names the choices.
pub fn text(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<String> {
    if !obj.is_instance_of::<PyString>() {
        return Err(wrong_type(name, what, obj));
    }
    obj.extract::<String>()
}

/// `[f(value)]` for an optional argument: `None` (left out, or given as
/// None) stays `None`.
pub fn optional<T>(
    obj: Option<&Bound<'_, PyAny>>,
    f: impl FnOnce(&Bound<'_, PyAny>) -> PyResult<T>,
) -> PyResult<Option<T>> {
    obj.filter(|o| !o.is_none()).map(f).transpose()
}

/// A file path: a str, an `os.PathLike` (`pathlib.Path`) or bytes, as
/// `os.fspath` takes them (bytes decoded as the file system's names are,
/// by `os.fsdecode`).
pub fn path(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<PathBuf> {
    let os = obj.py().import("os")?;
    let path = os.call_method1("fspath", (obj,)).map_err(|_| {
        wrong_type(
            name,
            "a path (a str or an os.PathLike such as pathlib.Path)",
            obj,
        )
    })?;
    let path = if path.is_instance_of::<PyBytes>() {
        os.call_method1("fsdecode", (path,))?
    } else {
        path
    };
    path.extract::<PathBuf>()
}

/// The `signed` of `Mesh.closest_point` (from_py_with: pyo3 adds no name).
pub fn signed(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    flag(obj, "signed")
}

/// The `uv` of `Mesh.all_hits`.
pub fn uv(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    flag(obj, "uv")
}

/// The `bad_rays` of a ray query: "raise" or "miss".
pub fn bad_rays(obj: &Bound<'_, PyAny>) -> PyResult<&'static str> {
    const WHAT: &str = "\"raise\" or \"miss\"";
    match text(obj, "bad_rays", WHAT)?.as_str() {
        "raise" => Ok("raise"),
        "miss" => Ok("miss"),
        other => Err(PyValueError::new_err(format!(
            "bad_rays must be {WHAT}; got {other:?}"
        ))),
    }
}

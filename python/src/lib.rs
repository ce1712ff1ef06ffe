//! `strata_rt._native`: strata's ray queries and renders for Python.
//!
//! A thin layer over the library: [`convert`] turns numpy arrays (any
//! float or integer dtype, lists, non-contiguous views) into strata's
//! types and refuses bad input with a `ValueError` that names the
//! argument; [`args`] reads the other arguments (numbers, flags, names,
//! paths), a wrong type a `TypeError` that names the argument; [`mesh`] holds the BVH and answers the ray and point queries;
//! [`run`] runs a query's rays on rayon with the GIL released, in chunks
//! between which Ctrl-C is checked, on no more threads than a chunk has
//! tasks (one task, or `threads=1`, on the calling thread); [`render`] is `strata render` returning
//! arrays (its warnings raised as Python warnings, Ctrl-C checked between
//! passes). The Python package (`python/strata_rt/`) re-exports all of it.

mod args;
mod convert;
mod mesh;
mod mesh_objects;
mod render;
mod results;
mod run;

use pyo3::prelude::*;

pyo3::create_exception!(
    strata_rt,
    InputError,
    pyo3::exceptions::PyValueError,
    "A file or scene strata cannot use: the message is strata's one line, naming the file and the key or line."
);

/// strata's ray queries (first hit, occlusion, every crossing, inside or
/// outside, closest point) on triangle meshes, and its renders, with numpy
/// arrays in and out.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<mesh::Mesh>()?;
    m.add_class::<results::Hits>()?;
    m.add_class::<results::ClosestPoints>()?;
    m.add_class::<results::Crossings>()?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("__version__", strata::VERSION)?;
    Ok(())
}

//! Other libraries' mesh objects passed as ``Mesh(obj)``: their vertices
//! and faces read by what they have, without importing their library.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// An Open3D tensor (``o3d.core.Tensor``) as a numpy array (from the CPU,
/// wherever it lies); anything else as it is.
fn tensor_to_numpy<'py>(obj: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if !obj.hasattr("numpy")? {
        return Ok(obj);
    }
    let obj = if obj.hasattr("cpu")? {
        obj.call_method0("cpu")?
    } else {
        obj
    };
    obj.call_method0("numpy")
}

/// ``obj.<table>[<key>]`` of an Open3D tensor mesh's attribute table
/// (``vertex["positions"]``), if it has one.
fn tensor_entry<'py>(
    obj: &Bound<'py, PyAny>,
    table: &str,
    key: &str,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let Ok(table) = obj.getattr(table) else {
        return Ok(None);
    };
    if !table.contains(key).unwrap_or(false) {
        return Ok(None);
    }
    table.get_item(key).map(Some)
}

/// ``vertices`` and ``faces`` of one object passed as ``Mesh(obj)``, by
/// what it has (nothing is imported): a trimesh.Trimesh (``vertices``,
/// ``faces``), a legacy Open3D ``o3d.geometry.TriangleMesh`` (``vertices``,
/// ``triangles``, which numpy reads as they are) or a tensor
/// ``o3d.t.geometry.TriangleMesh`` (``vertex.positions``,
/// ``triangle.indices``, by their ``numpy()``).
pub fn vertices_and_faces_of<'py>(
    obj: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let kind = obj.get_type().name()?;
    if obj.hasattr("geometry")? && obj.hasattr("graph")? {
        // trimesh.load's answer for a GLB, a glTF or any file of several
        // meshes: a scene of meshes and where each is placed.
        // A newer trimesh has `Scene.to_mesh` (its `load_mesh` is
        // `load_scene(...).to_mesh()`); an older one `dump(concatenate=True)`.
        let how = if obj.hasattr("to_mesh")? {
            "trimesh.load_mesh(path) (or trimesh.load(path, force=\"mesh\")) loads one, and \
             scene.to_mesh() joins this scene's meshes, each where the scene places it"
        } else {
            "trimesh.load(path, force=\"mesh\") loads one, and scene.dump(concatenate=True) \
             joins this scene's meshes, each where the scene places it"
        };
        return Err(PyTypeError::new_err(format!(
            "Mesh takes one mesh, and a {kind} is a scene of meshes (what trimesh.load gives \
             for a GLB, a glTF or a file of several meshes): {how}; or \
             strata_rt.Mesh.load(path) reads the file with strata's own loader"
        )));
    }
    if obj.hasattr("vertices")? {
        for faces in ["faces", "triangles"] {
            if obj.hasattr(faces)? {
                return Ok((obj.getattr("vertices")?, obj.getattr(faces)?));
            }
        }
    }
    if obj.hasattr("vertex")? && obj.hasattr("triangle")? {
        // An empty tensor mesh has neither (a mesh of no triangles).
        let numpy = obj.py().import("numpy")?;
        let none = |dtype: &str| numpy.call_method1("zeros", ((0, 3), dtype));
        let positions = match tensor_entry(obj, "vertex", "positions")? {
            Some(v) => tensor_to_numpy(v)?,
            None => none("float64")?,
        };
        let indices = match tensor_entry(obj, "triangle", "indices")? {
            Some(f) => tensor_to_numpy(f)?,
            None => none("int64")?,
        };
        return Ok((positions, indices));
    }
    Err(PyTypeError::new_err(format!(
        "Mesh takes vertices and faces, or one mesh object that has them (a trimesh.Trimesh, \
         an Open3D TriangleMesh, legacy or tensor); faces is missing and a {kind} has no \
         vertices and faces (nor vertices and triangles, nor vertex.positions and \
         triangle.indices)"
    )))
}

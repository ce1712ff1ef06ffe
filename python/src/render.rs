//! `render(scene, **settings)`: `strata render` with the image returned as
//! an array. The scene is loaded, edited and rendered by the library's own
//! functions (`load_edited_scene` or `load_model_file`, `render::render`)
//! and the image is the film's `to_rgb`, as the CLI writes into its EXR:
//! the same pixels bit for bit. The thread count, passes, packets and schedule change only the time.

use crate::args::{self, optional};
use crate::mesh::rows;
use crate::run::Threads;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{
    PyFileNotFoundError, PyRuntimeWarning, PyTypeError, PyUserWarning, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::ffi::CString;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use strata::render::aov::{self, Aov};
use strata::render::progress::PassDone;
use strata::render::{
    render as render_scene, Film, Observer, RenderOptions, Schedule, SliceSpec, Warning, Window,
};
use strata::scene::edit::Edit;
use strata::scene::model::{is_model_path, load_model_file, CameraChoice, ONLY_FOR_A_MODEL};
use strata::scene::settings::GlossySampling;
use strata::scene::BuildQuality;
use strata::scene::{load_edited_scene, load_edited_text, RenderOverrides};
use toml::Value;

fn error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// An optional count: `None`, or an int from `min` up.
fn count(value: Option<&Bound<'_, PyAny>>, name: &str, min: i64) -> PyResult<Option<u32>> {
    let what = format!("an int from {min} to {}", u32::MAX);
    match optional(value, |v| args::whole(v, name, &what))? {
        None => Ok(None),
        Some(v) if v >= min && v <= u32::MAX as i64 => Ok(Some(v as u32)),
        Some(v) => Err(error(format!("{name} must be {what}; got {v}"))),
    }
}

/// An optional number (`noise`, `exposure`).
fn number(value: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<f32>> {
    optional(value, |v| args::real(v, name, "a number")).map(|v| v.map(|v| v as f32))
}

/// An optional mode given by name (`"random"`), parsed as the CLI does.
fn mode<T: std::str::FromStr<Err = String>>(
    value: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<Option<T>> {
    optional(value, |v| args::text(v, name, "a name (a str)"))?
        .map(|text| text.parse().map_err(|e| error(format!("{name}: {e}"))))
        .transpose()
}

/// A Python value as the TOML value a `--set` would give; `at` names it
/// in errors (`set["camera.fov"]`, `scene`).
fn toml_value(obj: &Bound<'_, PyAny>, at: &str) -> PyResult<Value> {
    // numpy scalars and arrays, as Python numbers and lists.
    if !obj.is_instance_of::<PyString>() && obj.hasattr("tolist")? {
        return toml_value(&obj.call_method0("tolist")?, at);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        let v: i64 = obj
            .extract()
            .map_err(|_| error(format!("{at}: {obj} does not fit a 64-bit integer")))?;
        return Ok(Value::Integer(v));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(obj.extract()?));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Value::String(obj.extract()?));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items: PyResult<Vec<Value>> =
            obj.try_iter()?.map(|item| toml_value(&item?, at)).collect();
        return Ok(Value::Array(items?));
    }
    if let Ok(dict) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let k: String = k
                .extract()
                .map_err(|_| error(format!("{at}: table keys must be strings")))?;
            table.insert(k, toml_value(&v, at)?);
        }
        return Ok(Value::Table(table));
    }
    Err(error(format!(
        "{at}: a {} is not a scene value (a bool, number, string, list or dict)",
        obj.get_type().name()?
    )))
}

/// `render`'s `camera`: a model file's camera N (0-based), or "auto",
/// strata's framing camera, as `--camera` takes; a scene has its own.
fn camera_choice(
    camera: Option<&Bound<'_, PyAny>>,
    source: &SceneSource,
) -> PyResult<Option<CameraChoice>> {
    let Some(camera) = camera.filter(|c| !c.is_none()) else {
        return Ok(None);
    };
    if !matches!(source, SceneSource::File(path) if is_model_path(path)) {
        return Err(error(format!("camera {ONLY_FOR_A_MODEL}")));
    }
    let text = match camera.extract::<i64>() {
        Ok(n) if !camera.is_instance_of::<PyBool>() => n.to_string(),
        _ => camera.extract::<String>().unwrap_or_default(),
    };
    text.parse::<CameraChoice>().map(Some).map_err(|e| {
        error(format!(
            "camera must be a camera number (0, 1, …) or \"auto\"; got {}: {e}",
            camera.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    })
}

/// Where `render`'s scene comes from.
enum SceneSource {
    File(PathBuf),
    /// TOML text: given as a string with a line break, or a dict written
    /// as TOML.
    Text(String),
}

/// The name a scene given as text has in errors; its relative paths are
/// resolved against the working directory.
const TEXT_SCENE: &str = "<scene>";

/// `render`'s `scene`: a path (str, os.PathLike or bytes), TOML text (a str
/// with a line break), or a dict of the scene file's tables.
fn scene_source(scene: &Bound<'_, PyAny>) -> PyResult<SceneSource> {
    if let Ok(dict) = scene.cast::<PyDict>() {
        let Value::Table(table) = toml_value(dict.as_any(), "scene")? else {
            unreachable!("a dict is a table")
        };
        let text = toml::to_string(&table).map_err(|e| error(format!("scene: {e}")))?;
        return Ok(SceneSource::Text(text));
    }
    if scene.is_instance_of::<PyString>() {
        let text: String = scene.extract()?;
        if text.contains('\n') {
            return Ok(SceneSource::Text(text));
        }
    }
    args::path(scene, "scene")
        .map(SceneSource::File)
        .map_err(|_| {
            PyTypeError::new_err(format!(
                "scene must be a path, TOML text or a dict of the scene file's tables; got {}",
                args::described(scene)
            ))
        })
}

/// `set=`: a dict of key path to value, or `"KEY=VALUE"` strings as
/// `--set` takes them.
fn edits(set: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Edit>> {
    let Some(set) = set else {
        return Ok(Vec::new());
    };
    if let Ok(dict) = set.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in dict.iter() {
            let path: String = k
                .extract()
                .map_err(|_| error("set: keys must be key paths such as \"camera.fov\"".into()))?;
            // None removes the key, as `--set KEY=` does.
            let value = if v.is_none() {
                None
            } else {
                Some(toml_value(&v, &format!("set[{path:?}]"))?)
            };
            out.push(Edit { path, value });
        }
        return Ok(out);
    }
    let texts: Vec<String> = if set.is_instance_of::<PyString>() {
        vec![set.extract()?]
    } else {
        set.extract().map_err(|_| {
            error(
                "set must be a dict {\"camera.fov\": 30} or a list of \"KEY=VALUE\" strings".into(),
            )
        })?
    };
    texts
        .iter()
        .map(|t| t.parse::<Edit>().map_err(|e| error(format!("set: {e}"))))
        .collect()
}

/// `aovs=`: False or None (none), True (all three), or names.
fn aov_list(aovs: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Aov>> {
    let Some(aovs) = aovs else {
        return Ok(Vec::new());
    };
    if let Ok(all) = aovs.extract::<bool>() {
        return Ok(if all { Aov::ALL.to_vec() } else { Vec::new() });
    }
    let names: Vec<String> = if aovs.is_instance_of::<PyString>() {
        vec![aovs.extract()?]
    } else {
        aovs.extract().map_err(|_| {
            error("aovs must be True, False or a list of names (albedo, normal, depth, spp)".into())
        })?
    };
    names
        .iter()
        .map(|n| n.parse::<Aov>().map_err(|e| error(format!("aovs: {e}"))))
        .collect()
}

/// `crop=`: (x0, y0, x1, y1) or `"X0,Y0,X1,Y1"`, as `--crop`.
fn crop_text(crop: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(crop) = crop else {
        return Ok(None);
    };
    if crop.is_instance_of::<PyString>() {
        return Ok(Some(crop.extract()?));
    }
    let c: [i64; 4] = crop
        .extract()
        .map_err(|_| error("crop must be (x0, y0, x1, y1): four ints, pixels, half-open".into()))?;
    Ok(Some(format!("{},{},{},{}", c[0], c[1], c[2], c[3])))
}

/// strata's error for a scene it cannot use, in the package's words: what
/// the CLI blames on its command line (`<command line>: --set camera.foo:
/// …`, `--spp 0`, `--camera`) is blamed on the argument of `render` that
/// gave it (`set["camera.foo"]: …`, `spp=0: …`, `camera: …`).
fn in_python_words(mut e: strata::error::InputError) -> strata::error::InputError {
    if e.file == strata::error::COMMAND_LINE {
        e.file = argument_of(&e.location);
        e.location = String::new();
    }
    e.more = e.more.into_iter().map(in_python_words).collect();
    e
}

/// The argument of `render` that the CLI's `flag` stands for: `--set
/// camera.fov=0` is `set["camera.fov"] = 0`, `--spp 0` is `spp=0`,
/// `--camera` is `camera`.
fn argument_of(flag: &str) -> String {
    if flag == "--set" {
        return "set".to_string();
    }
    if let Some(edit) = flag.strip_prefix("--set ") {
        return match edit.split_once('=') {
            None => format!("set[{:?}]", edit.trim()),
            Some((path, "")) => format!("set[{:?}] = None", path.trim()),
            Some((path, value)) => format!("set[{:?}] = {}", path.trim(), value.trim()),
        };
    }
    let Some(flag) = flag.strip_prefix("--") else {
        return if flag.is_empty() {
            "render".to_string()
        } else {
            flag.to_string()
        };
    };
    match flag.split_once(' ') {
        Some((name, value)) => format!("{}={value}", name.replace('-', "_")),
        None => flag.replace('-', "_"),
    }
}

/// Raises each of the scene's and the render's warnings as a Python
/// warning, in strata's words: the loaders' and those of the settings as
/// `UserWarning`, samples the film dropped as `RuntimeWarning`.
fn warn(py: Python<'_>, scene: &[strata::error::InputError], render: &[Warning]) -> PyResult<()> {
    warn_input(py, scene)?;
    let found = render.iter().map(|w| {
        let user = !matches!(w, Warning::InvalidSamples { .. });
        (w.to_string(), user)
    });
    for (message, user) in found {
        let category = if user {
            py.get_type::<PyUserWarning>()
        } else {
            py.get_type::<PyRuntimeWarning>()
        };
        let message = CString::new(message).unwrap_or_default();
        PyErr::warn(py, &category, &message, 1)?;
    }
    Ok(())
}

/// Raises each of `said` (what a loader or the scene's settings read
/// leniently) as a `UserWarning`, in strata's words.
pub(crate) fn warn_input(py: Python<'_>, said: &[strata::error::InputError]) -> PyResult<()> {
    let category = py.get_type::<PyUserWarning>();
    for w in said {
        let message = CString::new(w.to_string()).unwrap_or_default();
        PyErr::warn(py, &category, &message, 1)?;
    }
    Ok(())
}

/// Checks for Ctrl-C at each pass's end, with the GIL taken for the
/// check, and ends the render there if one came, keeping its
/// `KeyboardInterrupt` to raise.
#[derive(Default)]
struct Interrupt(Option<PyErr>);

impl Observer for Interrupt {
    fn pass_done(&mut self, _: &Film, _: &PassDone) -> ControlFlow<()> {
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.0 = Some(e);
                ControlFlow::Break(())
            }
        }
    }
}

/// Render a scene file, or a model file as it comes, as ``strata render``
/// does, and return the image: float32 (height, width, 3), linear RGB, the
/// pixels of the CLI's EXR output bit for bit.
///
/// ``scene`` is a path (str or os.PathLike), the scene file's TOML text (a
/// str with a line break), or a dict of its tables (``{"camera": {...},
/// "objects": [...]}``); text and dicts render as the same file would,
/// their relative paths resolved against the working directory and their
/// errors naming ``<scene>``. A path to a model file (.obj, .ply, .gltf,
/// .glb, .off, .stl) renders it with its own camera and lights, or framed
/// and lit by a studio where it has none, as ``strata render MODEL`` does
/// (``set`` then edits that made scene, as ``--set`` does); ``camera=N``
/// renders from its camera N (0-based) instead, ``camera="auto"`` from
/// the studio's framing camera, as ``--camera`` does.
///
/// Every setting is the flag of the same name (``spp=64`` is ``--spp
/// 64``), and overrides the scene file's ``[render]`` table; ``set`` edits
/// any value of the file by key path, as ``--set`` does: a dict
/// (``{"camera.fov": 30, "lights[0].radiance": [1, 1, 1]}``; a value of
/// ``None`` removes the key, as ``--set KEY=`` does) or ``"KEY=VALUE"``
/// strings. ``crop=(x0, y0, x1, y1)`` renders only that
/// window (each pixel as in the whole image). ``aovs=True`` (or a list of
/// ``"albedo"``, ``"normal"``, ``"depth"``, ``"spp"``) also returns a dict
/// of the AOVs: albedo and normal (height, width, 3), depth and spp (the
/// samples each pixel took) (height, width). ``noise=0.02`` samples
/// adaptively: each pixel takes s/0.02² samples, s the estimated standard
/// deviation of its samples' luminance, while its neighbours go on
/// (``spp`` the ceiling, default 1024). ``exposure`` and ``tonemap`` are what an 8-bit file shows: the
/// array stays linear radiance (exposure only scales what the noise
/// target judges). ``integrator="path"`` traces light past the first
/// bounce (``"distribution"``, the seed's ray tracer, is the default for
/// scene files).
/// ``threads``, ``passes``, ``packets``, ``schedule`` and ``bvh_quality``
/// change the time, never a pixel.
///
/// The GIL is released while it renders; Ctrl-C ends it at the end of a
/// pass with ``KeyboardInterrupt``. What ``strata render`` warns of (a
/// mesh read leniently, a scene without light, more passes than samples)
/// is raised as a ``UserWarning``, and samples dropped as NaN or infinite
/// as a ``RuntimeWarning``. A bad setting raises ValueError naming it (one
/// of the wrong type, a bool for a number among them, TypeError); a scene
/// strata cannot read raises ``strata_rt.InputError`` with strata's
/// one-line message, which names the argument at fault where it is one of
/// these (``set["camera.fov"]: …``, ``camera: …``) rather than a flag.
#[pyfunction]
#[pyo3(signature = (
    scene, *, width=None, height=None, spp=None, shadow_samples=None,
    reflection_samples=None, max_depth=None, sampler=None, seed=None, background=None,
    light_sampling=None, glossy_sampling=None, noise=None, exposure=None, tonemap=None,
    integrator=None, set=None, camera=None, threads=None, passes=None,
    packets=None, schedule=None, bvh_quality=None, crop=None, aovs=None
))]
#[allow(clippy::too_many_arguments)]
pub fn render(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    width: Option<&Bound<'_, PyAny>>,
    height: Option<&Bound<'_, PyAny>>,
    spp: Option<&Bound<'_, PyAny>>,
    shadow_samples: Option<&Bound<'_, PyAny>>,
    reflection_samples: Option<&Bound<'_, PyAny>>,
    max_depth: Option<&Bound<'_, PyAny>>,
    sampler: Option<&Bound<'_, PyAny>>,
    seed: Option<&Bound<'_, PyAny>>,
    background: Option<&Bound<'_, PyAny>>,
    light_sampling: Option<&Bound<'_, PyAny>>,
    glossy_sampling: Option<&Bound<'_, PyAny>>,
    noise: Option<&Bound<'_, PyAny>>,
    exposure: Option<&Bound<'_, PyAny>>,
    tonemap: Option<&Bound<'_, PyAny>>,
    integrator: Option<&Bound<'_, PyAny>>,
    set: Option<&Bound<'_, PyAny>>,
    camera: Option<&Bound<'_, PyAny>>,
    threads: Option<&Bound<'_, PyAny>>,
    passes: Option<&Bound<'_, PyAny>>,
    packets: Option<&Bound<'_, PyAny>>,
    schedule: Option<&Bound<'_, PyAny>>,
    bvh_quality: Option<&Bound<'_, PyAny>>,
    crop: Option<&Bound<'_, PyAny>>,
    aovs: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let background = background
        .map(|b| {
            b.extract::<[f32; 3]>()
                .map_err(|_| error("background must be three numbers [r, g, b]".into()))
        })
        .transpose()?;
    let overrides = RenderOverrides {
        width: count(width, "width", 1)?,
        height: count(height, "height", 1)?,
        spp: count(spp, "spp", 1)?,
        shadow_samples: count(shadow_samples, "shadow_samples", 1)?,
        reflection_samples: count(reflection_samples, "reflection_samples", 1)?,
        max_depth: count(max_depth, "max_depth", 0)?,
        sampler: mode(sampler, "sampler")?,
        seed: count(seed, "seed", 0)?,
        background,
        light_sampling: mode(light_sampling, "light_sampling")?,
        glossy_sampling: mode::<GlossySampling>(glossy_sampling, "glossy_sampling")?,
        noise: number(noise, "noise")?,
        exposure: number(exposure, "exposure")?,
        tonemap: mode(tonemap, "tonemap")?,
        integrator: mode(integrator, "integrator")?,
    };
    overrides
        .check()
        .map_err(|bad| error(format!("{}={}: {}", bad.field, bad.value, bad.message)))?;
    let edits = edits(set)?;
    let pool = Threads::new(threads)?;
    let passes = count(passes, "passes", 1)?;
    if let (Some(p), Some(e)) = (passes, overrides.noise) {
        return Err(error(format!(
            "passes={p} with noise={e}: a noise target's passes are its decision points (after 4, 8, 12, 16, … samples); leave passes out"
        )));
    }
    let packets = mode(packets, "packets")?.unwrap_or_default();
    let schedule: Schedule = mode(schedule, "schedule")?.unwrap_or_default();
    let quality: BuildQuality = mode(bvh_quality, "bvh_quality")?.unwrap_or_default();
    let crop = crop_text(crop)?;
    let aovs = aov_list(aovs)?;

    let source = scene_source(scene)?;
    let camera = camera_choice(camera, &source)?;
    let loaded = py.detach(|| {
        pool.install(|| match &source {
            SceneSource::File(path) if is_model_path(path) => {
                load_model_file(path, &edits, &overrides, quality, camera)
            }
            SceneSource::File(path) => load_edited_scene(path, &edits, &overrides, quality),
            SceneSource::Text(text) => {
                let path = Path::new(TEXT_SCENE);
                load_edited_text(text, path, &edits, &overrides, quality)
            }
        })
    })?;
    let scene = match (loaded.map_err(in_python_words), &source) {
        (Ok((scene, _)), _) => scene,
        (Err(e), SceneSource::File(path)) if !path.exists() => {
            return Err(PyFileNotFoundError::new_err(e.to_string()))
        }
        (Err(e), _) => return Err(crate::InputError::new_err(e.to_string())),
    };
    let s = &scene.settings;
    let window = crop
        .map(|text| Window::crop(&text, s.width, s.height).map_err(|e| error(format!("crop: {e}"))))
        .transpose()?;
    // Weighed before the film is made: a size past the machine's memory is
    // an exception naming it, not an aborted interpreter.
    let (w, h) = window
        .as_ref()
        .map_or((s.width, s.height), |w| (w.width(), w.height()));
    strata::render::film::check_memory(w, h, !aovs.is_empty(), true).map_err(|m| {
        let given = if window.is_some() {
            "crop"
        } else {
            "width, height"
        };
        error(format!("{given}: {m}"))
    })?;
    let opts = RenderOptions {
        threads: pool.count(),
        slice: SliceSpec::WHOLE,
        schedule,
        passes,
        resume_from: None,
        packets,
        window: window.clone(),
        aovs: !aovs.is_empty(),
        timeline: None,
        budget: None,
        cpu_times: false,
    };
    let mut interrupt = Interrupt::default();
    let outcome = py.detach(|| render_scene(&scene, &opts, None, &mut interrupt));
    if let Some(e) = interrupt.0 {
        return Err(e);
    }
    warn(py, &scene.warnings, &outcome.warnings)?;
    let window = window.unwrap_or_else(|| Window::whole(s.width, s.height));
    let (w, h) = (window.width() as usize, window.height() as usize);
    let pixels: Vec<[f32; 3]> = outcome.film.to_rgb().iter().map(|p| p.to_array()).collect();
    let image = rows(py, pixels)?.reshape([h, w, 3])?;
    let Some(sums) = outcome.aov.as_deref().filter(|_| !aovs.is_empty()) else {
        return Ok(image.into_any().unbind());
    };
    // The EXR's own channels (`aov::channels`), regrouped per AOV.
    let mut channels = aov::channels(sums, &aovs).into_iter();
    let dict = PyDict::new(py);
    for a in &aovs {
        let planes: Vec<Vec<f32>> = channels
            .by_ref()
            .take(a.channels().len())
            .map(|(_, v)| v)
            .collect();
        let array = if let [plane] = &planes[..] {
            PyArray1::from_slice(py, plane).reshape([h, w])?.into_any()
        } else {
            let flat: Vec<f32> = (0..w * h)
                .flat_map(|i| planes.iter().map(move |p| p[i]))
                .collect();
            PyArray1::from_vec(py, flat)
                .reshape([h, w, planes.len()])?
                .into_any()
        };
        dict.set_item(a.name(), array)?;
    }
    Ok((image, dict).into_pyobject(py)?.into_any().unbind())
}

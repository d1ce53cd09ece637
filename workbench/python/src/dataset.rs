//! `flarebench.Sampler`: the dataset sampler of `flarebench dataset`
//! ([`flarebench::dataset::Sampler`]), its samples as dicts and rendered as NumPy arrays by
//! [`render_sample`] — the function the CLI writes its files from, so a sample's layers are
//! the EXR's channels bit for bit and its annotation is the JSON file's content.
//!
//! A sample is a pure function of `(seed, index)` and the sampler's TOML text: the sampler
//! keeps that text (and where mask paths are relative to), so it pickles by being read again
//! from it, and a DataLoader's worker processes draw the same samples as the parent.
//!
//! The GIL is released while a sample is drawn and rendered.

use std::path::{Path, PathBuf};

use flarebench::dataset::{SampleOutput, Sampler as RustSampler, SamplerError, render_sample};
use flarebench_sdk::image::HdrImage;
use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray2, PyArray3};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

use crate::errors::{runtime_error, value_error};

/// The name errors give a sampler read from a string.
const STRING_ORIGIN: &str = "<string>";
/// The name errors give the sampler of the defaults (as `Sampler::with_defaults`).
const DEFAULTS_ORIGIN: &str = "(defaults)";

/// A dataset sampler: lenses, f-numbers, apertures and lights drawn at random, each sample a
/// pure function of `(seed, index)`, as `flarebench dataset` draws them (docs/datasets.md
/// § The sampler lists the TOML fields).
///
/// Sampler(config=None, *, base=None): `config` is None (every field's default), a path to a
/// sampler TOML file (a `str` without a newline, `=` or `[`, or a `pathlib.Path`), or the
/// TOML text itself (a `str` holding a newline, `=` or `[`; `""` is the defaults). Mask and
/// dust paths in it are relative to `base`: by default the file's folder, or the current
/// folder for a string. A missing file raises FileNotFoundError; a field out of its domain,
/// misspelt or of the wrong type ValueError with the origin, line, column and field.
#[pyclass(frozen, module = "flarebench")]
#[derive(Debug)]
pub struct Sampler {
    inner: RustSampler,
    text: String,
    origin: String,
    base: PathBuf,
}

/// A `str` that is TOML text rather than a path.
fn is_toml_text(s: &str) -> bool {
    s.contains(['\n', '=', '['])
}

fn sampler_error(e: SamplerError) -> PyErr {
    match e {
        SamplerError::Read { .. } => PyOSError::new_err(e.to_string()),
        SamplerError::Field { .. } => PyValueError::new_err(e.to_string()),
    }
}

impl Sampler {
    /// Reads a sampler from its TOML text (no Python involved; the GIL may be released).
    fn build(text: String, origin: String, base: PathBuf) -> PyResult<Sampler> {
        let inner = RustSampler::from_toml_str(&text, &origin, &base).map_err(sampler_error)?;
        Ok(Sampler {
            inner,
            text,
            origin,
            base,
        })
    }

    /// Reads the sampler file at `path`, as `Sampler::from_file` does: errors name the path,
    /// mask paths are relative to its folder unless `base` is given.
    fn read(path: &Path, base: Option<PathBuf>) -> PyResult<Sampler> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            let msg = format!("could not read the sampler `{origin}`: {e}");
            if e.kind() == std::io::ErrorKind::NotFound {
                PyFileNotFoundError::new_err(msg)
            } else {
                PyOSError::new_err(msg)
            }
        })?;
        let base = base.unwrap_or_else(|| path.parent().unwrap_or(Path::new(".")).to_path_buf());
        Sampler::build(text, origin, base)
    }
}

/// `value` (anything serde serialises) as a Python object, through JSON: dicts, lists,
/// floats (serde_json writes each f64 so that it reads back to the same bits), ints, strings,
/// booleans and None.
fn to_python<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| PyValueError::new_err(format!("internal error: to JSON: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// An image as an H×W×3 float32 array (row-major, linear RGB).
fn rgb<'py>(py: Python<'py>, img: HdrImage) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (w, h) = (img.width, img.height);
    let flat: Vec<f32> = img.pixels.into_iter().flatten().collect();
    let a = Array3::from_shape_vec((h, w, 3), flat)
        .map_err(|e| PyValueError::new_err(format!("internal error: image shape: {e}")))?;
    Ok(PyArray3::from_owned_array(py, a))
}

/// A rendered sample as a dict of NumPy arrays and its annotation.
fn sample_dict<'py>(py: Python<'py>, out: SampleOutput) -> PyResult<Bound<'py, PyDict>> {
    let (w, h) = (out.flare.width, out.flare.height);
    let d = PyDict::new(py);
    d.set_item("annotation", to_python(py, &out.annotation)?)?;
    d.set_item("image", rgb(py, out.flare)?)?;
    d.set_item("ghosts", rgb(py, out.ghosts)?)?;
    if let Some(s) = out.starburst {
        d.set_item("starburst", rgb(py, s)?)?;
    }
    if !out.per_light.is_empty() {
        let lights = PyList::empty(py);
        for l in out.per_light {
            lights.append(rgb(py, l)?)?;
        }
        d.set_item("lights", lights)?;
    }
    if let Some(ids) = out.ghost_id {
        let a = Array2::from_shape_vec((h, w), ids)
            .map_err(|e| PyValueError::new_err(format!("internal error: ID shape: {e}")))?;
        d.set_item("ghost_id", PyArray2::from_owned_array(py, a))?;
    }
    Ok(d)
}

#[pymethods]
impl Sampler {
    #[new]
    #[pyo3(signature = (config = None, *, base = None))]
    fn new(
        py: Python<'_>,
        config: Option<&Bound<'_, PyAny>>,
        base: Option<PathBuf>,
    ) -> PyResult<Sampler> {
        let Some(config) = config else {
            let base = base.unwrap_or_else(|| PathBuf::from("."));
            return py.detach(|| Sampler::build(String::new(), DEFAULTS_ORIGIN.into(), base));
        };
        if let Ok(s) = config.cast::<PyString>() {
            let s = s.to_cow()?.into_owned();
            if s.is_empty() || is_toml_text(&s) {
                let base = base.unwrap_or_else(|| PathBuf::from("."));
                return py.detach(|| Sampler::build(s, STRING_ORIGIN.into(), base));
            }
        }
        let path: PathBuf = config.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "config `{config}` is not None, a path or a sampler's TOML text"
            ))
        })?;
        py.detach(|| Sampler::read(&path, base))
    }

    /// from_toml(text, origin="<string>", base=".")
    ///
    /// The sampler of TOML `text`; `origin` names it in errors, mask and dust paths are
    /// relative to `base`.
    #[staticmethod]
    #[pyo3(signature = (text, origin = STRING_ORIGIN.to_string(), base = PathBuf::from(".")))]
    fn from_toml(py: Python<'_>, text: String, origin: String, base: PathBuf) -> PyResult<Sampler> {
        py.detach(|| Sampler::build(text, origin, base))
    }

    /// The configuration with every default filled in, as `dataset.json`'s `sampler`.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, self.inner.config())
    }

    /// The lenses drawn from, sorted by name: `(name, weight)` pairs.
    #[getter]
    fn lenses(&self) -> Vec<(String, f64)> {
        self.inner
            .lenses()
            .iter()
            .map(|l| (l.name.clone(), l.weight))
            .collect()
    }

    /// The frame's `(width, height)` in pixels.
    #[getter]
    fn size(&self) -> (usize, usize) {
        let [w, h] = self.inner.config().size.0;
        (w, h)
    }

    /// The sampler's TOML text (`""` for the defaults).
    #[getter]
    fn toml(&self) -> &str {
        &self.text
    }

    /// sample(seed, index) -> dict
    ///
    /// Sample `index` of the dataset seeded `seed`: every sampled parameter (lens, size,
    /// quality, f-number, aperture, dust, lights, layers), the annotation's `sample`.
    fn sample<'py>(&self, py: Python<'py>, seed: u64, index: u64) -> PyResult<Bound<'py, PyAny>> {
        let spec = py
            .detach(|| self.inner.sample(seed, index))
            .map_err(|e| value_error(&e))?;
        to_python(py, &spec)
    }

    /// render(seed, index) -> dict
    ///
    /// Sample `index` of the dataset seeded `seed`, rendered as `flarebench dataset` renders
    /// it: `image` (the flare, H×W×3 float32, linear RGB), `ghosts`, `starburst` (with
    /// starbursts), `lights` (with `per_light`: a list, one H×W×3 array per light), `ghost_id`
    /// (with `ghost_id`: H×W uint32) and `annotation` (the sample's JSON file as a dict).
    /// The arrays equal the EXR's channels bit for bit. The GIL is released meanwhile.
    fn render<'py>(&self, py: Python<'py>, seed: u64, index: u64) -> PyResult<Bound<'py, PyDict>> {
        let spec = py
            .detach(|| self.inner.sample(seed, index))
            .map_err(|e| value_error(&e))?;
        let out = py
            .detach(|| render_sample(&spec))
            .map_err(|e| runtime_error(&e))?;
        sample_dict(py, out)
    }

    /// Pickled as its TOML text, origin and base, read again when unpickled.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let s = slf.get();
        let from_toml = py.get_type::<Sampler>().getattr("from_toml")?;
        (
            from_toml,
            (s.text.clone(), s.origin.clone(), s.base.clone()),
        )
            .into_pyobject(py)
    }

    fn __repr__(&self) -> String {
        let c = self.inner.config();
        let [w, h] = c.size.0;
        format!(
            "Sampler({}: {} lenses, {w}x{h}, quality {})",
            self.origin,
            self.inner.lenses().len(),
            c.quality.0.name()
        )
    }
}

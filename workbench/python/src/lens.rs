//! `flarebench.Lens`: a lens file, or a bundled lens by name, read as `flarebench info` reads
//! it (`lens_library::resolve`, then the file's reader), with its paraxial data at the lens's
//! default wavelength. The property names are the keys of `flarebench info --json`.

use std::path::PathBuf;

use flarebench::lens_library;
use flarebench::sensor_stack::{SensorStackArgs, SensorStackPreset};
use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::enumerate::enumerate_ghosts;
use flarebench_sdk::paraxial::{ParaxialData, analyse};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{not_found, value_error};

/// A lens: its prescription read from a file (OpenLensFlare/flarebench `.xml`, Zemax `.zmx`,
/// PBRT `.dat`, FlareSim `.lens`) or the bundled library, and its paraxial data (object at
/// infinity, at the lens's primary wavelength, else the d line).
///
/// Lens(lens, sensor_stack=None): `lens` is a path or a bundled lens's name
/// (`"heliar-tronnier"`, a unique part of one); `sensor_stack` is `"digital"` or `"none"`, as
/// `--sensor-stack` (default: the file's own). A missing lens raises FileNotFoundError, a bad
/// file ValueError naming the file, line, column and field.
#[pyclass(frozen, module = "flarebench")]
#[derive(Debug)]
pub struct Lens {
    pub system: LensSystem,
    path: PathBuf,
    paraxial: ParaxialData,
    warnings: Vec<String>,
}

impl Lens {
    /// Resolves, reads and analyses `spec` (no Python involved; the GIL may be released).
    pub fn load(spec: &str, sensor_stack: Option<&str>) -> PyResult<Lens> {
        let stack = match sensor_stack {
            None => None,
            Some("none") => Some(SensorStackPreset::None),
            Some("digital") => Some(SensorStackPreset::Digital),
            Some(other) => {
                return Err(PyValueError::new_err(format!(
                    "sensor_stack `{other}` is not one of `digital`, `none`"
                )));
            }
        };
        let path = lens_library::resolve(spec).map_err(|e| not_found(&e))?;
        let loaded =
            lens_library::load(&path.to_string_lossy(), true).map_err(|e| value_error(&e))?;
        let system = SensorStackArgs {
            sensor_stack: stack,
        }
        .apply(loaded.system)
        .map_err(|e| value_error(&e))?;
        let paraxial = analyse(&system, system.default_wavelength_nm())
            .map_err(|e| value_error(&anyhow::Error::new(e)))?;
        Ok(Lens {
            system,
            path,
            paraxial,
            warnings: loaded.warnings,
        })
    }
}

#[pymethods]
impl Lens {
    #[new]
    #[pyo3(signature = (lens, sensor_stack = None))]
    fn new(py: Python<'_>, lens: PathBuf, sensor_stack: Option<&str>) -> PyResult<Lens> {
        let spec = lens.to_string_lossy().into_owned();
        let stack = sensor_stack.map(str::to_string);
        py.detach(|| Lens::load(&spec, stack.as_deref()))
    }

    /// The lens's name (from its file).
    #[getter]
    fn name(&self) -> &str {
        &self.system.name
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// Warnings of the reader (`file:line:column: message`): assumptions and ignored tags.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Surfaces, the stop and the sensor included.
    #[getter]
    fn surface_count(&self) -> usize {
        self.system.surfaces.len()
    }

    /// The aperture stop's surface index (0-based, as `flarebench info` numbers surfaces).
    #[getter]
    fn stop_index(&self) -> Option<usize> {
        self.system.stop_index()
    }

    /// Two-reflection ghosts: one per pair of reflecting surfaces (`flarebench lenses`).
    #[getter]
    fn ghost_count(&self) -> usize {
        enumerate_ghosts(&self.system).len()
    }

    /// The film's width and height (mm): a frame spans the width.
    #[getter]
    fn film_width_mm(&self) -> f64 {
        self.system.film_width_mm
    }

    #[getter]
    fn film_height_mm(&self) -> f64 {
        self.system.film_height_mm
    }

    /// The focal length and f-number the file states, if it does.
    #[getter]
    fn stated_efl_mm(&self) -> Option<f64> {
        self.system.stated_efl_mm
    }

    #[getter]
    fn stated_f_number(&self) -> Option<f64> {
        self.system.f_number
    }

    /// The wavelength of the paraxial data (nm).
    #[getter]
    fn wavelength_nm(&self) -> f64 {
        self.paraxial.wavelength_nm
    }

    /// Effective focal length (mm).
    #[getter]
    fn efl_mm(&self) -> f64 {
        self.paraxial.efl_mm
    }

    /// Back focal length: last vertex to the rear focal point (mm).
    #[getter]
    fn bfl_mm(&self) -> f64 {
        self.paraxial.bfl_mm
    }

    /// Front focal length: front focal point to the first vertex (mm).
    #[getter]
    fn ffl_mm(&self) -> f64 {
        self.paraxial.ffl_mm
    }

    /// Paraxial f-number EFL/EPD at the working stop opening.
    #[getter]
    fn f_number(&self) -> f64 {
        self.paraxial.f_number
    }

    /// The f-number with the stop wide open.
    #[getter]
    fn open_f_number(&self) -> f64 {
        self.paraxial.open_f_number
    }

    /// Entrance pupil diameter (mm) and position from the first vertex (mm, + toward the
    /// sensor).
    #[getter]
    fn entrance_pupil_diameter_mm(&self) -> f64 {
        self.paraxial.entrance_pupil_diameter_mm
    }

    #[getter]
    fn entrance_pupil_z_mm(&self) -> f64 {
        self.paraxial.entrance_pupil_z_mm
    }

    /// Exit pupil diameter (mm) and position from the last vertex before the sensor (mm).
    #[getter]
    fn exit_pupil_diameter_mm(&self) -> f64 {
        self.paraxial.exit_pupil_diameter_mm
    }

    #[getter]
    fn exit_pupil_z_mm(&self) -> f64 {
        self.paraxial.exit_pupil_z_mm
    }

    /// The stop's working semi-diameter and its full one (mm).
    #[getter]
    fn stop_semi_diameter_mm(&self) -> f64 {
        self.paraxial.stop_semi_diameter_mm
    }

    #[getter]
    fn stop_full_semi_diameter_mm(&self) -> f64 {
        self.paraxial.stop_full_semi_diameter_mm
    }

    /// Front vertex to sensor (mm).
    #[getter]
    fn total_track_mm(&self) -> f64 {
        self.paraxial.total_track_mm
    }

    /// Sensor distance from the paraxial focus (mm, + behind it).
    #[getter]
    fn focus_error_mm(&self) -> f64 {
        self.paraxial.focus_error_mm
    }

    /// Petzval sum Σ φ/(n n′) (1/mm).
    #[getter]
    fn petzval_sum(&self) -> f64 {
        self.paraxial.petzval_sum
    }

    /// Every paraxial quantity as a dict (the keys of `flarebench info --json`).
    fn paraxial<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.paraxial;
        let d = PyDict::new(py);
        for (k, v) in [
            ("wavelength_nm", p.wavelength_nm),
            ("efl_mm", p.efl_mm),
            ("bfl_mm", p.bfl_mm),
            ("ffl_mm", p.ffl_mm),
            ("entrance_pupil_z_mm", p.entrance_pupil_z_mm),
            ("entrance_pupil_diameter_mm", p.entrance_pupil_diameter_mm),
            ("exit_pupil_z_mm", p.exit_pupil_z_mm),
            ("exit_pupil_diameter_mm", p.exit_pupil_diameter_mm),
            ("f_number", p.f_number),
            ("open_f_number", p.open_f_number),
            ("stop_semi_diameter_mm", p.stop_semi_diameter_mm),
            ("stop_full_semi_diameter_mm", p.stop_full_semi_diameter_mm),
            ("total_track_mm", p.total_track_mm),
            ("focus_error_mm", p.focus_error_mm),
            ("petzval_sum", p.petzval_sum),
        ] {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Lens({:?}: EFL {} mm, f/{}, {} surfaces, {} ghosts)",
            self.system.name,
            self.paraxial.efl_mm,
            self.paraxial.f_number,
            self.system.surfaces.len(),
            enumerate_ghosts(&self.system).len()
        )
    }
}

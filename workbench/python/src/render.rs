//! `flarebench.render`: one flare frame as `flarebench render … -o x.exr` draws it — the same
//! lens resolution, iris and starburst options (`cli::render`'s `IrisArgs` and
//! `StarburstArgs`), light parsing, plan options and [`Flare::render`] — returned as an
//! H×W×3 float32 NumPy array of linear RGB, the pixels the EXR holds, bit for bit. With
//! `layers=True` the ghosts and the starbursts come apart: each layer is the image
//! `--starburst off` and `--starburst only` give.
//!
//! The GIL is released from the moment the arguments are read until the pixels are copied
//! into NumPy, so other Python threads run (and render) meanwhile; the renderer's own threads
//! are rayon's.

use std::path::PathBuf;
use std::str::FromStr;

use flarebench::cli::render::{IrisArgs, StarburstArgs};
use flarebench::flare::{BackendChoice, Flare, Preset, Scene, StarburstMode, frame_for};
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};
use numpy::PyArray3;
use numpy::ndarray::Array3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::errors::{runtime_error, value_error};
use crate::lens::Lens;
use crate::lights::{LightInput, lights as read_lights};

/// The largest side of a frame, as `--size` allows.
const MAX_SIDE: usize = 16384;
/// The largest `max_downscale`, as `--max-downscale` allows.
const MAX_DOWNSCALE: usize = 64;

/// Why a frame was not made: its input (a `ValueError`) or the renderer (a `RuntimeError`).
enum Failure {
    Input(anyhow::Error),
    Render(anyhow::Error),
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        match f {
            Failure::Input(e) => value_error(&e),
            Failure::Render(e) => runtime_error(&e),
        }
    }
}

/// What a call asked for, read from its Python arguments (no Python object inside: it
/// crosses into the thread-free part).
struct Request {
    system: flarebench_sdk::LensSystem,
    lights: Vec<LightInput>,
    size: (usize, usize),
    plan_quality: Quality,
    reflections: ReflectionOrder,
    max_downscale: Option<usize>,
    iris: IrisArgs,
    starburst: StarburstArgs,
    render: RenderOptions,
    backend: BackendChoice,
    layers: bool,
}

/// The frame, and with `layers` its ghosts and starbursts apart.
struct Frames {
    image: HdrImage,
    ghosts: Option<HdrImage>,
    starbursts: Option<HdrImage>,
}

fn bad(msg: String) -> PyErr {
    PyValueError::new_err(msg)
}

/// `starburst`: True (ghosts and starbursts), False (ghosts only) or `"on"`, `"off"`,
/// `"only"` as `--starburst` takes them.
fn starburst_mode(v: Option<&Bound<'_, PyAny>>) -> PyResult<StarburstMode> {
    let Some(v) = v else {
        return Ok(StarburstMode::On);
    };
    if let Ok(s) = v.cast::<PyString>() {
        return match &*s.to_cow()? {
            "on" => Ok(StarburstMode::On),
            "off" => Ok(StarburstMode::Off),
            "only" => Ok(StarburstMode::Only),
            other => Err(bad(format!(
                "starburst `{other}` is not True, False, \"on\", \"off\" or \"only\""
            ))),
        };
    }
    match v.extract::<bool>() {
        Ok(true) => Ok(StarburstMode::On),
        Ok(false) => Ok(StarburstMode::Off),
        Err(_) => Err(bad(format!(
            "starburst `{v}` is not True, False, \"on\", \"off\" or \"only\""
        ))),
    }
}

/// `aperture`: None or `"circle"` (a circular stop), a blade count, a path to a mask image
/// (`--aperture-mask`), or a dict `{"blades": n, "rotation_deg": …, "roundness": …}` or
/// `{"mask": path}`.
fn iris(v: Option<&Bound<'_, PyAny>>) -> PyResult<IrisArgs> {
    let mut iris = IrisArgs {
        iris_blades: 0,
        iris_rotation_deg: 0.0,
        iris_roundness: 0.0,
        aperture_mask: None,
    };
    let Some(v) = v else {
        return Ok(iris);
    };
    if let Ok(s) = v.cast::<PyString>() {
        let s = s.to_cow()?;
        if s != "circle" {
            iris.aperture_mask = Some(PathBuf::from(&*s));
        }
        return Ok(iris);
    }
    if let Ok(d) = v.cast::<PyDict>() {
        for (k, value) in d.iter() {
            let k: String = k.extract()?;
            let number = |what: &str| -> PyResult<f64> {
                value
                    .extract()
                    .map_err(|_| bad(format!("aperture {what} `{value}` is not a number")))
            };
            match k.as_str() {
                "blades" => {
                    iris.iris_blades = value.extract().map_err(|_| {
                        bad(format!("aperture blades `{value}` is not a whole number"))
                    })?
                }
                "rotation_deg" => iris.iris_rotation_deg = number("rotation_deg")?,
                "roundness" => iris.iris_roundness = number("roundness")?,
                "mask" => iris.aperture_mask = Some(value.extract()?),
                other => {
                    return Err(bad(format!(
                        "aperture key `{other}` is not one of blades, rotation_deg, \
                         roundness, mask"
                    )));
                }
            }
        }
        if iris.aperture_mask.is_some() && iris.iris_blades != 0 {
            return Err(bad(
                "aperture: a mask and iris blades cannot be given together".to_string(),
            ));
        }
        return Ok(iris);
    }
    if let Ok(path) = v.extract::<PathBuf>() {
        iris.aperture_mask = Some(path);
        return Ok(iris);
    }
    iris.iris_blades = v.extract().map_err(|_| {
        bad(format!(
            "aperture `{v}` is not \"circle\", a blade count, a mask path or a dict"
        ))
    })?;
    Ok(iris)
}

fn lens_system(lens: &Bound<'_, PyAny>) -> PyResult<flarebench_sdk::LensSystem> {
    if let Ok(l) = lens.cast::<Lens>() {
        return Ok(l.get().system.clone());
    }
    let spec: PathBuf = lens
        .extract()
        .map_err(|_| bad(format!("lens `{lens}` is not a Lens, a path or a name")))?;
    let spec = spec.to_string_lossy().into_owned();
    let loaded = lens.py().detach(|| Lens::load(&spec, None))?;
    Ok(loaded.system)
}

impl Request {
    /// The frame (and its layers), drawn without touching Python.
    fn draw(self) -> Result<Frames, Failure> {
        let system = &self.system;
        let frame = frame_for(system, self.size);
        let aperture = self.iris.aperture().map_err(Failure::Input)?;
        let (starburst_settings, dust) = self.starburst.load().map_err(Failure::Input)?;
        let lights: Vec<LightSpec> = self
            .lights
            .iter()
            .map(|l| l.resolve(system, &frame))
            .collect::<anyhow::Result<_>>()
            .map_err(Failure::Input)?;
        let mode = self.starburst.starburst;
        let scene = Scene {
            starburst: mode,
            starburst_settings,
            dust: dust.as_ref(),
            ..Scene::new(system, &lights, &aperture, frame)
        };
        // `RenderArgs::plan_options`: the preset's, with `--max-downscale` and
        // `--reflections`.
        let plan = PlanOptions::for_quality(self.plan_quality, None);
        let preset = Preset {
            render: self.render,
            keep_ghosts: self.layers && mode == StarburstMode::On,
            ..Preset::new(PlanOptions {
                max_downscale: self.max_downscale.unwrap_or(plan.max_downscale),
                reflections: self.reflections,
                ..plan
            })
        };
        let mut flare = Flare::open(self.backend).map_err(Failure::Render)?;
        let mut out = flare.render(&scene, &preset).map_err(Failure::Render)?;
        let image = flare.take_image();
        if !self.layers {
            return Ok(Frames {
                image,
                ghosts: None,
                starbursts: None,
            });
        }
        Ok(match mode {
            StarburstMode::Off => Frames {
                ghosts: Some(image.clone()),
                image,
                starbursts: None,
            },
            StarburstMode::Only => Frames {
                starbursts: Some(image.clone()),
                image,
                ghosts: None,
            },
            StarburstMode::On => {
                let ghosts = out.ghosts_image.take();
                // The starbursts alone: the frame of `--starburst only` (no plan, no ghosts;
                // the patterns come from the renderer's cache).
                let only = Scene {
                    starburst: StarburstMode::Only,
                    ..scene
                };
                flare
                    .render(&only, &Preset::new(preset.plan))
                    .map_err(Failure::Render)?;
                Frames {
                    image,
                    ghosts,
                    starbursts: Some(flare.take_image()),
                }
            }
        })
    }
}

/// An image as an H×W×3 float32 array (row-major, linear RGB).
fn array<'py>(py: Python<'py>, img: HdrImage) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (w, h) = (img.width, img.height);
    let flat: Vec<f32> = img.pixels.into_iter().flatten().collect();
    let a = Array3::from_shape_vec((h, w, 3), flat)
        .map_err(|e| PyValueError::new_err(format!("internal error: image shape: {e}")))?;
    Ok(PyArray3::from_owned_array(py, a))
}

/// render(lens, lights, size=(1920, 1080), quality="default", aperture=None, starburst=True,
/// layers=False, *, reflections=2, max_downscale=None, starburst_texels=256, dust=None,
/// f64=False, band_by_band=False, backend="cpu")
///
/// The flare of `lens` (a Lens, a path or a bundled lens's name) for `lights`, as
/// `flarebench render` draws it: an H×W×3 float32 array of linear RGB, equal bit for bit to
/// the EXR `render -o x.exr` writes with the same options. With `layers=True`, a dict of
/// such arrays: `image`, and `ghosts` and/or `starbursts` (the images `--starburst off` and
/// `--starburst only` give). The GIL is released while the frame is drawn.
#[pyfunction]
#[pyo3(signature = (
    lens,
    lights,
    size = (1920, 1080),
    quality = "default",
    aperture = None,
    starburst = None,
    layers = false,
    *,
    reflections = 2,
    max_downscale = None,
    starburst_texels = 256,
    dust = None,
    f64 = false,
    band_by_band = false,
    backend = "cpu",
))]
#[allow(
    clippy::too_many_arguments,
    reason = "the keyword arguments of a Python function, one per CLI option"
)]
pub fn render<'py>(
    py: Python<'py>,
    lens: &Bound<'py, PyAny>,
    lights: &Bound<'py, PyAny>,
    size: (usize, usize),
    quality: &str,
    aperture: Option<&Bound<'py, PyAny>>,
    starburst: Option<&Bound<'py, PyAny>>,
    layers: bool,
    reflections: u32,
    max_downscale: Option<usize>,
    starburst_texels: usize,
    dust: Option<PathBuf>,
    f64: bool,
    band_by_band: bool,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = size;
    if !(1..=MAX_SIDE).contains(&w) || !(1..=MAX_SIDE).contains(&h) {
        return Err(bad(format!(
            "size {w}x{h} must be between 1 and {MAX_SIDE} pixels per side"
        )));
    }
    if let Some(f) = max_downscale
        && !(f.is_power_of_two() && f <= MAX_DOWNSCALE)
    {
        return Err(bad(format!(
            "max_downscale {f} is not a power of two from 1 to {MAX_DOWNSCALE}"
        )));
    }
    let request = Request {
        system: lens_system(lens)?,
        lights: read_lights(lights)?,
        size,
        plan_quality: Quality::from_str(quality).map_err(|e| bad(format!("quality: {e}")))?,
        reflections: ReflectionOrder::from_str(&reflections.to_string())
            .map_err(|e| bad(format!("reflections: {e}")))?,
        max_downscale,
        iris: iris(aperture)?,
        starburst: StarburstArgs {
            starburst: starburst_mode(starburst)?,
            starburst_texels,
            dust,
        },
        render: RenderOptions {
            trace_f64: f64,
            band_by_band,
            ..RenderOptions::default()
        },
        backend: match backend {
            "cpu" => BackendChoice::Cpu,
            "gpu" => BackendChoice::Gpu,
            "auto" => BackendChoice::Auto,
            other => {
                return Err(bad(format!(
                    "backend `{other}` is not one of cpu, gpu, auto"
                )));
            }
        },
        layers,
    };
    let frames = py.detach(move || request.draw())?;
    let image = array(py, frames.image)?;
    if !layers {
        return Ok(image.into_any());
    }
    let d = PyDict::new(py);
    d.set_item("image", image)?;
    if let Some(g) = frames.ghosts {
        d.set_item("ghosts", array(py, g)?)?;
    }
    if let Some(s) = frames.starbursts {
        d.set_item("starbursts", array(py, s)?)?;
    }
    Ok(d.into_any())
}

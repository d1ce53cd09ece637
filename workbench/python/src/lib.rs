//! flarebench's Python module, `flarebench._flarebench` (re-exported by the package
//! `flarebench`, `python/flarebench/__init__.py`): lenses with their paraxial data, and flare
//! frames rendered by the same pipeline as `flarebench render` ([`flarebench::flare::Flare`]),
//! returned as NumPy arrays. docs/python.md is the user's guide.
//!
//! - [`lens`]: `Lens`, a lens file or bundled lens read and analysed.
//! - [`lights`]: Python light descriptions into the CLI's `--light` and `--light-at`.
//! - [`render`]: `render`, one frame (or its layers), the GIL released while it is drawn.
//! - [`dataset`]: `Sampler`, the sampler of `flarebench dataset`: samples drawn from
//!   `(seed, index)` and rendered with their layers and annotation, the GIL released.
//! - [`errors`]: Rust errors into Python exceptions.
//!
//! Each binding is a submodule registered below.

mod dataset;
mod errors;
mod lens;
mod lights;
mod render;

use pyo3::prelude::*;

/// flarebench: physically based lens flare from real lens designs.
#[pymodule]
fn _flarebench(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<lens::Lens>()?;
    m.add_class::<dataset::Sampler>()?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    Ok(())
}

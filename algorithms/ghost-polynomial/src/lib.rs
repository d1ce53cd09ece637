//! Ghosts from sparse polynomials (after Hullin, Hanika & Heidrich 2012, "Polynomial optics",
//! with the terms chosen by orthogonal matching pursuit as in Schrade et al. 2016, "Sparse
//! high-degree polynomials for wide-angle lenses"). Per two-reflection ghost, polynomials in
//! the entrance point, the incidence angle and the wavelength are fitted to rays the exact
//! f64 tracer sends along the ghost's path — sensor position, stop crossing, throughput and
//! the largest relative radius at the rims — and a render evaluates them on the ray-traced
//! renderer's grids instead of tracing, handing the triangles to the host as a mesh.
//!
//! - [`basis`]: the monomials of the four normalised inputs.
//! - [`omp`]: orthogonal matching pursuit (QR by Gram–Schmidt, f64).
//! - [`sample`]: the fit's rays and the inputs' normalisation ([`sample::Domain`]).
//! - [`fit`]: one ghost's polynomials ([`fit::GhostFit`]) and the settings they are made with.
//! - [`accuracy`]: a fit's sensor-position error against the tracer.
//! - [`cache`]: fits and bounds tables kept in memory and on disk.
//! - [`model`]: a prepared lens — its bounds table and fits, with their times.
//! - [`plan`]: what a render draws — ghosts, their rectangles, grids and band colours.
//! - [`draw`]: the render — grids evaluated, triangles clipped, meshed.
//! - [`error`]: what can go wrong.

pub mod accuracy;
pub mod basis;
pub mod cache;
pub mod draw;
pub mod error;
pub mod fit;
pub mod model;
pub mod omp;
pub mod plan;
pub mod sample;

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};

use crate::error::PolyError;
use crate::fit::{DEFAULT_DEGREE, DEFAULT_SAMPLES, DEFAULT_TERMS, FitSettings};
use crate::model::{LensModel, Source, Timing};

/// Highest degree the plugin takes.
pub const MAX_DEGREE: i64 = 9;

/// The settings of a set of parameter values.
pub fn settings(params: &Params<'_>) -> Result<(FitSettings, usize), PluginError> {
    let int = |name: &'static str, min: i64, max: i64| -> Result<usize, PluginError> {
        let v = params.get_int(name)?;
        if !(min..=max).contains(&v) {
            return Err(PolyError::Param {
                name,
                min,
                max,
                value: v,
            }
            .into());
        }
        Ok(v as usize)
    };
    Ok((
        FitSettings {
            degree: int("degree", 1, MAX_DEGREE)?,
            terms: int("terms", 1, 400)?,
            samples: int("samples", 256, 1 << 18)?,
            seed: int("seed", 0, 1 << 31)? as u64,
        },
        int("bands", 0, 31)?,
    ))
}

/// The plugin: the prepared lens, and how its table and last fits were found.
#[derive(Debug, Default)]
pub struct GhostPolynomial {
    pub model: Option<LensModel>,
    /// The fits of the last render (or of `prepare`, made with the default settings).
    pub fit_timing: Option<Timing>,
}

fn describe(t: Timing) -> String {
    match t.source {
        Source::Memory => format!("from memory in {:.1} ms", t.ms),
        Source::Disk => format!("read from the disk cache in {:.1} ms", t.ms),
        Source::Made => format!("made in {:.1} ms", t.ms),
    }
}

impl GhostPolynomial {
    /// The model's fits with `settings`, reported on stderr when not already in memory (the
    /// ABI has no field for a plugin's own timings).
    fn fits(&mut self, settings: &FitSettings) -> Result<std::sync::Arc<cache::FitMap>, PolyError> {
        let model = self.model.as_ref().ok_or(PolyError::NoLens)?;
        let (fits, timing) = model.fits(settings);
        if timing.source != Source::Memory {
            eprintln!(
                "ghost-polynomial: {} ghost fits (degree {}, {} terms, {} samples, seed {}) {}",
                fits.len(),
                settings.degree,
                settings.terms,
                settings.samples,
                settings.seed,
                describe(timing)
            );
        }
        self.fit_timing = Some(timing);
        Ok(fits)
    }
}

impl FlarePlugin for GhostPolynomial {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "ghost-polynomial",
            version: env!("CARGO_PKG_VERSION"),
            description: "ghosts from sparse polynomials fitted to the exact tracer per ghost over entrance point, angle and wavelength (Hullin et al. 2012; OMP terms, Schrade et al. 2016), evaluated on the renderer's grids",
            kind: PluginKind::Ghosts,
            params: vec![
                ParamSpec::int(
                    "degree",
                    "highest total degree of a term",
                    1,
                    MAX_DEGREE,
                    DEFAULT_DEGREE as i64,
                ),
                ParamSpec::int(
                    "terms",
                    "most terms per fitted output (sensor x, y; stop u, v; throughput; rim radius)",
                    1,
                    400,
                    DEFAULT_TERMS as i64,
                ),
                ParamSpec::int(
                    "samples",
                    "rays traced per ghost for its fit",
                    256,
                    1 << 18,
                    DEFAULT_SAMPLES as i64,
                ),
                ParamSpec::int("seed", "seed of the fit's rays", 0, 1 << 31, 1),
                ParamSpec::int(
                    "bands",
                    "wavelength bands drawn (0: the renderer's default 7)",
                    0,
                    31,
                    0,
                ),
            ],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(GhostPolynomial::default())
    }

    /// Finds the bounds table and the default settings' fits (in memory, on disk, or made),
    /// so that a host that times `prepare` apart from `render` reports the fit's time apart.
    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        let model = LensModel::new(lens, cache::default_dir().as_deref())?;
        if model.table_timing.source != Source::Memory {
            eprintln!(
                "ghost-polynomial: bounds table of {} ghosts at {} angles to {:.1}° {}",
                model.table.ghosts.len(),
                model.table.angles_deg.len(),
                model.table.angles_deg.last().copied().unwrap_or(0.0),
                describe(model.table_timing)
            );
        }
        self.model = Some(model);
        self.fits(&FitSettings::default())?;
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let (settings, bands) = settings(params)?;
        let fits = self.fits(&settings)?;
        let model = self.model.as_ref().ok_or(PolyError::NoLens)?;
        let (jobs, beyond) = plan::plan_scene(&model.table, &fits, scene, bands)?;
        if beyond > 0 {
            eprintln!(
                "warning: ghost-polynomial: {beyond} ghosts not drawn: their light lies beyond the fitted angles (0 to {:.1}°)",
                model.table.angles_deg.last().copied().unwrap_or(0.0)
            );
        }
        let (mesh, stats) = draw::mesh_jobs(&model.system, &fits, scene, &jobs)?;
        out.mesh = mesh;
        out.items_drawn = stats.ghosts_drawn;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(GhostPolynomial);

//! `flarebench sweep`: error against run time, over lenses and lights (the cases) and over
//! algorithms, quality presets and the planner's thresholds (the points). Every cell (a case
//! and a point) is timed and compared with the reference renderer, as a whole and ghost by
//! ghost; the results are written as CSV and JSON, plotted with their Pareto front, tiled into
//! a contact sheet and tied together by an `index.html` (docs/accuracy.md § Sweeps).
//!
//! Cells and references are kept in the output directory under keys of everything they
//! depend on, so an interrupted sweep resumes where it stopped and a changed sweep redoes
//! only what changed.

pub mod measure;
pub mod moments;
pub mod pareto;
pub mod plot;
pub mod points;
pub mod report;
pub mod sheet;
pub mod store;

use serde::{Deserialize, Serialize};

use moments::Moments;

/// The aperture as a case names it.
pub fn aperture_text(a: &flarebench_sdk::aperture::Aperture) -> String {
    use flarebench_sdk::aperture::Aperture;
    match a {
        Aperture::Circular => "circle".to_string(),
        Aperture::Iris {
            blades,
            rotation_rad,
            roundness,
        } => format!(
            "iris {blades} blades {:.1}° roundness {roundness}",
            rotation_rad.to_degrees()
        ),
        Aperture::Mask(m) => format!("mask {}×{}", m.width(), m.height()),
    }
}

/// A lens and a light: one plot, one contact sheet.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CaseInfo {
    /// The lens's name (as its file names it).
    pub lens: String,
    /// As given on the command line (a bundled name or a path).
    pub lens_arg: String,
    pub theta_deg: f64,
    pub phi_deg: f64,
    pub width: usize,
    pub height: usize,
    /// The aperture, as text.
    pub aperture: String,
}

impl CaseInfo {
    /// A name for the case's files: lens and light, letters, digits and `-` only.
    pub fn slug(&self) -> String {
        crate::output::file_stem(&format!(
            "{}-{}-{}",
            self.lens, self.theta_deg, self.phi_deg
        ))
    }

    pub fn title(&self) -> String {
        format!(
            "{} · light {}°, {}° · {}×{} · {}",
            self.lens, self.theta_deg, self.phi_deg, self.width, self.height, self.aperture
        )
    }
}

/// The reference of a case, ghost by ghost.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceRecord {
    /// Everything the reference depends on ([`ghost_raytrace::reference::reference_key`]).
    pub key: String,
    /// How long rendering it took (milliseconds), when it was rendered.
    pub render_ms: f64,
    /// Each ghost's moments, by path (`8-0`), in the reference's plan order.
    pub ghosts: Vec<(String, Moments)>,
    /// The whole image's moments.
    pub total: Moments,
}

/// One ghost of a cell against the same ghost of the reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GhostError {
    pub ghost: String,
    /// The ghost's share of the reference's energy.
    pub reference_share: f64,
    /// False when the point's plan left the ghost out (its energy error is then −1).
    pub drawn: bool,
    /// (E − E_ref) / E_ref.
    pub energy_error: f64,
    /// Distance between the two centroids (pixels).
    pub centroid_shift_px: f64,
    /// RMS radius over the reference's (1: the same spread).
    pub size_ratio: f64,
}

/// One cell's results.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CellResult {
    /// Everything the cell depends on; its cache file is named by a hash of it.
    pub key: String,
    pub series: String,
    pub label: String,
    pub algo: String,
    /// Every parameter's value, defaults included, as `key=value` text.
    pub params: String,
    /// `cpu`, or the GPU adapter.
    pub backend: String,
    /// Each timed run's frame time (milliseconds): plan and render, or the plugin's render.
    pub times_ms: Vec<f64>,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    /// Medians of the plan and of the render (the built-in renderer only).
    pub plan_ms: Option<f64>,
    pub render_ms: Option<f64>,
    pub relative_rmse: f64,
    pub relative_l1: f64,
    pub energy_error: f64,
    /// Ghosts drawn and planned (the built-in renderer), or the plugin's items drawn.
    pub ghosts_drawn: usize,
    pub ghosts_total: Option<usize>,
    /// The share of the frame's ghost energy the plan left out: as the plan estimates it
    /// ([`ghost_raytrace::plan::LightPlan::culled_share`]: the dim ghosts' share of the
    /// energy of the ghosts that reach the frame), and as the reference measures it (its
    /// energy in the ghosts not drawn, over its whole energy).
    pub dropped_energy_estimated: Option<f64>,
    pub dropped_energy_measured: Option<f64>,
    /// Ghost by ghost (the built-in renderer), the reference's ghost order.
    pub ghosts: Vec<GhostError>,
    /// Why the cell failed, if it did (the sweep goes on).
    pub failure: Option<String>,
}

/// A case with its reference and its cells, as the report writers take them.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CaseResult {
    pub case: CaseInfo,
    pub reference: ReferenceRecord,
    /// Exposure (stops) every image of the case is shown at: the reference's.
    pub exposure_ev: f32,
    pub cells: Vec<CellResult>,
    /// Each cell's thumbnail file, relative to the sweep directory (as `cells`).
    pub thumbnails: Vec<Option<String>>,
    pub reference_thumbnail: Option<String>,
}

impl CaseResult {
    /// Indices of the cells on the case's Pareto front (median time against relative RMSE),
    /// fastest first.
    pub fn pareto(&self) -> Vec<usize> {
        let pts: Vec<(f64, f64)> = self
            .cells
            .iter()
            .map(|c| {
                if c.failure.is_some() {
                    (f64::NAN, f64::NAN)
                } else {
                    (c.median_ms, c.relative_rmse)
                }
            })
            .collect();
        pareto::front(&pts)
    }
}

//! How well a fit predicts the exact tracer: its sensor-position error over the ghost's
//! domain, measured on fresh rays (another seed than the fit's), counting only the rays that
//! carry light into the image — through every rim and inside the stop's working radius (a
//! circular aperture).

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::table::BoundsTable;

use crate::fit::GhostFit;
use crate::sample::{Domain, MAX_REL, SENSOR_X, SENSOR_Y, STOP_U, STOP_V, trace_samples};

/// A fit's sensor-position error (µm) over the rays checked.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PositionError {
    /// Rays checked (those that reach the sensor with light).
    pub rays: usize,
    pub rms_um: f64,
    /// The 99th percentile and the largest.
    pub p99_um: f64,
    pub max_um: f64,
}

/// The error of `fit` (ghost `g` of `table`) on `count` fresh rays drawn from `seed`.
pub fn position_error(
    system: &LensSystem,
    table: &BoundsTable,
    g: usize,
    fit: &GhostFit,
    count: usize,
    seed: u64,
) -> PositionError {
    let domain: Domain = fit.domain;
    let rays = trace_samples(system, fit.path, table, g, &domain, count, seed);
    let mut errs: Vec<f64> = rays
        .iter()
        .filter(|s| s.outputs[MAX_REL] <= 1.0 && s.outputs[STOP_U].hypot(s.outputs[STOP_V]) <= 1.0)
        .map(|s| {
            let p = crate::basis::Powers::of(s.inputs);
            let dx = fit.outputs[SENSOR_X].eval(&p) - s.outputs[SENSOR_X];
            let dy = fit.outputs[SENSOR_Y].eval(&p) - s.outputs[SENSOR_Y];
            1e3 * dx.hypot(dy)
        })
        .collect();
    if errs.is_empty() {
        return PositionError::default();
    }
    errs.sort_by(f64::total_cmp);
    let n = errs.len();
    PositionError {
        rays: n,
        rms_um: (errs.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt(),
        p99_um: errs[((n - 1) as f64 * 0.99).round() as usize],
        max_um: errs[n - 1],
    }
}

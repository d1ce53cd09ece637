//! One ghost's polynomials: per output ([`crate::sample`]), a sparse combination of the
//! monomials of [`crate::basis`] chosen by orthogonal matching pursuit ([`crate::omp`]) on rays
//! traced exactly over the ghost's domain — entrance position, incidence angle and wavelength.
//! One fit serves every light direction and wavelength in the domain.

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::table::BoundsTable;
use serde::{Deserialize, Serialize};

use crate::basis::{Monomial, Powers, monomials};
use crate::omp::pursue;
use crate::sample::{
    Domain, MAX_REL, OUTPUTS, SENSOR_X, SENSOR_Y, STOP_U, STOP_V, Sample, THROUGHPUT,
    trace_samples, x_odd,
};

/// What a fit is made with: the plugin's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FitSettings {
    /// Highest total degree of a term.
    pub degree: usize,
    /// Most terms per output.
    pub terms: usize,
    /// Rays traced per ghost.
    pub samples: usize,
    pub seed: u64,
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            degree: DEFAULT_DEGREE,
            terms: DEFAULT_TERMS,
            samples: DEFAULT_SAMPLES,
            seed: 1,
        }
    }
}

/// The parameters' defaults (chosen by measurement, docs/plugins.md §8).
pub const DEFAULT_DEGREE: usize = 7;
pub const DEFAULT_TERMS: usize = 60;
pub const DEFAULT_SAMPLES: usize = 4096;

/// The pursuit stops when an output's residual RMS is this small: 0.1 nm for positions
/// (mm), 1e-7 of the stop radius, of the throughput and of the relative radius.
const TOLERANCE: f64 = 1e-7;

/// One output's polynomial and its RMS residual over the fit's samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputPoly {
    pub terms: Vec<(Monomial, f64)>,
    pub rms: f64,
}

impl OutputPoly {
    #[inline]
    pub fn eval(&self, p: &Powers) -> f64 {
        self.terms.iter().map(|(m, c)| c * m.eval(p)).sum()
    }
}

/// A ghost's fitted polynomials.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GhostFit {
    pub path: GhostPath,
    pub domain: Domain,
    /// Indexed as [`crate::sample`]'s outputs.
    pub outputs: Vec<OutputPoly>,
    /// Rays the fit was made from.
    pub samples: usize,
}

/// The sensor position and throughput are fitted on the rays that pass within this margin of
/// every rim (`max_rel`) and of the stop's working radius: the rays drawn, and a band around
/// them for the triangles the clip cuts. The rays far outside (which still complete, through
/// the surfaces' mathematical extension beyond their rims) would otherwise pull the fit away
/// from where it is drawn. The clip functions (stop crossing, `max_rel`) are fitted on every
/// ray, so that they cross their thresholds where the tracer's do.
pub const NEAR: f64 = 1.2;

/// Fewest completed rays a fit is made from (below, the ghost has next to no light).
pub const MIN_SAMPLES: usize = 64;

impl GhostFit {
    /// Fits ghost `g` of `table` (its path `path`) of `system`; `None` when it has no light
    /// at any tabulated angle or fewer than [`MIN_SAMPLES`] of its rays complete.
    pub fn fit(
        system: &LensSystem,
        table: &BoundsTable,
        g: usize,
        settings: &FitSettings,
    ) -> Option<GhostFit> {
        let path = table.ghosts[g];
        let domain = Domain::of(table, g)?;
        let samples = trace_samples(
            system,
            path,
            table,
            g,
            &domain,
            settings.samples,
            settings.seed,
        );
        Self::from_samples(path, domain, &samples, settings)
    }

    /// The fit of `samples` (of `path` over `domain`).
    pub fn from_samples(
        path: GhostPath,
        domain: Domain,
        samples: &[Sample],
        settings: &FitSettings,
    ) -> Option<GhostFit> {
        if samples.len() < MIN_SAMPLES {
            return None;
        }
        let basis = monomials(settings.degree);
        let powers: Vec<Powers> = samples.iter().map(|s| Powers::of(s.inputs)).collect();
        // The candidate columns of each parity in x.
        let columns = |odd: bool| -> (Vec<Monomial>, Vec<Vec<f64>>) {
            let ms: Vec<Monomial> = basis.iter().copied().filter(|m| m.x_odd() == odd).collect();
            let cols = ms
                .iter()
                .map(|m| powers.iter().map(|p| m.eval(p)).collect())
                .collect();
            (ms, cols)
        };
        let (odd_ms, odd_cols) = columns(true);
        let (even_ms, even_cols) = columns(false);
        let near: Vec<bool> = samples
            .iter()
            .map(|s| {
                s.outputs[MAX_REL] <= NEAR && s.outputs[STOP_U].hypot(s.outputs[STOP_V]) <= NEAR
            })
            .collect();
        let use_near = near.iter().filter(|&&n| n).count() >= MIN_SAMPLES;
        let keep = |cols: &[Vec<f64>]| -> Vec<Vec<f64>> {
            cols.iter()
                .map(|c| {
                    c.iter()
                        .zip(&near)
                        .filter(|(_, n)| **n)
                        .map(|(v, _)| *v)
                        .collect()
                })
                .collect()
        };
        let (odd_near, even_near) = if use_near {
            (keep(&odd_cols), keep(&even_cols))
        } else {
            (odd_cols.clone(), even_cols.clone())
        };
        let outputs = (0..OUTPUTS)
            .map(|o| {
                let drawn = matches!(o, SENSOR_X | SENSOR_Y | THROUGHPUT);
                let (ms, cols) = match (x_odd(o), drawn) {
                    (true, false) => (&odd_ms, &odd_cols),
                    (false, false) => (&even_ms, &even_cols),
                    (true, true) => (&odd_ms, &odd_near),
                    (false, true) => (&even_ms, &even_near),
                };
                let y: Vec<f64> = samples
                    .iter()
                    .zip(&near)
                    .filter(|(_, n)| !drawn || !use_near || **n)
                    .map(|(s, _)| s.outputs[o])
                    .collect();
                let p = pursue(cols, &y, settings.terms, TOLERANCE);
                OutputPoly {
                    terms: p
                        .chosen
                        .iter()
                        .map(|&j| ms[j])
                        .zip(p.coefficients)
                        .collect(),
                    rms: p.rms,
                }
            })
            .collect();
        Some(GhostFit {
            path,
            domain,
            outputs,
            samples: samples.len(),
        })
    }

    /// Every output at entrance point `(x, y)` (mm, meridional frame), `theta_deg` and
    /// `lambda_nm`; the throughput is kept at or above 0.
    #[inline]
    pub fn eval(&self, x: f64, y: f64, theta_deg: f64, lambda_nm: f64) -> [f64; OUTPUTS] {
        let p = Powers::of(self.domain.inputs(x, y, theta_deg, lambda_nm));
        let mut out = [0.0; OUTPUTS];
        for (o, poly) in out.iter_mut().zip(&self.outputs) {
            *o = poly.eval(&p);
        }
        out[THROUGHPUT] = out[THROUGHPUT].max(0.0);
        out
    }

    /// True when the fit is well formed: an output per kind, finite coefficients, terms
    /// within the basis (a cache file is checked with this before use).
    pub fn is_well_formed(&self, settings: &FitSettings) -> bool {
        self.outputs.len() == OUTPUTS
            && self.outputs.iter().all(|o| {
                o.terms.len() <= settings.terms
                    && o.terms
                        .iter()
                        .all(|(m, c)| c.is_finite() && m.degree() <= settings.degree)
            })
            && [
                self.domain.x_scale,
                self.domain.y_scale,
                self.domain.theta_max_deg,
            ]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
            && self.domain.y_centre.is_finite()
    }
}

//! Errors of planning and rendering ghosts.

use flarebench_sdk::color::{LightSpectrumError, SpectralSamplingError};
use flarebench_sdk::paraxial::ParaxialError;

/// Why a scene could not be planned or rendered.
#[derive(Debug, thiserror::Error)]
pub enum GhostRenderError {
    #[error("spectral sampling: {0}")]
    Sampling(#[from] SpectralSamplingError),
    #[error("paraxial analysis: {0}")]
    Paraxial(#[from] ParaxialError),
    #[error("the light at {theta_deg}° is outside the precomputed table ({min_deg}–{max_deg}°)")]
    OutsideTable {
        theta_deg: f64,
        min_deg: f64,
        max_deg: f64,
    },
    #[error("the output buffer holds {len} pixels, not the frame's {width}×{height}")]
    OutputSize {
        width: usize,
        height: usize,
        len: usize,
    },
}

/// Why a `--light` specification was refused.
#[derive(Debug, thiserror::Error)]
pub enum LightSpecError {
    #[error("a light takes THETA,PHI[,INTENSITY[,KELVIN or R:G:B]] (degrees), got `{0}`")]
    Shape(String),
    #[error("light `{spec}`: {what} `{value}` is not a finite number")]
    NotANumber {
        spec: String,
        what: &'static str,
        value: String,
    },
    #[error("light `{0}`: THETA must be in [0, 90) degrees")]
    Theta(String),
    #[error("light `{0}`: INTENSITY must be positive")]
    Intensity(String),
    #[error("light `{spec}`: {source}")]
    Spectrum {
        spec: String,
        source: LightSpectrumError,
    },
}

//! What can go wrong in a polynomial render.

use flarebench_sdk::color::SpectralSamplingError;
use flarebench_sdk::paraxial::ParaxialError;

/// Why a render could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PolyError {
    /// A parameter out of what a fit can be made with.
    #[error("{name} must be in {min}..={max}, not {value}")]
    Param {
        name: &'static str,
        min: i64,
        max: i64,
        value: i64,
    },
    /// `render` before `prepare`.
    #[error("no lens prepared")]
    NoLens,
    /// The lens has no paraxial focal length or f-number.
    #[error(transparent)]
    Paraxial(#[from] ParaxialError),
    /// A light's spectrum could not be sampled.
    #[error(transparent)]
    Sampling(#[from] SpectralSamplingError),
}

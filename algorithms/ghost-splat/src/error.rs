//! What can go wrong in a splat render.

use flarebench_sdk::color::SpectralSamplingError;

/// Why a render could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SplatError {
    /// A kernel half-width that is neither 0 (the box) nor in `[1, 8]` pixels.
    #[error("kernel_px must be 0 (box) or a tent half-width in 1..=8 pixels, not {0}")]
    KernelWidth(f64),
    /// No rays, or no wavelength bands.
    #[error("{what} must be at least 1")]
    Zero { what: &'static str },
    /// More wavelength bands than a render takes.
    #[error("bands must be at most 64, not {0}")]
    TooManyBands(usize),
    /// A negative seed.
    #[error("seed must not be negative, not {0}")]
    Seed(i64),
    /// The output buffer does not hold the scene's frame.
    #[error("the output has {got} pixels, the frame {want}")]
    OutputSize { got: usize, want: usize },
    /// A light's spectrum could not be sampled.
    #[error(transparent)]
    Sampling(#[from] SpectralSamplingError),
}

//! The diffraction starburst: the Fraunhofer pattern of the aperture stop, as a bright light's
//! image on the sensor (Hullin et al. 2011 §3.1). Physics and scaling are written
//! out in `docs/starburst.md`; in short:
//!
//! 1. [`PowerSpectrum`]: the aperture (circle, iris or mask, times an optional dust/scratch
//!    overlay) rasterised with `pupil_texels` texels across its diameter, zero-padded to
//!    `P = pupil_texels × padding` per side, Fourier transformed (rustfft), `|F|²`, centred
//!    and normalised to unit sum. By Parseval, `Σ|F|² = P² Σ|a|²` before normalising.
//! 2. [`StarburstPattern`]: the spectral sum `Σ_k w_k (λs/λ_k)² I(u·λs/λ_k)` over the light's
//!    CIE-weighted wavelengths ([`crate::color::SpectralSampling`]): one transform at the
//!    shortest wavelength λs, every other wavelength the same pattern magnified by λ/λs, its
//!    density scaled so each wavelength keeps its energy. Linear sRGB, luminance sum 1 (less
//!    what falls outside the grid).
//! 3. Scale: a bin of the transform is `λs·N/padding` on the sensor (N the working f-number),
//!    so a circular stop's first dark ring lies at `1.22·λ·N`; the pattern reaches
//!    `±pupil_texels·λs·N/2` from its centre.
//! 4. [`add_starburst`]: the pattern, times the light's flux through the lens (its direct
//!    image's energy), added into an [`crate::image::HdrImage`] at the chief ray's landing
//!    point ([`chief_ray_landing`]) by exact area resampling — the image gains exactly the
//!    pattern's energy that lies in the frame.
//!
//! [`StarburstCache`] keeps transforms per aperture and patterns per aperture and light
//! spectrum, so several lights share the work.

mod cache;
mod chief_ray;
mod lights;
mod pattern;
mod power;
mod splat;

pub use cache::StarburstCache;
pub use chief_ray::{ChiefRayError, chief_ray_landing};
pub use lights::{
    FLUX_LAMBDA_NM, StarburstLens, StarburstLight, StarburstOutcome, StarburstSource,
    StarburstSplat, StarburstTarget,
};
pub use pattern::{StarburstPattern, TAPER_START, edge_window};
pub use power::PowerSpectrum;
pub use splat::{SplatGeometry, SplatStats, add_starburst, splat_stats};

use crate::aperture::ApertureError;
use crate::color::SpectralSamplingError;

/// How finely a starburst is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StarburstSettings {
    /// Texels across the aperture's diameter (the unit square [-1, 1]² of stop coordinates).
    /// It sets the pattern's reach: `±pupil_texels·λs·N/2` on the sensor.
    pub pupil_texels: usize,
    /// Zero padding factor (≥ 2; 4 by default resolves the rings, docs/starburst.md): the
    /// transform is `pupil_texels × padding` per side and a bin is `λs·N/padding` on the
    /// sensor.
    pub padding: usize,
    /// Wavelengths summed (stratified over 380–780 nm, CIE 1931 weighted).
    pub wavelengths: usize,
}

impl Default for StarburstSettings {
    /// 256 texels, padding 4 (a 1024² transform), 64 wavelengths.
    fn default() -> Self {
        StarburstSettings {
            pupil_texels: 256,
            padding: 4,
            wavelengths: 64,
        }
    }
}

/// Largest transform side accepted (a 8192² complex f32 transform takes 512 MiB).
pub const MAX_FFT_SIZE: usize = 8192;

impl StarburstSettings {
    /// The transform's side, `pupil_texels × padding`.
    pub fn fft_size(&self) -> usize {
        self.pupil_texels.saturating_mul(self.padding)
    }

    /// Checks the settings: at least 16 texels across, padding at least 2, an even transform
    /// of at most [`MAX_FFT_SIZE`], at least one wavelength.
    pub fn validate(&self) -> Result<(), StarburstError> {
        if self.pupil_texels < 16 {
            return Err(StarburstError::PupilTexels(self.pupil_texels));
        }
        if self.padding < 2 {
            return Err(StarburstError::Padding(self.padding));
        }
        let size = self.fft_size();
        if size > MAX_FFT_SIZE || !size.is_multiple_of(2) {
            return Err(StarburstError::FftSize(size));
        }
        if self.wavelengths == 0 {
            return Err(StarburstError::Wavelengths);
        }
        Ok(())
    }
}

/// Why a starburst could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StarburstError {
    #[error("aperture: {0}")]
    Aperture(#[from] ApertureError),
    #[error("spectral sampling: {0}")]
    Sampling(#[from] SpectralSamplingError),
    #[error("a starburst needs at least 16 texels across the pupil, got {0}")]
    PupilTexels(usize),
    #[error("the zero padding factor must be at least 2, got {0}")]
    Padding(usize),
    #[error(
        "the transform size (texels × padding) must be even and at most {MAX_FFT_SIZE}, got {0}"
    )]
    FftSize(usize),
    #[error("a starburst needs at least one wavelength")]
    Wavelengths,
    #[error("the aperture is closed: no light passes it")]
    Closed,
    #[error("the f-number must be finite and positive, got {0}")]
    FNumber(f64),
}

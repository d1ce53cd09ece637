//! [`StarburstCache`]: power spectra kept per aperture (shape, overlay, settings) and spectral
//! patterns per aperture and light spectrum, so lights that share them share the work. A
//! scene has a handful of each, so the keys are compared in a short list.

use std::sync::Arc;

use crate::aperture::{Aperture, ApertureMask};
use crate::color::{LightSpectrum, SpectralSampling};

use super::{PowerSpectrum, StarburstError, StarburstPattern, StarburstSettings};

#[derive(Clone, Debug, PartialEq)]
struct ApertureKey {
    aperture: Aperture,
    overlay: Option<ApertureMask>,
    pupil_texels: usize,
    padding: usize,
}

/// Computed starbursts, reused while the aperture and settings stay the same.
#[derive(Debug, Default)]
pub struct StarburstCache {
    spectra: Vec<(ApertureKey, Arc<PowerSpectrum>)>,
    patterns: Vec<(ApertureKey, usize, LightSpectrum, Arc<StarburstPattern>)>,
    /// Transforms computed so far (a cache miss each).
    transforms: usize,
}

impl StarburstCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The power spectrum of `aperture` × `overlay`, computed on first use.
    pub fn spectrum(
        &mut self,
        aperture: &Aperture,
        overlay: Option<&ApertureMask>,
        settings: &StarburstSettings,
    ) -> Result<Arc<PowerSpectrum>, StarburstError> {
        let key = key(aperture, overlay, settings);
        if let Some((_, s)) = self.spectra.iter().find(|(k, _)| *k == key) {
            return Ok(Arc::clone(s));
        }
        let s = Arc::new(PowerSpectrum::compute(aperture, overlay, settings)?);
        self.transforms += 1;
        self.spectra.push((key, Arc::clone(&s)));
        Ok(s)
    }

    /// The spectral pattern for a light of spectrum `light`, computed on first use.
    pub fn pattern(
        &mut self,
        aperture: &Aperture,
        overlay: Option<&ApertureMask>,
        settings: &StarburstSettings,
        light: LightSpectrum,
    ) -> Result<Arc<StarburstPattern>, StarburstError> {
        let key = key(aperture, overlay, settings);
        let found = self
            .patterns
            .iter()
            .find(|(k, n, l, _)| *k == key && *n == settings.wavelengths && *l == light);
        if let Some((_, _, _, p)) = found {
            return Ok(Arc::clone(p));
        }
        let spectrum = self.spectrum(aperture, overlay, settings)?;
        let sampling = SpectralSampling::new(settings.wavelengths, light)?;
        let p = Arc::new(StarburstPattern::new(&spectrum, &sampling));
        self.patterns
            .push((key, settings.wavelengths, light, Arc::clone(&p)));
        Ok(p)
    }

    /// How many Fourier transforms this cache has computed.
    pub fn transforms(&self) -> usize {
        self.transforms
    }
}

fn key(
    aperture: &Aperture,
    overlay: Option<&ApertureMask>,
    settings: &StarburstSettings,
) -> ApertureKey {
    ApertureKey {
        aperture: aperture.clone(),
        overlay: overlay.cloned(),
        pupil_texels: settings.pupil_texels,
        padding: settings.padding,
    }
}

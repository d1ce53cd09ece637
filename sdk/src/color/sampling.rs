//! [`SpectralSampling`]: which wavelengths a spectral render traces and the linear-sRGB weight
//! of each, so that `Σ_k w_k · r(λ_k)` is the colour of the light after a wavelength-dependent
//! response `r` (the lens's ghost transmission, for example).
//!
//! **Wavelengths.** `K` stratified samples over 380–780 nm: the centres of `K` equal bins,
//! `λ_k = 380 + (k + ½) · 400 / K` nm.
//!
//! **Weights.** With `s` the light's relative spectrum and `x̄ ȳ z̄` the CIE 1931 functions,
//! `w_k = M · [x̄, ȳ, z̄](λ_k) · s(λ_k) / Σ_j ȳ(λ_j) s(λ_j)`, `M` the XYZ → linear sRGB matrix.
//!
//! **Normalisation.** The light's own colour (`r ≡ 1`) has luminance Y = 1 *exactly*, for
//! every `K` (the denominator is the same discrete sum as the numerator's ȳ part): the
//! intensity of a light is its luminance, the spectrum only sets its colour. As `K` grows,
//! `Σ_k w_k` converges to the light's continuous colour ([`LightSpectrum::linear_srgb`]). There
//! is no chromatic adaptation: white in sRGB is D65, which comes out as (1, 1, 1); an
//! equal-energy light ([`LightSpectrum::Flat`]) is (1.205, 0.948, 0.909), a 6500 K black body
//! (1.043, 0.984, 1.035). Weights may be negative for saturated spectral colours outside the
//! sRGB gamut (the red weight between about 440 and 545 nm), as in any CMF-based render.
//!
//! **How many wavelengths.** Colour error of `Σ_k w_k` against `K → ∞`, relative to the largest
//! channel, measured over blackbody, D65, flat and RGB lights (`many_wavelengths_converge_…`):
//! K = 4 up to 39%, K = 16 up to 3.8%, K = 64 up to 0.2%, K = 1024 below 1e-5.

use super::cmf::cie1931_xyz_bar;
use super::light::{LightSpectrum, LightSpectrumError};
use super::srgb::xyz_to_linear_srgb;

/// Shortest wavelength sampled (nm).
pub const SAMPLING_MIN_NM: f64 = 380.0;
/// Longest wavelength sampled (nm).
pub const SAMPLING_MAX_NM: f64 = 780.0;

/// Wavelengths and their linear-sRGB weights for one light (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralSampling {
    light: LightSpectrum,
    wavelengths_nm: Vec<f64>,
    weights: Vec<[f32; 3]>,
}

/// Why a [`SpectralSampling`] cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpectralSamplingError {
    /// Zero wavelengths were asked for.
    #[error("a spectral sampling needs at least one wavelength")]
    NoWavelengths,
    /// The light's parameters are invalid.
    #[error(transparent)]
    Light(#[from] LightSpectrumError),
    /// The light has no luminance at the sampled wavelengths.
    #[error("the light has no visible power at the {0} sampled wavelengths")]
    NoVisiblePower(usize),
}

impl SpectralSampling {
    /// `count` stratified wavelengths over 380–780 nm and their weights for `light`.
    pub fn new(count: usize, light: LightSpectrum) -> Result<Self, SpectralSamplingError> {
        if count == 0 {
            return Err(SpectralSamplingError::NoWavelengths);
        }
        light.validate()?;
        let width = (SAMPLING_MAX_NM - SAMPLING_MIN_NM) / count as f64;
        let wavelengths_nm: Vec<f64> = (0..count)
            .map(|k| SAMPLING_MIN_NM + (k as f64 + 0.5) * width)
            .collect();
        let xyz: Vec<[f64; 3]> = wavelengths_nm
            .iter()
            .map(|&l| cie1931_xyz_bar(l).map(|c| c * light.relative(l)))
            .collect();
        let y_sum: f64 = xyz.iter().map(|v| v[1]).sum();
        if !(y_sum > 0.0 && y_sum.is_finite()) {
            return Err(SpectralSamplingError::NoVisiblePower(count));
        }
        let weights = xyz
            .iter()
            .map(|v| xyz_to_linear_srgb(v.map(|c| c / y_sum)).map(|c| c as f32))
            .collect();
        Ok(SpectralSampling {
            light,
            wavelengths_nm,
            weights,
        })
    }

    /// The light this sampling was built for.
    pub fn light(&self) -> LightSpectrum {
        self.light
    }

    /// Number of wavelengths `K` (at least 1).
    pub fn len(&self) -> usize {
        self.wavelengths_nm.len()
    }

    /// Always false: a sampling has at least one wavelength.
    pub fn is_empty(&self) -> bool {
        self.wavelengths_nm.is_empty()
    }

    /// The wavelengths `λ_k` (nm), increasing.
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// The linear-sRGB weights `w_k`, one per wavelength.
    pub fn weights(&self) -> &[[f32; 3]] {
        &self.weights
    }

    /// Width of each wavelength bin, `400 / K` nm.
    pub fn bin_width_nm(&self) -> f64 {
        (SAMPLING_MAX_NM - SAMPLING_MIN_NM) / self.len() as f64
    }

    /// `Σ_k w_k · response[k]`: the linear-sRGB colour of the light after a response given at
    /// each sampled wavelength.
    ///
    /// # Panics
    /// If `response.len() != self.len()` (a programming error).
    pub fn combine(&self, response: &[f32]) -> [f32; 3] {
        assert_eq!(
            response.len(),
            self.len(),
            "one response value per sampled wavelength"
        );
        let mut rgb = [0.0_f32; 3];
        for (w, &r) in self.weights.iter().zip(response) {
            for c in 0..3 {
                rgb[c] += w[c] * r;
            }
        }
        rgb
    }

    /// `Σ_k w_k · response(λ_k)` in f64, for a response given as a function of wavelength (nm).
    pub fn rgb_of(&self, response: impl Fn(f64) -> f64) -> [f64; 3] {
        let mut rgb = [0.0_f64; 3];
        for (w, &l) in self.weights.iter().zip(&self.wavelengths_nm) {
            let r = response(l);
            for c in 0..3 {
                rgb[c] += f64::from(w[c]) * r;
            }
        }
        rgb
    }
}

#[cfg(test)]
mod tests {
    use super::super::srgb::luminance;
    use super::*;

    const LIGHTS: [LightSpectrum; 6] = [
        LightSpectrum::Flat,
        LightSpectrum::D65,
        LightSpectrum::Blackbody { kelvin: 6500.0 },
        LightSpectrum::Blackbody { kelvin: 2700.0 },
        LightSpectrum::Rgb([0.2, 0.5, 0.9]),
        LightSpectrum::Rgb([1.0, 0.05, 0.0]),
    ];

    fn white(s: &SpectralSampling) -> [f64; 3] {
        s.rgb_of(|_| 1.0)
    }

    fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
        (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn wavelengths_are_the_centres_of_equal_bins() {
        let s = SpectralSampling::new(4, LightSpectrum::Flat).unwrap();
        assert_eq!(s.wavelengths_nm(), &[430.0, 530.0, 630.0, 730.0]);
        assert_eq!(s.bin_width_nm(), 100.0);
        assert_eq!(s.len(), 4);
        assert!(!s.is_empty());
        assert_eq!(s.weights().len(), 4);
    }

    /// Y = 1 for every K: the luminance of Σ w_k is 1 up to the rounding of the IEC matrices
    /// (their Y row times the XYZ → RGB matrix is (1e-5, 1.00003, 4e-6)).
    #[test]
    fn the_lights_own_colour_has_unit_luminance_for_every_k() {
        for light in LIGHTS {
            for k in [1, 2, 3, 7, 16, 31, 100] {
                let s = SpectralSampling::new(k, light).unwrap();
                let y = luminance(white(&s));
                assert!((y - 1.0).abs() < 1e-4, "{light:?} K={k}: Y = {y}");
            }
        }
    }

    /// The colour of the light over 380–780 nm, at Y = 1: trapezoid rule in 0.05 nm steps.
    fn integral_380_780(light: LightSpectrum) -> [f64; 3] {
        let mut xyz = [0.0; 3];
        for i in 0..=8000 {
            let w = if i == 0 || i == 8000 { 0.5 } else { 1.0 };
            let l = 380.0 + f64::from(i) * 0.05;
            let v = cie1931_xyz_bar(l).map(|c| c * light.relative(l) * w);
            (0..3).for_each(|c| xyz[c] += v[c]);
        }
        xyz_to_linear_srgb(xyz.map(|c| c / xyz[1]))
    }

    /// Σ w_k converges to the integral over 380–780 nm as K grows (midpoint rule, error
    /// O(1/K²)); that integral differs from the full 360–830 nm colour by under 1e-3.
    #[test]
    fn many_wavelengths_converge_to_the_integral() {
        for light in LIGHTS {
            let want = integral_380_780(light);
            let scale = want.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
            let errors: Vec<f64> = [4, 16, 64, 1024]
                .into_iter()
                .map(|k| max_diff(white(&SpectralSampling::new(k, light).unwrap()), want) / scale)
                .collect();
            assert!(
                errors.windows(2).all(|e| e[1] < e[0]),
                "{light:?}: {errors:?}"
            );
            // Relative to the largest component. Measured (largest over these lights; the RGB
            // uplift is piecewise quadratic between 5 nm nodes, so it converges last):
            // K = 16: 0.038, 64: 2.0e-3, 1024: 7.5e-6.
            assert!(errors[1] < 0.05, "{light:?}: {errors:?}");
            assert!(errors[2] < 3e-3, "{light:?}: {errors:?}");
            assert!(errors[3] < 1.5e-5, "{light:?}: {errors:?}");
            let truncation = max_diff(want, light.linear_srgb());
            assert!(truncation < 1e-3, "{light:?}: {truncation}");
        }
    }

    #[test]
    fn d65_comes_out_white_and_6500_k_near_white() {
        let d65 = white(&SpectralSampling::new(16, LightSpectrum::D65).unwrap());
        assert!(max_diff(d65, [1.0; 3]) < 1e-2, "{d65:?}");
        let bb =
            white(&SpectralSampling::new(16, LightSpectrum::Blackbody { kelvin: 6500.0 }).unwrap());
        assert!(max_diff(bb, [1.0; 3]) < 0.06, "{bb:?}");
        let rgb = white(&SpectralSampling::new(16, LightSpectrum::Rgb([1.0; 3])).unwrap());
        assert!(max_diff(rgb, [1.0; 3]) < 1e-2, "{rgb:?}");
    }

    /// The equal-energy light is (1.205, 0.948, 0.909): its XYZ is (1, 1, 1).
    #[test]
    fn the_equal_energy_light_is_the_row_sums_of_the_matrix() {
        let e = white(&SpectralSampling::new(64, LightSpectrum::Flat).unwrap());
        assert!(max_diff(e, [1.2048, 0.9484, 0.9087]) < 5e-3, "{e:?}");
    }

    #[test]
    fn a_2700_k_light_is_warm() {
        let s = SpectralSampling::new(16, LightSpectrum::Blackbody { kelvin: 2700.0 }).unwrap();
        let [r, g, b] = white(&s);
        // Continuous value (colour-science): (1.935, 0.804, 0.192).
        assert!(r > g && g > b && r > 5.0 * b, "{r} {g} {b}");
        assert!(max_diff([r, g, b], [1.935, 0.804, 0.192]) < 0.03);
    }

    #[test]
    fn combine_applies_a_response_per_wavelength() {
        let s = SpectralSampling::new(8, LightSpectrum::D65).unwrap();
        let ones = vec![1.0_f32; 8];
        let half = vec![0.5_f32; 8];
        let a = s.combine(&ones);
        let b = s.combine(&half);
        for c in 0..3 {
            assert!((b[c] - 0.5 * a[c]).abs() < 1e-6);
            assert!((f64::from(a[c]) - white(&s)[c]).abs() < 1e-5);
        }
        // Only the long wavelengths: reddish.
        let red: Vec<f32> = s
            .wavelengths_nm()
            .iter()
            .map(|&l| if l > 600.0 { 1.0 } else { 0.0 })
            .collect();
        let [r, g, b] = s.combine(&red);
        assert!(r > g && r > b);
    }

    #[test]
    fn bad_requests_are_errors() {
        assert_eq!(
            SpectralSampling::new(0, LightSpectrum::Flat),
            Err(SpectralSamplingError::NoWavelengths)
        );
        assert!(matches!(
            SpectralSampling::new(8, LightSpectrum::Blackbody { kelvin: -1.0 }),
            Err(SpectralSamplingError::Light(_))
        ));
    }
}

//! Light spectra: Planck's law and [`LightSpectrum`], the relative spectral power of a light.

use serde::{Deserialize, Serialize};

use super::cmf::{lerp, lerp_rows, spectrum_to_xyz};
use super::srgb::xyz_to_linear_srgb;
use super::tables::{
    D65, D65_START_NM, D65_STEP_NM, MALLETT2019_SRGB, MALLETT2019_SRGB_START_NM,
    MALLETT2019_SRGB_STEP_NM,
};

/// Planck constant (J s), exact in the SI since 2019.
const PLANCK_H: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum (m/s), exact.
const LIGHT_C: f64 = 299_792_458.0;
/// Boltzmann constant (J/K), exact.
const BOLTZMANN_K: f64 = 1.380_649e-23;

/// Spectral radiance of a black body by Planck's law,
/// `B(λ, T) = 2 h c² / λ⁵ · 1 / (exp(h c / (λ k T)) − 1)`,
/// in W·sr⁻¹·m⁻²·nm⁻¹ (per nanometre of wavelength), for `lambda_nm` in nm and `kelvin` in K.
/// Underflows to 0 where the exponent exceeds ~700 (e.g. visible light below ~30 K).
pub fn planck_radiance(lambda_nm: f64, kelvin: f64) -> f64 {
    let lambda_m = lambda_nm * 1e-9;
    let x = PLANCK_H * LIGHT_C / (lambda_m * BOLTZMANN_K * kelvin);
    2.0 * PLANCK_H * LIGHT_C * LIGHT_C / lambda_m.powi(5) / x.exp_m1() * 1e-9
}

/// `ln B(λ, T)` up to a constant, finite for any λ, T > 0 (no overflow of `exp`), so that
/// ratios of radiances at very low temperatures stay exact.
fn ln_planck_shape(lambda_nm: f64, kelvin: f64) -> f64 {
    let lambda_m = lambda_nm * 1e-9;
    let x = PLANCK_H * LIGHT_C / (lambda_m * BOLTZMANN_K * kelvin);
    // ln(e^x − 1) = x + ln(1 − e^−x), which does not overflow for large x.
    let ln_expm1 = if x > 30.0 {
        x + (-(-x).exp()).ln_1p()
    } else {
        x.exp_m1().ln()
    };
    -5.0 * lambda_nm.ln() - ln_expm1
}

/// The spectrum of a light source, as relative spectral power (the absolute scale is the
/// light's intensity, set elsewhere; [`super::SpectralSampling`] normalises the colour to
/// luminance Y = 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightSpectrum {
    /// A black body at `kelvin` (Planck's law). 6500 K is close to white in sRGB, 2700 K is a
    /// warm incandescent lamp.
    Blackbody {
        /// Temperature (K), finite and positive.
        kelvin: f64,
    },
    /// CIE standard illuminant D65 (daylight), the white point of sRGB: it renders as
    /// (1, 1, 1) to the precision of the IEC matrix (2e-4).
    D65,
    /// A linear sRGB colour, turned into a smooth spectrum by the Mallett & Yuksel (2019)
    /// spectral primary decomposition: `s(λ) = D65(λ) · (r ρ_r(λ) + g ρ_g(λ) + b ρ_b(λ))`,
    /// where the basis spectra ρ ∈ [0, 1] sum to 1, so (1, 1, 1) is exactly D65 and every
    /// non-negative colour gets a non-negative spectrum whose sRGB colour is `rgb` (within
    /// 3e-3, the accuracy of the published 5 nm basis). Zero outside 380–780 nm.
    /// Components must be finite and non-negative, with a positive luminance.
    Rgb([f32; 3]),
    /// Equal energy at every wavelength (CIE illuminant E). Not white in sRGB: at Y = 1 it is
    /// (1.205, 0.948, 0.909), slightly pink, since the sRGB white is D65.
    Flat,
}

/// Why a [`LightSpectrum`] cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LightSpectrumError {
    /// The blackbody temperature is not a finite positive number.
    #[error("blackbody temperature must be a finite number of kelvin above 0, got {0}")]
    BadTemperature(f64),
    /// The RGB colour has a negative or non-finite component, or zero luminance.
    #[error(
        "light colour must have finite non-negative components and a positive luminance, got {0:?}"
    )]
    BadRgb([f32; 3]),
}

impl LightSpectrum {
    /// Checks the parameters (see the variants).
    pub fn validate(&self) -> Result<(), LightSpectrumError> {
        match *self {
            LightSpectrum::Blackbody { kelvin } => {
                if kelvin.is_finite() && kelvin > 0.0 {
                    Ok(())
                } else {
                    Err(LightSpectrumError::BadTemperature(kelvin))
                }
            }
            LightSpectrum::Rgb(rgb) => {
                let ok = rgb.iter().all(|c| c.is_finite() && *c >= 0.0)
                    && super::srgb::luminance_f32(rgb) > 0.0;
                if ok {
                    Ok(())
                } else {
                    Err(LightSpectrumError::BadRgb(rgb))
                }
            }
            LightSpectrum::D65 | LightSpectrum::Flat => Ok(()),
        }
    }

    /// Relative spectral power at `lambda_nm`, on an arbitrary scale that is the same for
    /// every wavelength of one light: the blackbody is 1 at 560 nm, D65 is 1 at 560 nm (the
    /// CIE table / 100, zero outside 300–780 nm), `Flat` is 1. Meaningful only for a light
    /// that passes [`validate`](Self::validate).
    pub fn relative(&self, lambda_nm: f64) -> f64 {
        match *self {
            LightSpectrum::Blackbody { kelvin } => {
                (ln_planck_shape(lambda_nm, kelvin) - ln_planck_shape(560.0, kelvin)).exp()
            }
            LightSpectrum::D65 => d65(lambda_nm),
            LightSpectrum::Rgb(rgb) => {
                let Some(basis) = lerp_rows(
                    &MALLETT2019_SRGB,
                    MALLETT2019_SRGB_START_NM,
                    MALLETT2019_SRGB_STEP_NM,
                    lambda_nm,
                ) else {
                    return 0.0;
                };
                let reflectance = f64::from(rgb[0]) * basis[0]
                    + f64::from(rgb[1]) * basis[1]
                    + f64::from(rgb[2]) * basis[2];
                d65(lambda_nm) * reflectance
            }
            LightSpectrum::Flat => 1.0,
        }
    }

    /// CIE XYZ of the relative spectrum (`∫ s x̄ dλ` …, on the scale of [`relative`](Self::relative)).
    pub fn xyz(&self) -> [f64; 3] {
        spectrum_to_xyz(|l| self.relative(l))
    }

    /// The light's colour in linear sRGB, scaled to luminance Y = 1 (the normalisation of
    /// [`super::SpectralSampling`] in the limit of many wavelengths). NaN for a light with no
    /// luminance.
    pub fn linear_srgb(&self) -> [f64; 3] {
        let xyz = self.xyz();
        xyz_to_linear_srgb(xyz).map(|c| c / xyz[1])
    }
}

/// D65 relative power / 100 (1 at 560 nm); zero outside the table.
fn d65(lambda_nm: f64) -> f64 {
    lerp(&D65, D65_START_NM, D65_STEP_NM, lambda_nm).map_or(0.0, |v| v / 100.0)
}

#[cfg(test)]
mod tests {
    use super::super::cmf::chromaticity;
    use super::*;

    /// Wien's displacement law: the peak lies at b / T, b = 2.897771955e-3 m·K.
    #[test]
    fn planck_peaks_where_wien_says() {
        let t = 5000.0;
        let peak_nm = 2.897_771_955e-3 / t * 1e9; // 579.55 nm
        let b = planck_radiance(peak_nm, t);
        assert!(b > planck_radiance(peak_nm - 0.5, t));
        assert!(b > planck_radiance(peak_nm + 0.5, t));
        // The slope changes sign within ±0.05 nm of the predicted peak.
        assert!(planck_radiance(peak_nm - 0.05, t) < b && planck_radiance(peak_nm + 0.05, t) < b);
    }

    /// Stefan–Boltzmann: ∫ B dλ = σ T⁴ / π, σ = 5.670374419e-8 W m⁻² K⁻⁴.
    #[test]
    fn planck_integrates_to_stefan_boltzmann() {
        let t = 3000.0;
        // Midpoint rule on a logarithmic grid from 10 nm to 1 mm.
        let (lo, hi, n) = (10.0_f64.ln(), 1e6_f64.ln(), 200_000);
        let h = (hi - lo) / n as f64;
        let integral: f64 = (0..n)
            .map(|i| {
                let l = (lo + (i as f64 + 0.5) * h).exp();
                planck_radiance(l, t) * l * h
            })
            .sum();
        let want = 5.670_374_419e-8 * t.powi(4) / std::f64::consts::PI;
        assert!((integral / want - 1.0).abs() < 1e-6, "{integral} vs {want}");
    }

    #[test]
    fn the_blackbody_spectrum_is_relative_to_560_nm_and_stays_finite_when_cold() {
        let bb = LightSpectrum::Blackbody { kelvin: 2700.0 };
        assert!((bb.relative(560.0) - 1.0).abs() < 1e-15);
        let r = bb.relative(650.0);
        let want = planck_radiance(650.0, 2700.0) / planck_radiance(560.0, 2700.0);
        assert!((r / want - 1.0).abs() < 1e-12);
        // At 10 K, exp(h c / λ k T) overflows f64; the ratio does not.
        let cold = LightSpectrum::Blackbody { kelvin: 10.0 };
        assert!(cold.relative(700.0).is_finite() && cold.relative(700.0) > 1.0);
    }

    /// CIE standard illuminant A is a Planckian radiator at 2856 K with c₂ = 1.4388e-2 m·K,
    /// that is 2855.95 K with today's c₂ = h c / k = 1.438777e-2; its chromaticity is
    /// (0.44757, 0.40745) (CIE 015:2018).
    #[test]
    fn a_blackbody_at_illuminant_a_has_its_published_chromaticity() {
        let kelvin = 2856.0 * (PLANCK_H * LIGHT_C / BOLTZMANN_K) / 1.4388e-2;
        let [x, y] = chromaticity(LightSpectrum::Blackbody { kelvin }.xyz());
        assert!(
            (x - 0.44757).abs() < 1e-4 && (y - 0.40745).abs() < 1e-4,
            "{x} {y}"
        );
    }

    /// D65 (CIE 015): chromaticity (0.31271, 0.32902), white in sRGB.
    #[test]
    fn d65_has_its_published_chromaticity_and_is_srgb_white() {
        let [x, y] = chromaticity(LightSpectrum::D65.xyz());
        assert!(
            (x - 0.31271).abs() < 2e-5 && (y - 0.32902).abs() < 2e-5,
            "{x} {y}"
        );
        for c in LightSpectrum::D65.linear_srgb() {
            assert!((c - 1.0).abs() < 3e-4, "{c}");
        }
    }

    /// Illuminant E at Y = 1 has XYZ ≈ (1, 1, 1), so its sRGB is the row sums of the matrix.
    #[test]
    fn the_flat_spectrum_is_the_row_sums_of_the_srgb_matrix() {
        let rgb = LightSpectrum::Flat.linear_srgb();
        let want = [1.2048, 0.9484, 0.9087];
        for c in 0..3 {
            assert!((rgb[c] - want[c]).abs() < 5e-4, "{rgb:?}");
        }
    }

    /// The uplift reproduces the colour it was given (scaled to Y = 1).
    #[test]
    fn the_rgb_uplift_reproduces_its_colour() {
        for rgb in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.2, 0.5, 0.9],
            [0.9, 0.6, 0.1],
        ] {
            let light = LightSpectrum::Rgb(rgb);
            light.validate().unwrap();
            let y = super::super::srgb::luminance(rgb.map(f64::from));
            let got = light.linear_srgb();
            for c in 0..3 {
                // 5e-3: the published basis is fitted at 5 nm; we integrate at 1 nm
                // (measured: at most 3.5e-3, the blue primary's blue).
                assert!(
                    (got[c] * y - f64::from(rgb[c])).abs() < 5e-3,
                    "{rgb:?}: {got:?}"
                );
            }
            for l in (380..=780).step_by(5) {
                assert!(light.relative(f64::from(l)) >= 0.0);
            }
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        for kelvin in [0.0, -5.0, f64::NAN, f64::INFINITY] {
            assert!(LightSpectrum::Blackbody { kelvin }.validate().is_err());
        }
        for rgb in [
            [0.0; 3],
            [-0.1, 1.0, 1.0],
            [f32::NAN, 1.0, 1.0],
            [f32::INFINITY, 0.0, 0.0],
        ] {
            assert!(LightSpectrum::Rgb(rgb).validate().is_err(), "{rgb:?}");
        }
        assert!(LightSpectrum::Flat.validate().is_ok());
        assert!(LightSpectrum::D65.validate().is_ok());
    }
}

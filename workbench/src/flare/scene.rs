//! A flare scene: the lens, its lights, the output frame and the quality preset.

use anyhow::{Context, bail};
use flarebench_sdk::color::LightSpectrum;

/// A light at infinity.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpec {
    /// Angle to the optical axis and azimuth about it (degrees).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Irradiance perpendicular to the beam, in image units per mm² of entrance pupil.
    pub intensity: f64,
    pub spectrum: LightSpectrum,
}

impl LightSpec {
    /// Parses `THETA,PHI[,INTENSITY[,KELVIN]]` (degrees; intensity 1; daylight D65 unless a
    /// blackbody temperature is given).
    pub fn parse(s: &str) -> anyhow::Result<LightSpec> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if !(2..=4).contains(&parts.len()) {
            bail!("--light takes THETA,PHI[,INTENSITY[,KELVIN]] (degrees), got `{s}`");
        }
        let num = |i: usize, what: &str| -> anyhow::Result<f64> {
            let v: f64 = parts[i]
                .parse()
                .with_context(|| format!("--light `{s}`: {what} `{}` is not a number", parts[i]))?;
            anyhow::ensure!(v.is_finite(), "--light `{s}`: {what} must be finite");
            Ok(v)
        };
        let theta_deg = num(0, "THETA")?;
        anyhow::ensure!(
            (0.0..90.0).contains(&theta_deg),
            "--light `{s}`: THETA must be in [0, 90) degrees"
        );
        let phi_deg = num(1, "PHI")?;
        let intensity = if parts.len() > 2 {
            num(2, "INTENSITY")?
        } else {
            1.0
        };
        anyhow::ensure!(intensity > 0.0, "--light `{s}`: INTENSITY must be positive");
        let spectrum = if parts.len() > 3 {
            LightSpectrum::Blackbody {
                kelvin: num(3, "KELVIN")?,
            }
        } else {
            LightSpectrum::D65
        };
        spectrum
            .validate()
            .with_context(|| format!("--light `{s}`"))?;
        Ok(LightSpec {
            theta_deg,
            phi_deg,
            intensity,
            spectrum,
        })
    }
}

/// Speed against accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    Fast,
    Default,
    High,
}

impl Quality {
    /// Wavelength bands traced (before planning merges bands whose dispersion is invisible).
    /// Default 7: ghosts' colour fringes need several bands; 7 stratified bands keep the
    /// colour error of a smooth spectrum under a few per cent.
    pub fn bands(self) -> usize {
        match self {
            Quality::Fast => 3,
            Quality::Default => 7,
            Quality::High => 15,
        }
    }

    /// Multiplier on each ghost's precomputed grid size.
    pub fn grid_scale(self) -> f64 {
        match self {
            Quality::Fast => 0.5,
            Quality::Default => 1.0,
            Quality::High => 2.0,
        }
    }

    /// Ghosts whose energy share (of the direct image) is below this are left out.
    pub fn energy_threshold(self) -> f64 {
        match self {
            Quality::Fast => 1e-5,
            Quality::Default => 1e-6,
            Quality::High => 1e-8,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_parsing() {
        let l = LightSpec::parse("10,45").unwrap();
        assert_eq!((l.theta_deg, l.phi_deg, l.intensity), (10.0, 45.0, 1.0));
        let l = LightSpec::parse(" 5 , -30 , 2.5 , 3200 ").unwrap();
        assert_eq!(l.intensity, 2.5);
        assert_eq!(l.spectrum, LightSpectrum::Blackbody { kelvin: 3200.0 });
        for bad in ["10", "a,b", "95,0", "10,0,-1", "10,0,1,2,3", "10,nan"] {
            assert!(LightSpec::parse(bad).is_err(), "{bad}");
        }
    }
}

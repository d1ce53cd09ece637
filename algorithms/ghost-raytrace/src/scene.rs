//! A flare scene's lights and the quality preset.

use std::fmt;
use std::str::FromStr;

use flarebench_sdk::color::LightSpectrum;

use crate::error::LightSpecError;

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
    pub fn parse(s: &str) -> Result<LightSpec, LightSpecError> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if !(2..=4).contains(&parts.len()) {
            return Err(LightSpecError::Shape(s.to_string()));
        }
        let num = |i: usize, what: &'static str| -> Result<f64, LightSpecError> {
            parts[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| LightSpecError::NotANumber {
                    spec: s.to_string(),
                    what,
                    value: parts[i].to_string(),
                })
        };
        let theta_deg = num(0, "THETA")?;
        if !(0.0..90.0).contains(&theta_deg) {
            return Err(LightSpecError::Theta(s.to_string()));
        }
        let phi_deg = num(1, "PHI")?;
        let intensity = if parts.len() > 2 {
            num(2, "INTENSITY")?
        } else {
            1.0
        };
        if intensity <= 0.0 {
            return Err(LightSpecError::Intensity(s.to_string()));
        }
        let spectrum = if parts.len() > 3 {
            LightSpectrum::Blackbody {
                kelvin: num(3, "KELVIN")?,
            }
        } else {
            LightSpectrum::D65
        };
        spectrum
            .validate()
            .map_err(|source| LightSpecError::Spectrum {
                spec: s.to_string(),
                source,
            })?;
        Ok(LightSpec {
            theta_deg,
            phi_deg,
            intensity,
            spectrum,
        })
    }
}

impl FromStr for LightSpec {
    type Err = LightSpecError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        LightSpec::parse(s)
    }
}

/// Speed against accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    Fast,
    Default,
    High,
}

impl Quality {
    /// Every preset, fastest first.
    pub const ALL: [Quality; 3] = [Quality::Fast, Quality::Default, Quality::High];

    /// The preset's name as written on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Fast => "fast",
            Quality::Default => "default",
            Quality::High => "high",
        }
    }

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

    /// Coarse pixels a ghost's radius must span when it is drawn into a coarse frame
    /// (`plan::coarse_factor`): the edge blur this allows touches about 1/this of the ghost's
    /// area. Measured on the Heliar (480×270, 10°): 64 gives 2.0% relative RMSE against the
    /// reference, 128 gives 1.2%, full resolution 0.84%.
    pub fn coarse_pixels_per_radius(self) -> f64 {
        match self {
            Quality::Fast => 32.0,
            Quality::Default => 128.0,
            Quality::High => 512.0,
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

impl fmt::Display for Quality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Quality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Quality::ALL
            .into_iter()
            .find(|q| q.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| format!("quality `{s}` is not one of fast, default, high"))
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

    #[test]
    fn quality_names_round_trip() {
        for q in Quality::ALL {
            assert_eq!(q.name().parse::<Quality>(), Ok(q));
        }
        assert!("best".parse::<Quality>().is_err());
    }
}

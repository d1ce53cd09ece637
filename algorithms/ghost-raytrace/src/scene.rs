//! A flare scene's lights and the quality preset.

use std::fmt;
use std::str::FromStr;

use flarebench_sdk::color::LightSpectrum;

use crate::error::LightSpecError;

/// Largest coarse-frame factor of the presets (`Quality::max_downscale`).
pub const MAX_DOWNSCALE: usize = 16;

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
    /// Parses `THETA,PHI[,INTENSITY[,COLOUR]]` (degrees; intensity 1; COLOUR a blackbody
    /// temperature in kelvin, or linear sRGB `R:G:B` (smoothly uplifted to a spectrum);
    /// daylight D65 when absent).
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
        let spectrum = match parts.get(3) {
            None => LightSpectrum::D65,
            Some(c) if c.contains(':') => {
                let rgb: Vec<&str> = c.split(':').map(str::trim).collect();
                if rgb.len() != 3 {
                    return Err(LightSpecError::NotANumber {
                        spec: s.to_string(),
                        what: "COLOUR (R:G:B)",
                        value: c.to_string(),
                    });
                }
                let mut v = [0f32; 3];
                for (k, part) in rgb.iter().enumerate() {
                    v[k] = part
                        .parse::<f32>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| LightSpecError::NotANumber {
                            spec: s.to_string(),
                            what: "COLOUR (R:G:B)",
                            value: c.to_string(),
                        })?;
                }
                LightSpectrum::Rgb(v)
            }
            Some(_) => LightSpectrum::Blackbody {
                kelvin: num(3, "KELVIN")?,
            },
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

impl LightSpec {
    /// The light as a plugin scene takes it (the inverse of [`crate::plugin::light_specs`]).
    pub fn scene_light(&self) -> flarebench_sdk::abi::author::SceneLight {
        flarebench_sdk::abi::author::SceneLight {
            theta_deg: self.theta_deg,
            phi_deg: self.phi_deg,
            intensity: self.intensity,
            spectrum: self.spectrum,
        }
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

    /// The light's spectral sampling, and the most bands any ghost is traced at: each ghost
    /// takes as many as keep neighbouring bands within half a drawn pixel of its dispersion,
    /// up to this (`plan::plan`), so the cap costs only where a ghost's colour fringe is wide.
    /// Measured on the Nikon zoom (480×270, light 10°, 30°, against the reference): a cap of 7
    /// gives 9.8% relative RMSE, 11 gives 3.6%, 15 gives 2.6%, 31 (the reference's) 1.9% — the
    /// two most dispersive ghosts made 92% of the error at 7. The Heliar's ghosts need fewer
    /// than 7 bands, so its error and time do not change with the cap.
    pub fn bands(self) -> usize {
        match self {
            Quality::Fast => 7,
            Quality::Default => 31,
            Quality::High => 31,
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

    /// Multiplier, with [`Quality::grid_scale`], on a smooth ghost's grid
    /// (`plan::SMOOTH_GRID`): its triangles cost time by their number more than by their
    /// pixels. For the default preset (light 10°, 30°, with a table, against the reference),
    /// 0.75 takes the Heliar's 1920 × 1080 frame from 17.5 to about 14 ms for an error of
    /// 1.926% against 1.882% at 1, and the Nikon zoom's (960 × 540) to 1.809% against 1.752%;
    /// 0.65 reaches 1.997% and 1.894%, too close to the 2% budget. The fast preset's grids are
    /// at or near their floor already; the high one keeps every grid.
    pub fn smooth_grid_scale(self) -> f64 {
        match self {
            Quality::Fast => 1.0,
            Quality::Default => 0.75,
            Quality::High => 1.0,
        }
    }

    /// Coarse pixels a ghost's radius must span when it is drawn into a coarse frame
    /// (`plan::coarse_factor`): the edge blur this allows touches about 1/this of the ghost's
    /// area. The default, 96, keeps every measured frame within 2% relative RMSE against the
    /// reference, with traced bounds and with a precomputed table (the Heliar at 1920 × 1080,
    /// 10°, 30°: 1.882% / 1.733%, table / traced, with the smooth grids at 1; the Nikon zoom at
    /// 960 × 540: 1.752% / 1.558%). 80 leaves the Heliar no margin (1.990%) for no time, and
    /// 64 exceeds the budget (2.79%).
    pub fn coarse_pixels_per_radius(self) -> f64 {
        match self {
            Quality::Fast => 32.0,
            Quality::Default => 96.0,
            Quality::High => 512.0,
        }
    }

    /// Largest coarse-frame factor a ghost may be drawn at (`plan::coarse_factor`). For the
    /// default preset (Heliar at 1920 × 1080, light 10°, 30°, against the reference), 8 costs
    /// no more time than 16 (the one ghost at 1/16, 4-0, costs little more at 1/8) and lowers
    /// the error from 1.961% to 1.836% with a precomputed table (1.750% to 1.619% traced); the
    /// Nikon zoom's does not change. 4 lowers the Heliar's error further (1.852% to 1.637%) but
    /// its frame takes 15.9 instead of 12.3 ms. The fast preset keeps 16: at 8 its frames take
    /// 7% (Heliar) and 12% (Nikon zoom) longer.
    pub fn max_downscale(self) -> usize {
        match self {
            Quality::Fast => MAX_DOWNSCALE,
            Quality::Default => 8,
            Quality::High => 8,
        }
    }

    /// The share of the ghosts' energy on the frame that may be left out: the dimmest
    /// ghosts are dropped, dimmest first, while together they carry at most this much
    /// ([`crate::plan::dim_threshold`]; each ghost weighed by [`crate::plan::on_frame_share`]). Measured on the Nikon zoom (480×270, light 10°, 30°,
    /// 31 bands): a fixed cut at 1e-6 of the direct image's energy dropped 83 of 210 ghosts
    /// and 3.2% of the ghost energy, which alone made 2.2% of the default's error. The
    /// default's 1e-3, against 3e-3 (light 10°, 30°): Nikon zoom at 960 × 540 1.872% against
    /// 2.014% (157 ghosts drawn instead of 146, no measurable time), Heliar at 1920 × 1080
    /// 1.718% against 1.855% (its small, bright ghost 7-3 kept); 3e-4 gains little more
    /// (1.858%, 1.718%).
    pub fn dim_budget(self) -> f64 {
        match self {
            Quality::Fast => 3e-2,
            Quality::Default => 1e-3,
            Quality::High => 3e-4,
        }
    }

    /// The colour error a ghost's spectral sampling may make where its flux varies across the
    /// spectrum other than its throughput at normal incidence does
    /// ([`crate::colour::GhostColours::bins_error`]): a ghost takes at least the fewest bands
    /// that keep it within this ([`crate::plan::PlanOptions::spectral_tolerance`]).
    pub fn spectral_tolerance(self) -> f64 {
        match self {
            Quality::Fast => 2e-2,
            Quality::Default => 5e-3,
            Quality::High => 2e-3,
        }
    }

    /// The relative RMSE the plan's choice of drawing methods may add to a frame, in
    /// quadrature with the rest of its error (`crate::method::choose`). The fast preset
    /// splats its near-focus ghosts within 3%; the default and high presets mesh every ghost:
    /// their frames are within 2% of the reference meshed, with little of the budget to spend
    /// (docs/performance.md, § Why the frame costs what it does).
    pub fn method_error_budget(self) -> f64 {
        match self {
            Quality::Fast => 3e-2,
            Quality::Default => 0.0,
            Quality::High => 0.0,
        }
    }

    /// Four-reflection paths whose energy bound (of the direct image's energy) is below this
    /// are left out before their own bounds are traced (`ghost::FourReflectionBounds`). Two-
    /// reflection ghosts are culled by [`Quality::dim_budget`] instead, once traced.
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
        let l = LightSpec::parse("1,2,3,1:0.5:0.25").unwrap();
        assert_eq!(l.spectrum, LightSpectrum::Rgb([1.0, 0.5, 0.25]));
        for bad in [
            "10",
            "a,b",
            "95,0",
            "10,0,-1",
            "10,0,1,2,3",
            "10,nan",
            "1,2,3,1:2",
            "1,2,3,a:b:c",
            "1,2,3,0:0:0",
            "1,2,3,-1:1:1",
        ] {
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

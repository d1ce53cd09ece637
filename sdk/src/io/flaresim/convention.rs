//! What the `semi_ap` column holds, [`LensApertureConvention`], and how it is told from the
//! data when the user does not say.
//!
//! FlareSim's format names the column a semi-aperture, but most files of its library (those
//! converted from the Optical Bench) hold clear **diameters**. Each reading is checked against
//! what a clear aperture cannot do — exceed |R|, or make neighbouring surfaces cross — and the
//! stop against the stated f-number. In order:
//!
//! 1. fewer semi-diameters beyond |R| (such a lens cannot be traced at all);
//! 2. the stop: the reading whose paraxial f-number is nearer the stated one, when that one is
//!    within [`F_NUMBER_MATCH`] of it;
//! 3. fewer crossings of neighbouring surfaces (softer: a file without its aspheres may cross
//!    whatever its apertures);
//! 4. otherwise semi-diameters, as the column is named.
//!
//! Halving never makes a clear aperture less possible, so steps 1 and 3 can only ever choose
//! diameters; only the stop can show that the file holds semi-diameters.

use std::str::FromStr;

use super::clearance::Impossible;
use super::f_number::Stated;

/// The stop's paraxial f-number matches the stated one when their ratio is within this factor:
/// the two readings differ by a factor of 2, and the files state f-numbers rounded to 0.1
/// (and some zooms the nominal, not the prescription's).
pub(super) const F_NUMBER_MATCH: f64 = 1.25;

/// What the `semi_ap` column of a `.lens` file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LensApertureConvention {
    /// Clear semi-diameters (radii), as the column is named.
    Semi,
    /// Clear diameters: each value is halved.
    Diameter,
}

impl LensApertureConvention {
    /// The name used on the command line and in messages.
    pub fn name(self) -> &'static str {
        match self {
            LensApertureConvention::Semi => "semi",
            LensApertureConvention::Diameter => "diameter",
        }
    }

    /// The factor from the column to a semi-diameter.
    pub fn scale(self) -> f64 {
        match self {
            LensApertureConvention::Semi => 1.0,
            LensApertureConvention::Diameter => 0.5,
        }
    }

    /// What the column is read as, for messages.
    pub(super) fn reading(self) -> &'static str {
        match self {
            LensApertureConvention::Semi => "semi-diameters",
            LensApertureConvention::Diameter => "diameters (halved)",
        }
    }
}

impl FromStr for LensApertureConvention {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "semi" => Ok(LensApertureConvention::Semi),
            "diameter" => Ok(LensApertureConvention::Diameter),
            other => Err(format!(
                "unknown `.lens` aperture convention `{other}`; expected semi or diameter"
            )),
        }
    }
}

/// What one reading of the column gives.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Reading {
    pub impossible: Impossible,
    /// The stop's paraxial f-number wide open (EFL/EPD), when the lens has a focal length.
    pub f_number: Option<f64>,
}

/// The evidence for both readings and the stated f-number.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Evidence {
    pub semi: Reading,
    pub diameter: Reading,
    /// The f-number the file states, and where it says so (for messages).
    pub stated_f_number: Option<Stated>,
}

/// Which step of the rule decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Basis {
    BeyondRadius,
    Stop,
    Crossings,
    Undecided,
}

impl Basis {
    /// What decided, for messages.
    pub fn label(self) -> &'static str {
        match self {
            Basis::BeyondRadius => "by semi-diameters beyond |R|",
            Basis::Stop => "by the stop against the stated f-number",
            Basis::Crossings => "by crossing surfaces",
            Basis::Undecided => "undecided, as the column is named",
        }
    }
}

impl Evidence {
    fn reading(&self, c: LensApertureConvention) -> &Reading {
        match c {
            LensApertureConvention::Semi => &self.semi,
            LensApertureConvention::Diameter => &self.diameter,
        }
    }

    /// The convention the data point to, and the step that decided.
    pub fn decide(&self) -> (LensApertureConvention, Basis) {
        use LensApertureConvention::{Diameter, Semi};
        let (s, d) = (&self.semi.impossible, &self.diameter.impossible);
        if s.beyond_radius.len() != d.beyond_radius.len() {
            let c = if d.beyond_radius.len() < s.beyond_radius.len() {
                Diameter
            } else {
                Semi
            };
            return (c, Basis::BeyondRadius);
        }
        if let Some(c) = self.by_stop() {
            return (c, Basis::Stop);
        }
        if s.crossings.len() != d.crossings.len() {
            let c = if d.crossings.len() < s.crossings.len() {
                Diameter
            } else {
                Semi
            };
            return (c, Basis::Crossings);
        }
        (Semi, Basis::Undecided)
    }

    /// The reading whose stop matches the stated f-number, if one does.
    fn by_stop(&self) -> Option<LensApertureConvention> {
        let (stated, _) = self.stated_f_number?;
        let off = |r: &Reading| r.f_number.map(|n| (n / stated).ln().abs());
        let (s, d) = (off(&self.semi)?, off(&self.diameter)?);
        let (c, best) = if d < s {
            (LensApertureConvention::Diameter, d)
        } else {
            (LensApertureConvention::Semi, s)
        };
        (best <= F_NUMBER_MATCH.ln()).then_some(c)
    }

    /// Why `chosen` was read, in one sentence (without the conclusion), e.g. "as
    /// semi-diameters, 2 semi-diameters exceed |R| (…); the stop gives f/1.42 as diameters,
    /// f/0.71 as semi-diameters, against the stated f/1.4 (comment header)"; `lines` gives each
    /// surface's line in the file.
    pub fn explain(&self, chosen: LensApertureConvention, basis: Basis, lines: &[usize]) -> String {
        let other = match chosen {
            LensApertureConvention::Semi => LensApertureConvention::Diameter,
            LensApertureConvention::Diameter => LensApertureConvention::Semi,
        };
        let mut parts = Vec::new();
        let other_bad = &self.reading(other).impossible;
        if !other_bad.is_empty() {
            parts.push(format!(
                "as {}, {}",
                other.reading(),
                other_bad.describe(lines)
            ));
        }
        parts.push(self.stop_sentence(chosen, other));
        if basis == Basis::Undecided {
            parts.push(
                "the data allow both readings: the column is read as it is named".to_string(),
            );
        }
        parts.join("; ")
    }

    fn stop_sentence(
        &self,
        chosen: LensApertureConvention,
        other: LensApertureConvention,
    ) -> String {
        let (Some(a), Some(b)) = (self.reading(chosen).f_number, self.reading(other).f_number)
        else {
            return "the stop's f-number is unknown (no focal length)".to_string();
        };
        let stops = format!(
            "the stop gives f/{} as {}, f/{} as {}",
            round2(a),
            chosen.reading(),
            round2(b),
            other.reading()
        );
        match self.stated_f_number {
            Some((n, from)) => format!("{stops}, against the stated f/{n} ({from})"),
            None => format!("{stops}; the file states no f-number"),
        }
    }
}

fn round2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::flaresim::clearance::BeyondRadius;

    fn reading(beyond: usize, f_number: Option<f64>) -> Reading {
        Reading {
            impossible: Impossible {
                beyond_radius: vec![
                    BeyondRadius {
                        surface: 0,
                        semi_diameter: 2.0,
                        limit: 1.0,
                    };
                    beyond
                ],
                crossings: Vec::new(),
            },
            f_number,
        }
    }

    #[test]
    fn the_stop_decides_when_both_readings_are_possible() {
        let e = Evidence {
            semi: reading(0, Some(2.0)),
            diameter: reading(0, Some(4.0)),
            stated_f_number: Some((4.0, "comment header")),
        };
        assert_eq!(e.decide(), (LensApertureConvention::Diameter, Basis::Stop));
        let e = Evidence {
            stated_f_number: Some((2.1, "name")),
            ..e
        };
        assert_eq!(e.decide(), (LensApertureConvention::Semi, Basis::Stop));
        // f/2.9 is within neither 1.25 × 2 nor 4 / 1.25: no decision by the stop.
        let e = Evidence {
            stated_f_number: Some((2.9, "name")),
            ..e
        };
        assert_eq!(e.decide(), (LensApertureConvention::Semi, Basis::Undecided));
    }

    #[test]
    fn a_semi_diameter_beyond_its_radius_outweighs_the_stop() {
        let e = Evidence {
            semi: reading(2, Some(2.0)),
            diameter: reading(0, Some(4.0)),
            stated_f_number: Some((2.0, "comment header")),
        };
        assert_eq!(
            e.decide(),
            (LensApertureConvention::Diameter, Basis::BeyondRadius)
        );
        let why = e.explain(LensApertureConvention::Diameter, Basis::BeyondRadius, &[12]);
        assert!(
            why.contains("as semi-diameters, 2 semi-diameters exceed |R| (first: line 12, 2 mm"),
            "{why}"
        );
        assert!(
            why.contains("against the stated f/2 (comment header)"),
            "{why}"
        );
    }

    #[test]
    fn conventions_parse_by_name() {
        for c in [
            LensApertureConvention::Semi,
            LensApertureConvention::Diameter,
        ] {
            assert_eq!(c.name().parse::<LensApertureConvention>(), Ok(c));
        }
        assert!("radius".parse::<LensApertureConvention>().is_err());
    }
}

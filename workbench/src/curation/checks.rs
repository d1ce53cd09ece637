//! The checks of a curated lens: its paraxial focal length against the one its file states
//! and its ghosts rendered finite for lights at 0°, 10° and the edge of its field, which it
//! must pass to be written, and the quick stability suite (`flarebench stability --quick`,
//! without the synthetic lenses), whose result is recorded: the lens's notes say that it
//! passed, or which findings lay outside their limits and by how much.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::paraxial::analyse;
use ghost_raytrace::ghosts::{RenderOptions, render_with};
use ghost_raytrace::plan::{PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};

use crate::stability::{self, SuiteOptions, field, frame_of, non_finite};

/// Largest relative difference between the paraxial EFL and the stated focal length (the
/// issue's bound; 92.7% of FlareSim's lenses are within 1%, `docs/lenses.md`).
pub const MAX_EFL_DEVIATION: f64 = 0.02;

/// Largest relative difference between the focal length the lens's name gives and the one
/// its file states (for a zoom: outside its range): a patent's focal length differs from the
/// marketed one by up to 6% in the selection (Fujifilm XF18mm: 19.3 mm); more means the name
/// was misread.
pub const MAX_NOMINAL_DEVIATION: f64 = 0.08;

/// Width of the frames the ghosts are rendered into for the checks (pixels).
pub const RENDER_WIDTH: usize = 96;

/// The light angles off the axis that do not depend on the lens (degrees); the field's edge is
/// the third.
pub const FIXED_ANGLES_DEG: [f64; 2] = [0.0, 10.0];

/// The azimuth of the lights (degrees).
pub const LIGHT_PHI_DEG: f64 = 30.0;

/// One render of the checks.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderCheck {
    pub theta_deg: f64,
    /// Ghosts drawn.
    pub ghosts: usize,
    /// NaN/Inf channel values in the image; the error when it could not be rendered.
    pub result: Result<usize, String>,
}

/// What the checks found.
#[derive(Clone, Debug, PartialEq)]
pub struct Checks {
    pub efl_mm: f64,
    pub stated_mm: Option<f64>,
    /// The focal length the lens's name gives (a zoom's range).
    pub nominal_mm: Option<[f64; 2]>,
    pub edge_deg: f64,
    pub renders: Vec<RenderCheck>,
    /// The quick stability suite's findings and those outside their limits (what they were);
    /// `None` when it was not run.
    pub stability: Option<Stability>,
}

/// What the quick stability suite found.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    pub findings: usize,
    /// The findings outside their limits, one phrase each (check, case, value, limit; the
    /// figures to two significant digits, so the phrase does not change with the last bits).
    pub failures: Vec<String>,
}

impl Checks {
    /// The EFL's relative difference from the stated focal length.
    pub fn efl_deviation(&self) -> Option<f64> {
        self.stated_mm.map(|s| self.efl_mm / s - 1.0)
    }

    /// What failed of the checks a lens must pass to be written (focal length, renders), one
    /// sentence each; empty when it passes them. The stability suite's findings outside their
    /// limits are recorded in the note instead ([`Checks::note`]).
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        match self.efl_deviation() {
            Some(d) if d.abs() <= MAX_EFL_DEVIATION => {}
            Some(d) => out.push(format!(
                "the paraxial EFL {:.2} mm is {:+.2}% from the stated {} mm (limit ±{}%)",
                self.efl_mm,
                100.0 * d,
                self.stated_mm.unwrap_or_default(),
                100.0 * MAX_EFL_DEVIATION
            )),
            None => out.push("the file states no focal length".into()),
        }
        if let (Some([lo, hi]), Some(stated)) = (self.nominal_mm, self.stated_mm) {
            let within = lo * (1.0 - MAX_NOMINAL_DEVIATION) <= stated
                && stated <= hi * (1.0 + MAX_NOMINAL_DEVIATION);
            if !within {
                out.push(format!(
                    "the stated focal length {stated} mm is not within {}% of the name's \
                     {lo}–{hi} mm",
                    100.0 * MAX_NOMINAL_DEVIATION
                ));
            }
        }
        for r in &self.renders {
            match &r.result {
                Ok(0) => {}
                Ok(n) => out.push(format!("{n} non-finite values at θ {:.1}°", r.theta_deg)),
                Err(e) => out.push(format!("no render at θ {:.1}°: {e}", r.theta_deg)),
            }
        }
        out
    }

    /// The stability suite's findings outside their limits (empty when it passed or did not
    /// run).
    pub fn stability_failures(&self) -> &[String] {
        self.stability.as_ref().map_or(&[], |s| &s.failures)
    }

    /// The sentence for the lens's notes.
    pub fn note(&self) -> String {
        let efl = match (self.stated_mm, self.efl_deviation()) {
            (Some(s), Some(d)) => format!(
                "paraxial EFL {:.2} mm at the d line, {:+.2}% from the stated {s} mm",
                self.efl_mm,
                100.0 * d
            ),
            _ => format!("paraxial EFL {:.2} mm at the d line", self.efl_mm),
        };
        let angles: Vec<String> = self
            .renders
            .iter()
            .map(|r| format!("{:.1}° ({} ghosts drawn)", r.theta_deg, r.ghosts))
            .collect();
        let finite = if self.renders.iter().all(|r| r.result == Ok(0)) {
            "finite"
        } else {
            "NOT finite"
        };
        let stability = match &self.stability {
            Some(s) if s.failures.is_empty() => {
                format!("passed ({} findings, none outside its limit)", s.findings)
            }
            Some(s) => format!(
                "FAILED, {} of {} findings outside their limits: {}",
                s.failures.len(),
                s.findings,
                s.failures.join("; ")
            ),
            None => "not run".into(),
        };
        format!(
            "Checks (flarebench curate): {efl}; ghosts {finite} for lights at {} (the last the \
             field's edge; {RENDER_WIDTH} px wide, fast preset); stability --quick: {stability}.",
            angles.join(", "),
        )
    }
}

/// `x` to two significant digits (`1.1e-3`; whole numbers as they are).
fn two_digits(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e6 {
        format!("{x}")
    } else {
        format!("{x:.1e}")
    }
}

/// Renders the ghosts of one light at `theta_deg` into a frame `width` pixels across at the
/// fast preset.
pub fn render_check(system: &LensSystem, theta_deg: f64, width: usize) -> RenderCheck {
    let frame = frame_of(system, width);
    let light = LightSpec {
        theta_deg,
        phi_deg: LIGHT_PHI_DEG,
        ..LightSpec::parse("0,0").expect("a valid light")
    };
    let options = PlanOptions::for_quality(Quality::Fast, None);
    let rendered = plan(system, &[light], &frame, &options)
        .map_err(|e| format!("plan: {e}"))
        .and_then(|plans| {
            let ghosts = plans.iter().map(|p| p.ghosts.len()).sum();
            render_with(
                system,
                &Aperture::Circular,
                frame,
                &plans,
                RenderOptions::default(),
            )
            .map(|(img, _)| (ghosts, non_finite(&img)))
            .map_err(|e| format!("render: {e}"))
        });
    match rendered {
        Ok((ghosts, bad)) => RenderCheck {
            theta_deg,
            ghosts,
            result: Ok(bad),
        },
        Err(e) => RenderCheck {
            theta_deg,
            ghosts: 0,
            result: Err(e),
        },
    }
}

/// Runs the checks on `system` (named `name` in the stability findings); the quick stability
/// suite only when `stability`.
pub fn run(name: &str, system: &LensSystem, stability: bool) -> Checks {
    let efl_mm = analyse(system, system.default_wavelength_nm()).map_or(f64::NAN, |p| p.efl_mm);
    let edge_deg = field::edge_deg(system);
    let renders = FIXED_ANGLES_DEG
        .into_iter()
        .chain([edge_deg])
        .map(|theta| render_check(system, theta, RENDER_WIDTH))
        .collect();
    let options = SuiteOptions {
        synthetic: false,
        ..SuiteOptions::quick()
    };
    let stability = stability.then(|| {
        let report = stability::run(&[(name.to_string(), system.clone())], options, &|_| {});
        Stability {
            findings: report.findings.len(),
            failures: report
                .findings
                .iter()
                .filter(|f| !f.pass)
                .map(|f| {
                    if f.value.is_nan() {
                        return format!("{} at {}: not measured ({})", f.check, f.case, f.note);
                    }
                    format!(
                        "{} at {}: {} (limit {})",
                        f.check,
                        f.case,
                        two_digits(f.value),
                        two_digits(f.limit)
                    )
                })
                .collect(),
        }
    });
    Checks {
        efl_mm,
        stated_mm: system.stated_efl_mm,
        nominal_mm: system.nominal_focal_mm,
        edge_deg,
        renders,
        stability,
    }
}

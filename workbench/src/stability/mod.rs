//! The stiff and extreme suite behind `flarebench stability`: every check measures one figure
//! against a stated limit, and the suite passes when every figure is within its limit.
//!
//! Three groups of checks (docs/accuracy.md § Stability):
//! - [`field`]: per lens, lights from the axis to past the edge of the field and at 89° —
//!   NaN/Inf counts, f32 against f64 images, the chief ray aimed through the stop's centre;
//! - [`stops`]: per lens, the stop opened wide and closed to f/64 — NaN/Inf, f32 against f64,
//!   the direct flux against the pupil's area;
//! - [`synthetic`]: lenses built for one difficulty each — the analytic plate (energy against
//!   its closed form, two and four reflections), a near-flat surface against a flat one, rays
//!   on both sides of total internal reflection, a 0.01 mm air gap, tiny radii (a whole lens
//!   scaled by 1e-3 and 1e3), caustics — measured against closed forms or against the
//!   independent Monte-Carlo reference (`flarebench_sdk::ghost::monte_carlo`).

pub mod field;
pub mod stops;
pub mod synthetic;

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::ghosts::{RenderOptions, render_with};
use ghost_raytrace::plan::{PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

/// One measured figure against its limit: it passes when `value ≤ limit`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// What is checked (`non-finite`, `f32-vs-f64`, `chief-ray`, `plate-energy`, …).
    pub check: &'static str,
    /// The lens (a bundled lens's name, or the synthetic lens's).
    pub lens: String,
    /// The case within the check (`θ 30.0°`, `f/64`, …).
    pub case: String,
    pub value: f64,
    pub limit: f64,
    pub pass: bool,
    /// What the figure is, or why a case is right as it is.
    pub note: String,
}

impl Finding {
    /// A finding that passes when `value ≤ limit` (a NaN value fails).
    pub fn measured(
        check: &'static str,
        lens: &str,
        case: String,
        value: f64,
        limit: f64,
        note: String,
    ) -> Finding {
        Finding {
            check,
            lens: lens.to_string(),
            case,
            value,
            limit,
            pass: value <= limit,
            note,
        }
    }

    /// A case that could not be measured (an error where a result belongs): it fails.
    pub fn failed(check: &'static str, lens: &str, case: String, why: String) -> Finding {
        Finding {
            check,
            lens: lens.to_string(),
            case,
            value: f64::NAN,
            limit: 0.0,
            pass: false,
            note: why,
        }
    }
}

/// How much of the suite to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SuiteOptions {
    /// The quick subset (fewer angles, smaller frames, fewer Monte-Carlo rays): for CI.
    pub quick: bool,
    /// Width of the frames the ghosts are rendered into (height by the film's aspect).
    pub width: usize,
    /// Run the synthetic lenses' checks ([`synthetic`]) after the lenses'.
    pub synthetic: bool,
}

impl SuiteOptions {
    pub fn quick() -> SuiteOptions {
        SuiteOptions {
            quick: true,
            width: 160,
            synthetic: true,
        }
    }

    pub fn full() -> SuiteOptions {
        SuiteOptions {
            quick: false,
            width: 320,
            synthetic: true,
        }
    }
}

/// A frame `width` pixels across the lens's film.
pub fn frame_of(system: &LensSystem, width: usize) -> Frame {
    let height = ((width as f64 * system.film_height_mm / system.film_width_mm).round() as usize)
        .clamp(1, 4 * width);
    Frame {
        width,
        height,
        film_width_mm: system.film_width_mm,
        film_height_mm: system.film_height_mm,
    }
}

/// Non-finite channel values in `img`.
pub fn non_finite(img: &HdrImage) -> usize {
    img.pixels
        .iter()
        .flatten()
        .filter(|v| !v.is_finite())
        .count()
}

/// Relative RMSE and energy error of `a` against `b`; both 0 when `b` is black and `a` too.
pub fn difference(a: &HdrImage, b: &HdrImage) -> (f64, f64) {
    let energy = |img: &HdrImage| img.sum().iter().sum::<f64>();
    if energy(b) == 0.0 && energy(a) == 0.0 {
        return (0.0, 0.0);
    }
    match a.compare(b) {
        Ok(c) => (c.relative_rmse, c.energy_error),
        Err(_) => (f64::NAN, f64::NAN),
    }
}

/// The ghosts of one light (θ, φ in degrees) at the default preset, traced in f32 and in f64.
#[derive(Debug)]
pub struct PrecisionPair {
    pub f32_image: HdrImage,
    pub f64_image: HdrImage,
    /// Ghosts drawn.
    pub ghosts: usize,
    /// The flux the f64 render's ghosts carry before the frame crops them (image units).
    pub f64_flux: f64,
}

/// Renders the ghosts of a light at `theta_deg`, `phi_deg` through `aperture` in f32 and in
/// f64 (the same plan), every triangle with exact coverage: the renderer point-samples its
/// large triangles, and a pixel centre within a hair of an edge shared by two triangles of
/// different brightness takes either one's shade as a rounding moves the edge, so the
/// sampled images' difference would measure where pixel centres fall, not the trace.
pub fn render_pair(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    theta_deg: f64,
    phi_deg: f64,
    options: &PlanOptions<'_>,
) -> Result<PrecisionPair, String> {
    let light = LightSpec {
        theta_deg,
        phi_deg,
        ..LightSpec::parse("0,0").expect("a valid light")
    };
    let plans = plan(system, &[light], &frame, options).map_err(|e| format!("plan: {e}"))?;
    let render = |trace_f64| {
        render_with(
            system,
            aperture,
            frame,
            &plans,
            RenderOptions {
                trace_f64,
                exact_coverage: true,
                ..Default::default()
            },
        )
        .map_err(|e| format!("render: {e}"))
    };
    let (f32_image, _) = render(false)?;
    let (f64_image, stats) = render(true)?;
    Ok(PrecisionPair {
        f32_image,
        f64_image,
        ghosts: plans.iter().map(|p| p.ghosts.len()).sum(),
        f64_flux: stats.iter().flatten().map(|g| g.flux).sum(),
    })
}

/// The default preset's plan options.
pub fn default_plan() -> PlanOptions<'static> {
    PlanOptions::for_quality(Quality::Default, None)
}

/// The findings of the f32/f64 pair of one case: non-finite values in either image, and the
/// f32 image's relative RMSE and energy error against the f64 one.
pub fn precision_findings(lens: &str, case: &str, pair: &PrecisionPair) -> Vec<Finding> {
    let bad = non_finite(&pair.f32_image) + non_finite(&pair.f64_image);
    let (rmse, energy) = difference(&pair.f32_image, &pair.f64_image);
    let drawn = format!("{} ghosts drawn", pair.ghosts);
    vec![
        Finding::measured(
            "non-finite",
            lens,
            case.to_string(),
            bad as f64,
            0.0,
            format!("NaN/Inf values in the f32 and f64 images; {drawn}"),
        ),
        Finding::measured(
            "f32-vs-f64",
            lens,
            case.to_string(),
            rmse,
            F32_RMSE_LIMIT,
            format!("relative RMSE of the f32 image against the f64 one; {drawn}"),
        ),
        Finding::measured(
            "f32-vs-f64-energy",
            lens,
            case.to_string(),
            energy.abs(),
            F32_ENERGY_LIMIT,
            "|energy error| of the f32 image against the f64 one".to_string(),
        ),
    ]
}

/// Relative RMSE an f32 image may differ from the f64 one by (drawn with exact coverage,
/// [`render_pair`]). On the 19 lenses of the full suite the two agree to 5.2e-4 at most; on
/// the 338 bundled lenses in the quick suite's 160-pixel frames, to 2.7e-3 (the Samyang 135 mm
/// f/2 at 10.8°): the largest differences come from grid vertices that pass an aperture's rim
/// in one precision and not in the other. (Lights beyond
/// `ghost_raytrace::ghosts::F64_ABOVE_DEG` are traced in f64 either way.)
pub const F32_RMSE_LIMIT: f64 = 5e-3;
/// |Energy error| an f32 image may differ from the f64 one by.
pub const F32_ENERGY_LIMIT: f64 = 2e-4;

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityReport {
    pub quick: bool,
    pub findings: Vec<Finding>,
    pub failed: usize,
    pub seconds: f64,
}

/// Runs the suite on `lenses` (name and system) and the synthetic cases: each lens's field and
/// stop checks and the synthetic lenses are independent jobs, run in parallel (a job's own
/// renders are parallel too); the findings come in the same order whatever the threads.
pub fn run(
    lenses: &[(String, LensSystem)],
    options: SuiteOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> StabilityReport {
    use rayon::prelude::*;

    enum Job {
        Field(usize),
        Stops(usize),
        Synthetic,
    }
    let start = std::time::Instant::now();
    let mut jobs: Vec<Job> = (0..lenses.len())
        .flat_map(|i| [Job::Field(i), Job::Stops(i)])
        .collect();
    if options.synthetic {
        jobs.push(Job::Synthetic);
    }
    let findings: Vec<Finding> = jobs
        .par_iter()
        .map(|job| match *job {
            Job::Field(i) => {
                let (name, system) = &lenses[i];
                progress(&format!("{name}: field"));
                field::check_lens(name, system, options)
            }
            Job::Stops(i) => {
                let (name, system) = &lenses[i];
                progress(&format!("{name}: stops"));
                stops::check_lens(name, system, options)
            }
            Job::Synthetic => {
                progress("synthetic lenses");
                synthetic::check_all(options)
            }
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect();
    let failed = findings.iter().filter(|f| !f.pass).count();
    StabilityReport {
        quick: options.quick,
        findings,
        failed,
        seconds: start.elapsed().as_secs_f64(),
    }
}

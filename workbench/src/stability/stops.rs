//! A lens at extreme f-numbers: its stop opened to twice its clear semi-diameter (the other
//! elements' rims then vignette the beam) and closed to f/64 (a pupil a few tenths of a
//! millimetre across on a short lens).
//!
//! At each, the ghosts of a light 5° off axis in f32 and f64 (NaN/Inf, f32 against f64), and
//! at f/64 the direct flux on the axis against the paraxial pupil's area `π (D_EP / 2)²`: so
//! small a pupil is free of aberration and vignetting, and both the renderer's flux (the
//! bounds search's, every ghost's energy share is measured against it) and the independent
//! Monte-Carlo estimate must find it.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds::reference_flux;
use flarebench_sdk::ghost::monte_carlo::{McSettings, path_flux};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::{InterfaceTableSet, Sequence};

use super::{Finding, SuiteOptions, default_plan, frame_of, precision_findings, render_pair};

/// The small f-number's stop.
pub const SMALL_STOP_F_NUMBER: f64 = 64.0;
/// How far the stop is opened past its clear semi-diameter.
pub const OVER_OPEN: f64 = 2.0;
/// The light's angle for the renders (degrees).
const LIGHT_DEG: f64 = 5.0;
/// The direct flux at f/64 against the paraxial pupil's area (relative): the bounds search
/// integrates over a 65² grid with the pupil's edge placed between vertices (measured within
/// 0.1%). The Monte-Carlo estimate is held to this plus [`PUPIL_MC_SIGMAS`] of its own
/// standard error.
pub const PUPIL_FLUX_LIMIT: f64 = 5e-3;
/// Standard errors the Monte-Carlo pupil flux may lie from the analytic one beyond
/// [`PUPIL_FLUX_LIMIT`]. Its error is about 0.1% where the pilot grid zooms onto the pupil;
/// where a fold at the front element's rim (rays there swing across the stop before total
/// internal reflection stops them) keeps active pilot cells far from the axis, the pilot
/// cannot zoom and the pupil gets a few of the cells the rays are spread over: 1.4% and 4.6%
/// (the Viltrox 33 mm f/1.4, the Hasselblad HC 50 mm), whose estimates lay 1.3 and 0.12
/// standard errors from the analytic flux. An unbiased estimate from 16 batches lies beyond 3
/// standard errors in about 1% of lenses (Student's t, 15 degrees of freedom); a flux error the estimate's own noise hides is not one it can
/// show, and the note gives the error, so a weak check reads as one.
pub const PUPIL_MC_SIGMAS: f64 = 3.0;
/// Monte-Carlo rays for the pupil flux (quick suite; the full one traces four times as many).
const PUPIL_MC_RAYS: usize = 1 << 16;
/// The wavelength the fluxes are measured at (nm).
const FLUX_NM: f64 = 550.0;

/// The lens with its stop's clear semi-diameter scaled by `factor` and no f-number set.
fn opened(system: &LensSystem, factor: f64) -> LensSystem {
    let mut s = system.clone();
    if let Some(stop) = s.stop_index() {
        s.surfaces[stop].semi_diameter *= factor;
    }
    s.f_number = None;
    s
}

/// The lens stopped down to f/`n` (the stop's opening set from the paraxial focal length).
fn stopped(system: &LensSystem, n: f64) -> LensSystem {
    let mut s = system.clone();
    s.f_number = Some(n);
    s
}

/// The stop findings of `system`.
pub fn check_lens(name: &str, system: &LensSystem, options: SuiteOptions) -> Vec<Finding> {
    let mut out = Vec::new();
    let frame = frame_of(system, options.width);
    let plan = default_plan();
    let small = stopped(system, SMALL_STOP_F_NUMBER);
    let cases = [
        (format!("stop ×{OVER_OPEN}"), opened(system, OVER_OPEN)),
        (format!("f/{SMALL_STOP_F_NUMBER}"), small.clone()),
    ];
    for (case, lens) in &cases {
        let case = format!("{case}, θ {LIGHT_DEG}°");
        match render_pair(lens, &Aperture::Circular, frame, LIGHT_DEG, 30.0, &plan) {
            Ok(pair) => out.extend(precision_findings(name, &case, &pair)),
            Err(e) => out.push(Finding::failed("non-finite", name, case, e)),
        }
    }
    // The direct flux through the small pupil on the axis.
    let case = format!("f/{SMALL_STOP_F_NUMBER}, on axis");
    let para = match analyse(&small, FLUX_NM) {
        Ok(p) => p,
        Err(e) => {
            out.push(Finding::failed("pupil-flux", name, case, e.to_string()));
            return out;
        }
    };
    if para.stop_semi_diameter_mm >= para.stop_full_semi_diameter_mm {
        // The stop is not closed down (the lens is slower than f/64 wide open): nothing to
        // measure.
        return out;
    }
    let area = std::f64::consts::PI * (0.5 * para.entrance_pupil_diameter_mm).powi(2);
    let tables = InterfaceTableSet::for_system(&small, FLUX_NM);
    let bounds = reference_flux(&small, &tables, &mut GridTrace::default());
    // Fresnel/coating losses: the flux through the pupil is its area times the axial ray's
    // transmittance, which the same tracer gives for a ray at the pupil's centre.
    let seq = Sequence::forward(&small, FLUX_NM);
    let axial = seq.trace(&flarebench_sdk::trace::Ray::collimated(0.0, 0.0, 0.0));
    let transmittance = if axial.completed {
        axial.throughput
    } else {
        f64::NAN
    };
    let want = area * transmittance;
    out.push(Finding::measured(
        "pupil-flux",
        name,
        case.clone(),
        (bounds / want - 1.0).abs(),
        PUPIL_FLUX_LIMIT,
        format!(
            "the renderer's direct flux {bounds:.4e} mm² against π (D_EP/2)² × T = {want:.4e} \
             (D_EP {:.4} mm, T {transmittance:.4})",
            para.entrance_pupil_diameter_mm
        ),
    ));
    let rays = if options.quick {
        PUPIL_MC_RAYS
    } else {
        4 * PUPIL_MC_RAYS
    };
    let mc = path_flux(
        &small,
        &seq,
        0.0,
        &McSettings {
            rays,
            ..McSettings::default()
        },
    );
    let sigma = (mc.std_error / want).abs();
    out.push(Finding::measured(
        "pupil-flux-mc",
        name,
        case,
        (mc.mean / want - 1.0).abs(),
        PUPIL_FLUX_LIMIT + PUPIL_MC_SIGMAS * sigma,
        format!(
            "the Monte-Carlo direct flux {:.4e} ± {:.1e} mm² against π (D_EP/2)² × T (limit \
             {PUPIL_FLUX_LIMIT} + {PUPIL_MC_SIGMAS} × its relative standard error {sigma:.1e})",
            mc.mean, mc.std_error
        ),
    ));
    out
}

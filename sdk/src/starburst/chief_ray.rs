//! [`chief_ray_landing`]: where a light at infinity images on the sensor — the landing point
//! of its chief ray, the ray through the centre of the aperture stop.
//!
//! The ray is traced in the meridional plane (light in the y–z plane, as the ghost grids are)
//! and its landing rotated by the light's azimuth φ, `(x, y) → (x cos φ − y sin φ,
//! x sin φ + y cos φ)`, exactly as the ghost renderer turns its meshes, so a starburst lands
//! where the ghosts' frame puts the light. Its height on the front vertex plane starts at the
//! paraxial entrance pupil, `h = −z_EP tan θ`, and is refined by the secant method until the
//! ray crosses the stop within 1e-9 mm of the axis (real pupils are aberrated).
//!
//! Far off axis a wide-angle lens's real entrance pupil has moved well away from the paraxial
//! one (a fisheye's at 60° lies millimetres off the paraxial guess), and the secant method's
//! start may be vignetted before it reaches the stop. Then heights across the whole entrance
//! ([`crate::ghost::bounds::entrance_search_rect`]) are sampled, and the pairs of neighbours
//! whose stop crossings lie on either side of the axis are bisected, those whose rays reach
//! the sensor first: the first bisection that closes on a crossing of the axis (not on a
//! jump across it, where rays fold back at a rim) gives the chief ray.

use crate::paraxial::{ParaxialError, analyse};
use crate::system::LensSystem;
use crate::trace::{Fate, Ray, Sequence};

/// Why the chief ray could not be found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChiefRayError {
    #[error("paraxial analysis: {0}")]
    Paraxial(#[from] ParaxialError),
    #[error("the chief ray at {theta_deg}° does not reach the sensor ({fate:?})")]
    Lost { theta_deg: f64, fate: Fate },
    #[error("the chief ray at {theta_deg}° could not be aimed through the stop's centre")]
    NoConvergence { theta_deg: f64 },
}

/// Crossing of the stop within this distance of the axis (mm) ends the search.
const STOP_TOLERANCE_MM: f64 = 1e-9;

/// The chief ray's landing point on the sensor (mm, lens frame) for a light at `theta` from
/// the axis and azimuth `phi` (radians), traced at `lambda_nm`.
pub fn chief_ray_landing(
    system: &LensSystem,
    lambda_nm: f64,
    theta: f64,
    phi: f64,
) -> Result<[f64; 2], ChiefRayError> {
    let para = analyse(system, lambda_nm)?;
    let stop = system.stop_index().ok_or(ParaxialError::NoStop)?;
    let seq = Sequence::forward(system, lambda_nm);
    let theta_deg = theta.to_degrees();
    let mut hits = Vec::new();
    // Stop-plane height of the ray entering at height h, and its sensor landing.
    let mut shoot = |h: f64| -> Result<(f64, [f64; 2]), ChiefRayError> {
        hits.clear();
        let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
        let at_stop = hits.iter().find(|hit| hit.surface == stop);
        match (r.completed, at_stop) {
            (true, Some(hit)) => Ok((hit.position.y, [r.ray.origin.x, r.ray.origin.y])),
            _ => Err(ChiefRayError::Lost {
                theta_deg,
                fate: r.fate,
            }),
        }
    };
    let turn = |[x, y]: [f64; 2]| {
        let (s, c) = phi.sin_cos();
        [x * c - y * s, x * s + y * c]
    };
    let h0 = -para.entrance_pupil_z_mm * theta.tan();
    let step = 1e-3 * para.entrance_pupil_diameter_mm.max(1e-3);
    let secant = secant_from(&mut shoot, h0, step, theta_deg);
    if let Ok(land) = secant {
        return Ok(turn(land));
    }
    // The paraxial start is lost or the secant method wandered: bracket the chief ray among
    // heights across the entrance and bisect.
    let half = crate::ghost::bounds::entrance_search_rect(system, theta).y1;
    let heights: Vec<f64> = (0..=BRACKET_SAMPLES)
        .map(|k| -half + 2.0 * half * k as f64 / BRACKET_SAMPLES as f64)
        .collect();
    let samples: Vec<Option<(f64, Fate)>> = heights
        .iter()
        .map(|&h| {
            hits.clear();
            let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
            let y = hits.iter().find(|hit| hit.surface == stop)?.position.y;
            Some((y, if r.completed { r.fate } else { STOPPED }))
        })
        .collect();
    // Every pair of neighbouring heights whose stop crossings lie on either side of the axis,
    // best first: both rays reaching the sensor unvignetted, then both completing, then the
    // rest, each group nearest the paraxial start first. A stop crossing can change sign
    // without passing the axis — where the rays fold back at a rim or a total internal
    // reflection sets in (the M.Zuiko 8 mm fisheye at 70°: +16.4 mm to −16.4 mm between two
    // rays outside its front element) —, so each bracket is bisected, and the first that
    // closes on a crossing of the axis by a ray that completes is the chief ray.
    let rank = |f: Fate| match f {
        Fate::Sensor => 0,
        f if f != STOPPED => 1,
        _ => 2,
    };
    let mut brackets: Vec<(usize, f64, usize)> = (0..BRACKET_SAMPLES)
        .filter_map(|k| match (samples[k], samples[k + 1]) {
            (Some((a, fa)), Some((b, fb))) if a.signum() != b.signum() || a == 0.0 => {
                let mid = 0.5 * (heights[k] + heights[k + 1]);
                Some((rank(fa).max(rank(fb)), (mid - h0).abs(), k))
            }
            _ => None,
        })
        .collect();
    brackets.sort_by(|a, b| (a.0, a.1).partial_cmp(&(b.0, b.1)).expect("finite heights"));
    for &(_, _, k) in &brackets {
        let y_lo = samples[k].expect("a bracket's rays cross the stop").0;
        if let Some(h) = bisect(&seq, stop, theta, heights[k], y_lo, heights[k + 1]) {
            let r = seq.trace(&Ray::collimated(theta, 0.0, h));
            if r.completed {
                return Ok(turn([r.ray.origin.x, r.ray.origin.y]));
            }
        }
    }
    secant.map(turn)
}

/// The fate recorded for a ray that stopped (missed a surface, total internal reflection)
/// when ranking brackets: only its rank matters.
const STOPPED: Fate = Fate::Missed {
    surface: usize::MAX,
};

/// Bisection on the stop-crossing height between entrance heights `lo` (crossing at `y_lo`)
/// and `hi` (crossing on the other side of the axis): the height whose ray crosses the stop
/// within [`CONVERGED_MM`] of the axis, or `None` when a ray misses the stop or the crossing
/// jumps across the axis instead of passing through it.
fn bisect(
    seq: &Sequence<f64>,
    stop: usize,
    theta: f64,
    mut lo: f64,
    mut y_lo: f64,
    mut hi: f64,
) -> Option<f64> {
    let mut hits = Vec::new();
    let mut crossing = |h: f64| {
        hits.clear();
        seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
        hits.iter()
            .find(|hit| hit.surface == stop)
            .map(|hit| hit.position.y)
    };
    if y_lo.abs() <= STOP_TOLERANCE_MM {
        return Some(lo);
    }
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        let y = crossing(mid)?;
        if y.abs() <= STOP_TOLERANCE_MM {
            return Some(mid);
        }
        if y.signum() == y_lo.signum() {
            (lo, y_lo) = (mid, y);
        } else {
            hi = mid;
        }
    }
    (y_lo.abs() <= CONVERGED_MM).then_some(lo)
}

/// A bisection that ends with the crossing farther than this from the axis (mm) closed on a
/// jump, not a crossing: after [`BISECTIONS`] halvings of a bracket at most the entrance's
/// width, a crossing that passes through the axis is within its slope × 2⁻⁶⁰ × that width
/// of it, far below this.
const CONVERGED_MM: f64 = 1e-6;

/// Heights sampled across the entrance when the secant method cannot start.
const BRACKET_SAMPLES: usize = 256;
/// Bisection steps: each halves the bracket (from at most the entrance's width, 2⁻⁶⁰ of it is
/// far below [`STOP_TOLERANCE_MM`]).
const BISECTIONS: usize = 60;

/// The secant method on the stop-crossing height from entrance height `h0` (next `h0 + step`):
/// the landing point once the crossing is within [`STOP_TOLERANCE_MM`] of the axis.
fn secant_from(
    shoot: &mut impl FnMut(f64) -> Result<(f64, [f64; 2]), ChiefRayError>,
    mut h0: f64,
    step: f64,
    theta_deg: f64,
) -> Result<[f64; 2], ChiefRayError> {
    let (mut y0, mut land) = shoot(h0)?;
    let mut h1 = h0 + step;
    for _ in 0..50 {
        if y0.abs() <= STOP_TOLERANCE_MM {
            return Ok(land);
        }
        let (y1, land1) = shoot(h1)?;
        let slope = (y1 - y0) / (h1 - h0);
        if slope == 0.0 || !slope.is_finite() {
            break;
        }
        let h2 = h1 - y1 / slope;
        (h0, y0, land) = (h1, y1, land1);
        h1 = h2;
    }
    Err(ChiefRayError::NoConvergence { theta_deg })
}

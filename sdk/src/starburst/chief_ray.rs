//! [`chief_ray_landing`]: where a light at infinity images on the sensor — the landing point
//! of its chief ray, the ray through the centre of the aperture stop.
//!
//! The ray is traced in the meridional plane (light in the y–z plane, as the ghost grids are)
//! and its landing rotated by the light's azimuth φ, `(x, y) → (x cos φ − y sin φ,
//! x sin φ + y cos φ)`, exactly as the ghost renderer turns its meshes, so a starburst lands
//! where the ghosts' frame puts the light. Its height on the front vertex plane starts at the
//! paraxial entrance pupil, `h = −z_EP tan θ`, and is refined by the secant method until the
//! ray crosses the stop within 1e-9 mm of the axis (real pupils are aberrated).

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
    let mut h0 = -para.entrance_pupil_z_mm * theta.tan();
    let (mut y0, mut land) = shoot(h0)?;
    let mut h1 = h0 + 1e-3 * para.entrance_pupil_diameter_mm.max(1e-3);
    for _ in 0..50 {
        if y0.abs() <= STOP_TOLERANCE_MM {
            let (s, c) = phi.sin_cos();
            return Ok([land[0] * c - land[1] * s, land[0] * s + land[1] * c]);
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

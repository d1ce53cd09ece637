//! First-order (paraxial) analysis with 2×2 ray-transfer matrices in (y, n·u) form.
//!
//! Refraction at a surface of curvature c from n to n′ is `[[1, 0], [−c(n′−n), 1]]`, transfer by
//! t in a medium n is `[[1, t/n], [0, 1]]`. From the matrix `[[A, B], [C, D]]` of the surfaces
//! in front of the sensor: EFL = −1/C, BFL = −n′A/C (from the last vertex), front focal point at
//! n·D/C from the first vertex. The entrance pupil is the stop seen through the front group,
//! the exit pupil the stop seen through the rear group.

use serde::Serialize;

use crate::spectrum::LAMBDA_D_NM;
use crate::system::{LensSystem, SurfaceKind};

/// A 2×2 ray-transfer matrix acting on (y, n·u).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Abcd {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
}

impl Abcd {
    pub const IDENTITY: Abcd = Abcd {
        a: 1.0,
        b: 0.0,
        c: 0.0,
        d: 1.0,
    };

    /// Refraction by a surface of power `phi = c (n′ − n)`.
    pub fn refraction(phi: f64) -> Abcd {
        Abcd {
            a: 1.0,
            b: 0.0,
            c: -phi,
            d: 1.0,
        }
    }

    /// Transfer over `t` mm in a medium of index `n`.
    pub fn transfer(t: f64, n: f64) -> Abcd {
        Abcd {
            a: 1.0,
            b: t / n,
            c: 0.0,
            d: 1.0,
        }
    }

    /// `self` followed by `next` (the matrix product next · self).
    pub fn then(self, next: Abcd) -> Abcd {
        Abcd {
            a: next.a * self.a + next.b * self.c,
            b: next.a * self.b + next.b * self.d,
            c: next.c * self.a + next.d * self.c,
            d: next.c * self.b + next.d * self.d,
        }
    }

    /// Applies the matrix to a ray (y, n·u).
    pub fn apply(self, y: f64, nu: f64) -> (f64, f64) {
        (self.a * y + self.b * nu, self.c * y + self.d * nu)
    }
}

/// Why the analysis could not be done.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParaxialError {
    #[error("the system has no aperture stop")]
    NoStop,
    #[error("the system is afocal (zero power): it has no focal length")]
    Afocal,
}

/// First-order data of a lens at one wavelength, object at infinity. Lengths in mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ParaxialData {
    pub wavelength_nm: f64,
    /// Effective focal length 1/Φ.
    pub efl_mm: f64,
    /// Back focal distance: last vertex to the rear focal point.
    pub bfl_mm: f64,
    /// Front focal distance: from the front focal point to the first vertex (positive when
    /// the focal point lies in front of the lens).
    pub ffl_mm: f64,
    /// Entrance pupil: position from the first vertex (positive toward the sensor) and diameter,
    /// at the working stop opening.
    pub entrance_pupil_z_mm: f64,
    pub entrance_pupil_diameter_mm: f64,
    /// Exit pupil: position from the last vertex before the sensor, and diameter.
    pub exit_pupil_z_mm: f64,
    pub exit_pupil_diameter_mm: f64,
    /// Paraxial f-number EFL/EPD at the working stop opening (equal to the working f-number
    /// 1/(2 n′ u′) for an object at infinity).
    pub f_number: f64,
    /// The f-number with the stop wide open.
    pub open_f_number: f64,
    /// The stop's working semi-diameter (after the f-number setting) and its full one.
    pub stop_semi_diameter_mm: f64,
    pub stop_full_semi_diameter_mm: f64,
    /// Front vertex to sensor.
    pub total_track_mm: f64,
    /// Sensor distance from the paraxial focus (positive: sensor behind focus).
    pub focus_error_mm: f64,
    /// Petzval sum Σ φ/(n n′) (1/mm).
    pub petzval_sum: f64,
}

/// Matrices of the surfaces in front of the sensor, split at the stop: the front group maps
/// the first vertex to the stop plane, the rear group the stop plane to the last vertex.
fn groups(system: &LensSystem, lambda_nm: f64) -> Option<(Abcd, Abcd, f64)> {
    let stop = system.stop_index()?;
    let n = system.indices(lambda_nm);
    let last = system.sensor_index().checked_sub(1)?;
    let mut front = Abcd::IDENTITY;
    let mut rear = Abcd::IDENTITY;
    let mut petzval = 0.0;
    for (i, s) in system.surfaces[..=last].iter().enumerate() {
        let phi = s.curvature * (n[i + 1] - n[i]);
        petzval += phi / (n[i] * n[i + 1]);
        let m = Abcd::refraction(phi);
        let t = Abcd::transfer(s.thickness, n[i + 1]);
        if i < stop {
            front = front.then(m).then(t);
        } else {
            rear = rear.then(m);
            if i < last {
                rear = rear.then(t);
            }
        }
    }
    Some((front, rear, petzval))
}

/// The stop's working semi-diameter: its full semi-diameter, closed down so that the paraxial
/// f-number at the d line is at least the system's `f_number` setting.
pub fn stop_opening(system: &LensSystem) -> f64 {
    let Some(stop) = system.stop_index() else {
        return 0.0;
    };
    let full = system.surfaces[stop].semi_diameter;
    let (Some(n_set), Some((front, rear, _))) = (system.f_number, groups(system, LAMBDA_D_NM))
    else {
        return full;
    };
    let total = front.then(rear);
    if total.c == 0.0 || front.a == 0.0 {
        return full;
    }
    let efl = (1.0 / total.c).abs();
    let needed = efl / (2.0 * n_set) * front.a.abs();
    full.min(needed)
}

/// First-order analysis at `lambda_nm`.
pub fn analyse(system: &LensSystem, lambda_nm: f64) -> Result<ParaxialData, ParaxialError> {
    let stop = system.stop_index().ok_or(ParaxialError::NoStop)?;
    let (front, rear, petzval) = groups(system, lambda_nm).ok_or(ParaxialError::NoStop)?;
    let m = front.then(rear);
    if m.c == 0.0 || !m.c.is_finite() {
        return Err(ParaxialError::Afocal);
    }
    let n = system.indices(lambda_nm);
    let n_obj = n[0];
    let n_img = n[system.sensor_index()];
    let efl = -1.0 / m.c;
    let bfl = -n_img * m.a / m.c;
    let ffl = -n_obj * m.d / m.c;
    let full = system.surfaces[stop].semi_diameter;
    let opening = stop_opening(system);
    let epd = 2.0 * opening / front.a.abs();
    let open_epd = 2.0 * full / front.a.abs();
    let last_z = system.vertex_z()[system.sensor_index() - 1];
    let total_track = system.total_track();
    debug_assert_eq!(system.surfaces[stop].kind, SurfaceKind::ApertureStop);
    Ok(ParaxialData {
        wavelength_nm: lambda_nm,
        efl_mm: efl,
        bfl_mm: bfl,
        ffl_mm: ffl,
        entrance_pupil_z_mm: n_obj * front.b / front.a,
        entrance_pupil_diameter_mm: epd,
        exit_pupil_z_mm: -n_img * rear.b / rear.d,
        exit_pupil_diameter_mm: 2.0 * opening / rear.d.abs(),
        f_number: efl.abs() / epd,
        open_f_number: efl.abs() / open_epd,
        stop_semi_diameter_mm: opening,
        stop_full_semi_diameter_mm: full,
        total_track_mm: total_track,
        focus_error_mm: total_track - (last_z + bfl),
        petzval_sum: petzval,
    })
}

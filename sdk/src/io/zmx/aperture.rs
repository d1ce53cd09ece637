//! Sizing what a `.zmx` file leaves to Zemax, by paraxial ray tracing at the primary
//! wavelength: the stop's semi-diameter from the system aperture (`ENPD`, `FNUM`, `OBNA`), and
//! the semi-diameters of surfaces the file gives none for, from the marginal and chief ray
//! heights at the largest field.
//!
//! Rays are traced in (y, n·u): refraction `nu' = nu − y·c·(n' − n)`, transfer
//! `y' = y + t·nu'/n'`. The marginal ray of an object at infinity is `a` (y = 1, u = 0 at the
//! first vertex) scaled to the stop; the chief ray is `u0·(b − a·b_stop/a_stop)` with `b`
//! (y = 0, u = 1), which crosses the axis at the stop.

use crate::io::LensFileError;
use crate::io::located::Reporter;
use crate::paraxial::analyse;
use crate::system::LensSystem;

use super::header::{Aperture, FieldKind, MaxField};

/// Margin on derived semi-diameters over the paraxial marginal + chief heights, for the real
/// rays' aberrations (as `lenses/sources/convert.py` does for the library).
pub(super) const DERIVED_MARGIN: f64 = 1.05;

/// Largest field angle used to size apertures; paraxial chief rays at 90° are infinite.
const MAX_FIELD_DEG: f64 = 89.0;

/// Heights of a paraxial ray at every surface before the sensor.
fn heights(system: &LensSystem, lambda_nm: f64, y0: f64, u0: f64) -> Vec<f64> {
    let n = system.indices(lambda_nm);
    let last = system.sensor_index();
    let (mut y, mut nu) = (y0, u0 * n[0]);
    let mut out = Vec::with_capacity(last);
    for (i, s) in system.surfaces[..last].iter().enumerate() {
        out.push(y);
        nu -= y * s.curvature * (n[i + 1] - n[i]);
        y += s.thickness * nu / n[i + 1];
    }
    out
}

/// What the file says about the aperture and the object.
#[derive(Clone, Copy, Debug)]
pub(super) struct ApertureSpec {
    pub aperture: Aperture,
    /// Byte offset of the aperture value (for errors).
    pub pos: usize,
    /// Object distance in front of the first surface (mm) when finite.
    pub object_distance: Option<f64>,
    /// The stop surface's own semi-diameter (mm), for float-by-stop-size.
    pub stop_semi: Option<f64>,
}

/// Sets the stop's semi-diameter; returns a note saying how.
pub(super) fn size_stop(
    ctx: &Reporter<'_>,
    system: &mut LensSystem,
    stop: usize,
    lambda_nm: f64,
    spec: &ApertureSpec,
) -> Result<String, LensFileError> {
    let a = heights(system, lambda_nm, 1.0, 0.0);
    let a_stop = a[stop].abs();
    let field = match spec.aperture {
        Aperture::EntrancePupil(_) => "ENPD",
        Aperture::FNumber(_) => "FNUM",
        Aperture::ObjectNa(_) => "OBNA",
        Aperture::FloatByStop => "DIAM",
    };
    if !(a_stop > 0.0 && a_stop.is_finite()) {
        return Err(ctx.error(
            spec.pos,
            field,
            "a ray parallel to the axis crosses the axis at the stop: the stop cannot be sized",
        ));
    }
    let (sd, note) = match spec.aperture {
        Aperture::EntrancePupil(epd) => (
            epd / 2.0 * a_stop,
            format!("the entrance pupil diameter ENPD {epd} mm"),
        ),
        Aperture::FNumber(f) => {
            let efl = analyse(system, lambda_nm)
                .map_err(|e| ctx.error(spec.pos, field, e.to_string()))?
                .efl_mm;
            (
                efl.abs() / f / 2.0 * a_stop,
                format!(
                    "the f-number FNUM {f} (entrance pupil diameter EFL/FNUM = {:.6} mm)",
                    efl.abs() / f
                ),
            )
        }
        Aperture::ObjectNa(na) => {
            let Some(d) = spec.object_distance else {
                return Err(ctx.error(
                    spec.pos,
                    field,
                    "an object-space numerical aperture needs an object at a finite distance; \
                     this file's object is at infinity",
                ));
            };
            // The marginal ray leaves the axial object point at the real angle asin(NA);
            // its paraxial slope is the tangent of that angle.
            let u = na.asin().tan();
            let y = heights(system, lambda_nm, d * u, u)[stop].abs();
            (
                y,
                format!(
                    "the object-space numerical aperture OBNA {na} with the object {d} mm in \
                     front of the first surface (paraxial marginal ray of slope tan(asin NA))"
                ),
            )
        }
        Aperture::FloatByStop => match spec.stop_semi {
            Some(sd) => (
                sd,
                "the stop surface's own semi-diameter (float by stop size)".into(),
            ),
            None => {
                return Err(ctx.error(
                    spec.pos,
                    "DIAM",
                    "no system aperture (ENPD, FNUM or OBNA) and no semi-diameter on the stop \
                     surface: the stop cannot be sized",
                ));
            }
        },
    };
    if !(sd.is_finite() && sd > 0.0) {
        return Err(ctx.error(
            spec.pos,
            field,
            format!("the stop semi-diameter comes out as {sd} mm"),
        ));
    }
    system.surfaces[stop].semi_diameter = sd;
    Ok(format!(
        "The stop semi-diameter, {sd:.6} mm, is set from {note}, traced paraxially at \
         {lambda_nm} nm."
    ))
}

/// The object-space chief ray slope at the largest field, and a note when it is approximated.
fn chief_slope(
    ctx: &mut Reporter<'_>,
    system: &LensSystem,
    lambda_nm: f64,
    field: &MaxField,
    object_distance: Option<f64>,
) -> f64 {
    let p = analyse(system, lambda_nm).ok();
    match field.kind {
        FieldKind::Angle => {
            let deg = field.value.min(MAX_FIELD_DEG);
            if field.value > MAX_FIELD_DEG {
                ctx.warn(
                    field.pos,
                    format!(
                        "the largest field, {}°, is beyond what paraxial rays describe; \
                         semi-diameters are derived at {MAX_FIELD_DEG}°",
                        field.value
                    ),
                );
            }
            deg.to_radians().tan()
        }
        FieldKind::ParaxialImageHeight | FieldKind::RealImageHeight => {
            if field.kind == FieldKind::RealImageHeight {
                ctx.warn(
                    field.pos,
                    "the fields are real image heights; semi-diameters are derived as if they \
                     were paraxial image heights",
                );
            }
            p.map_or(0.0, |p| field.value / p.efl_mm.abs())
        }
        FieldKind::ObjectHeight => match (object_distance, p) {
            (Some(d), Some(p)) => field.value / (d + p.entrance_pupil_z_mm).abs(),
            _ => {
                ctx.warn(
                    field.pos,
                    "the fields are object heights but the object is at infinity; \
                     semi-diameters are derived on axis only",
                );
                0.0
            }
        },
        FieldKind::Other(k) => {
            ctx.warn(
                field.pos,
                format!("field type {k} is not read; semi-diameters are derived on axis only"),
            );
            0.0
        }
    }
}

/// Gives every surface in `derive` (indices; never the stop or the sensor) the semi-diameter
/// `DERIVED_MARGIN × (|marginal| + |chief|)`, limited to what the surface's shape allows.
/// Returns the note describing it.
pub(super) fn derive_semi_diameters(
    ctx: &mut Reporter<'_>,
    system: &mut LensSystem,
    (stop, lambda_nm): (usize, f64),
    derive: &[usize],
    field: Option<&MaxField>,
    object_distance: Option<f64>,
    pos: usize,
) -> Result<Option<String>, LensFileError> {
    if derive.is_empty() {
        return Ok(None);
    }
    let a = heights(system, lambda_nm, 1.0, 0.0);
    let b = heights(system, lambda_nm, 0.0, 1.0);
    let scale = system.surfaces[stop].semi_diameter / a[stop].abs();
    let u0 = field.map_or(0.0, |f| {
        chief_slope(ctx, system, lambda_nm, f, object_distance)
    });
    let ratio = b[stop] / a[stop];
    let mut limited = Vec::new();
    for &i in derive {
        let marginal = a[i] * scale;
        let chief = u0 * (b[i] - a[i] * ratio);
        let mut sd = DERIVED_MARGIN * (marginal.abs() + chief.abs());
        let s = &system.surfaces[i];
        let q = (1.0 + s.conic) * s.curvature * s.curvature;
        if q > 0.0 && sd * sd * q > 1.0 {
            sd = 0.999 / q.sqrt();
            limited.push(i);
        }
        if !(sd.is_finite() && sd > 0.0) {
            return Err(ctx.error(
                pos,
                "DIAM",
                format!("surface {i}: a derived semi-diameter comes out as {sd} mm"),
            ));
        }
        system.surfaces[i].semi_diameter = sd;
    }
    let list = |v: &[usize]| {
        v.iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !limited.is_empty() {
        ctx.warn(
            pos,
            format!(
                "derived semi-diameters of surfaces {} are limited to what the surface shape \
                 allows",
                list(&limited)
            ),
        );
    }
    let at = match field {
        Some(_) if u0 != 0.0 => format!(
            "the chief ray at the largest field ({:.6}° in object space)",
            u0.atan().to_degrees()
        ),
        _ => "no field (on axis only)".into(),
    };
    Ok(Some(format!(
        "The file gives no semi-diameter for surfaces {} (numbered as here): each is \
         {DERIVED_MARGIN} × (|paraxial marginal ray height| + |paraxial chief ray height|), \
         with {at}, at {lambda_nm} nm.",
        list(derive)
    )))
}

//! Ray fans in the meridional plane: forward fans at the standard fields and the path of one
//! ghost, each ray a polyline from a lead-in in front of the lens to where it ends.

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::{Fate, Hit, Interaction, Ray, Sequence};

use super::profile::{drawn_semi_diameter, profile};

/// Rays per fan in the default fans ([`default_fans`]; what [`super::Bounds`] covers).
pub const DEFAULT_FAN_RAYS: usize = 7;

/// The part of the entrance pupil a fan spans: its rays cross the pupil plane between
/// ±0.95 of its radius (the outermost rays just inside the stop's opening).
pub const PUPIL_FILL: f64 = 0.95;

/// The lead-in in front of the lens, as a fraction of the total track.
pub const LEAD_IN: f64 = 0.15;

/// Where and why a drawn ray ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayEnd {
    /// On the sensor plane, inside every clear aperture on the way.
    Sensor,
    /// Blocked at surface `row`: it met the surface outside its clear semi-diameter (the
    /// stop: outside its working opening).
    Vignetted { row: usize },
    /// Totally internally reflected at surface `row` (the tracer stops there); the path ends
    /// on that surface.
    TotalInternalReflection { row: usize },
    /// Found no intersection with surface `row` (its line does not meet the surface, or an
    /// even asphere's intersection did not converge); the path ends where the ray crosses
    /// that surface's vertex plane, when it does so ahead of it and not absurdly far away.
    Missed { row: usize },
}

impl RayEnd {
    /// The surface where the ray ended early, if it did.
    pub fn row(self) -> Option<usize> {
        match self {
            RayEnd::Sensor => None,
            RayEnd::Vignetted { row }
            | RayEnd::TotalInternalReflection { row }
            | RayEnd::Missed { row } => Some(row),
        }
    }
}

/// One drawn ray: points (z, y) in mm, from the lead-in through every surface it met (in the
/// order met: a ghost's path goes back and forth) to where it ends.
#[derive(Clone, Debug, PartialEq)]
pub struct RayPath {
    pub points: Vec<[f64; 2]>,
    pub end: RayEnd,
    /// How many of `points` the tracer carried out: the lead-in and every completed
    /// interaction. A ray that ended in total internal reflection or missed a surface may have
    /// one more point after them, where it met (TIR) or passed (missed) that surface.
    pub completed: usize,
}

impl RayPath {
    /// The points up to the last completed interaction, without the final segment to a
    /// surface where the ray totally internally reflected or that it missed.
    pub fn completed_points(&self) -> &[[f64; 2]] {
        &self.points[..self.completed.min(self.points.len())]
    }
}

/// The rays of one fan: one field angle (degrees, toward +y) and one wavelength (nm).
#[derive(Clone, Debug, PartialEq)]
pub struct RayFan {
    pub field_deg: f64,
    pub wavelength_nm: f64,
    pub rays: Vec<RayPath>,
}

/// The three standard fields (degrees): axial, 0.7 and full field (half the film diagonal
/// through the paraxial focal length, at the default wavelength); None without paraxial data.
pub fn standard_fields(system: &LensSystem) -> Option<[f64; 3]> {
    let p = analyse(system, system.default_wavelength_nm()).ok()?;
    let half_diagonal = 0.5 * system.film_width_mm.hypot(system.film_height_mm);
    let full = (half_diagonal / p.efl_mm.abs()).atan().to_degrees();
    full.is_finite().then_some([0.0, 0.7 * full, full])
}

/// Meridional fans of `rays` collimated rays per field and wavelength, across the entrance
/// pupil, each ray drawn from a lead-in in front of the first surface to where it ends.
///
/// Fans come field by field, each field's wavelengths in the order given. The rays are aimed
/// at the paraxial entrance pupil at each wavelength, spread over ±[`PUPIL_FILL`] of its
/// radius (bottom to top); without paraxial data, across the first surface instead. A field
/// of 90° or more, a wavelength that is not a positive number, or a system without surfaces
/// gives a fan without rays.
pub fn ray_fans(
    system: &LensSystem,
    fields_deg: &[f64],
    wavelengths_nm: &[f64],
    rays: usize,
) -> Vec<RayFan> {
    let lead = lead_in(system);
    let mut fans = Vec::with_capacity(fields_deg.len() * wavelengths_nm.len());
    for &field_deg in fields_deg {
        for &wavelength_nm in wavelengths_nm {
            let rays = if usable(field_deg, wavelength_nm) && !system.surfaces.is_empty() {
                let seq = Sequence::forward(system, wavelength_nm);
                let (ep_z, ep_r) = pupil(system, wavelength_nm);
                pupil_fan(&seq, field_deg, ep_z, ep_r, lead, rays)
            } else {
                Vec::new()
            };
            fans.push(RayFan {
                field_deg,
                wavelength_nm,
                rays,
            });
        }
    }
    fans
}

/// The fan of `ghost`'s path (through both of its reflections, so the polyline goes back and
/// forth) at one field and wavelength, aimed like [`ray_fans`]. A path the lens does not
/// have (`Sequence::ghost_path` refuses it) gives a fan without rays. Four-reflection paths
/// are drawn the same way.
pub fn ghost_fan(
    system: &LensSystem,
    ghost: GhostPath,
    field_deg: f64,
    wavelength_nm: f64,
    rays: usize,
) -> RayFan {
    let rays = match Sequence::ghost_path(system, wavelength_nm, &ghost) {
        Ok(seq) if usable(field_deg, wavelength_nm) => {
            let (ep_z, ep_r) = pupil(system, wavelength_nm);
            pupil_fan(&seq, field_deg, ep_z, ep_r, lead_in(system), rays)
        }
        _ => Vec::new(),
    };
    RayFan {
        field_deg,
        wavelength_nm,
        rays,
    }
}

/// The default fans: [`DEFAULT_FAN_RAYS`] rays at each of the [`standard_fields`] (only the
/// axis without paraxial data) at the lens's default wavelength. [`super::LensDrawing`]'s
/// bounds cover them.
pub fn default_fans(system: &LensSystem) -> Vec<RayFan> {
    let fields = standard_fields(system);
    let fields: &[f64] = match &fields {
        Some(f) => f,
        None => &[0.0],
    };
    ray_fans(
        system,
        fields,
        &[system.default_wavelength_nm()],
        DEFAULT_FAN_RAYS,
    )
}

/// How far in front of the first vertex (z = 0) rays are drawn from: [`LEAD_IN`] of the
/// total track in front of the frontmost point of any surface.
pub fn lead_in(system: &LensSystem) -> f64 {
    let front = system
        .surfaces
        .iter()
        .zip(system.vertex_z())
        .flat_map(|(s, z0)| profile(s, z0))
        .map(|p| p[0])
        .filter(|z| z.is_finite())
        .fold(0.0, f64::min);
    -front + LEAD_IN * system.total_track().max(1e-3)
}

/// `count` collimated rays at `field_deg` (toward +y) across the entrance pupil at `ep_z`
/// (mm from the first vertex) of radius `ep_r`: ray k crosses the pupil plane at height
/// `t·ep_r`, t spread evenly over ±[`PUPIL_FILL`] (t = 0 for a single ray). Each is drawn
/// from `lead` mm in front of the first vertex (see [`trace_path`]).
pub fn pupil_fan(
    seq: &Sequence<f64>,
    field_deg: f64,
    ep_z: f64,
    ep_r: f64,
    lead: f64,
    count: usize,
) -> Vec<RayPath> {
    let tan = field_deg.to_radians().tan();
    let mut hits = Vec::new();
    (0..count)
        .map(|k| {
            let t = if count > 1 {
                PUPIL_FILL * (2.0 * k as f64 / (count - 1) as f64 - 1.0)
            } else {
                0.0
            };
            // Height at z = 0 of the ray that crosses the pupil plane at t·ep_r.
            let h = t * ep_r - tan * ep_z;
            let ray = Ray::collimated(field_deg.to_radians(), 0.0, h);
            trace_into(seq, &ray, [-lead, h - tan * lead], &mut hits)
        })
        .collect()
}

/// Traces `ray` along `seq` and draws it: from `start` (a point on the ray's line where the
/// drawing begins, e.g. a lead-in in front of the lens) through every hit, up to and
/// including the first hit outside a clear aperture ([`RayEnd::Vignetted`]), the surface
/// where it totally internally reflects, the vertex plane of a surface it misses, or the
/// sensor.
pub fn trace_path(seq: &Sequence<f64>, ray: &Ray, start: [f64; 2]) -> RayPath {
    trace_into(seq, ray, start, &mut Vec::new())
}

fn trace_into(seq: &Sequence<f64>, ray: &Ray, start: [f64; 2], hits: &mut Vec<Hit>) -> RayPath {
    hits.clear();
    let result = seq.trace_with_hits(ray, hits);
    let mut points = vec![start];
    for hit in hits.iter() {
        let p = [hit.position.z, hit.position.y];
        if !(p[0].is_finite() && p[1].is_finite()) {
            return ended(points, RayEnd::Missed { row: hit.surface });
        }
        points.push(p);
        // Blocked here: outside this surface's clear semi-diameter.
        if hit.relative_radius > 1.0 {
            return ended(points, RayEnd::Vignetted { row: hit.surface });
        }
    }
    if result.completed {
        return ended(points, RayEnd::Sensor);
    }
    // Tracing stopped at the step after the last recorded hit; `result.ray` is the ray as it
    // arrived there.
    let Some(step) = seq.steps.get(hits.len()) else {
        return ended(points, RayEnd::Sensor);
    };
    let row = step.surface;
    let fate = if result.fate.is_terminal() {
        result.fate
    } else {
        // The fate names the first thing that happened, a vignetting the drawing did not
        // stop at (a relative radius a hair over 1): ask the failing step alone.
        one_step(seq, step, step.interaction)
            .trace(&result.ray)
            .fate
    };
    let completed = points.len();
    match fate {
        Fate::TotalInternalReflection { .. } => {
            // Where it met the surface: the same intersection, reflected instead.
            let mut h = Vec::new();
            one_step(seq, step, Interaction::Reflect).trace_with_hits(&result.ray, &mut h);
            if let Some(hit) = h.first() {
                let p = [hit.position.z, hit.position.y];
                if p[0].is_finite() && p[1].is_finite() {
                    points.push(p);
                }
            }
            RayPath {
                points,
                end: RayEnd::TotalInternalReflection { row },
                completed,
            }
        }
        _ => {
            // Missed (or no convergence): on to the surface's vertex plane, if ahead.
            let (o, d) = (result.ray.origin, result.ray.dir);
            let t = (step.z - o.z) / d.z;
            if t.is_finite() && t >= 0.0 && t <= reach(seq) {
                let p = o + t * d;
                let p = [p.z, p.y];
                if p[0].is_finite() && p[1].is_finite() && points.last() != Some(&p) {
                    points.push(p);
                }
            }
            RayPath {
                points,
                end: RayEnd::Missed { row },
                completed,
            }
        }
    }
}

/// A path that ended at its last point.
fn ended(points: Vec<[f64; 2]>, end: RayEnd) -> RayPath {
    let completed = points.len();
    RayPath {
        points,
        end,
        completed,
    }
}

/// The sequence of the single step `step` of `seq`, doing `interaction`.
fn one_step(
    seq: &Sequence<f64>,
    step: &flarebench_sdk::trace::Step<f64>,
    interaction: Interaction,
) -> Sequence<f64> {
    let mut step = *step;
    step.interaction = interaction;
    step.table = None;
    Sequence {
        steps: vec![step],
        lambda_nm: seq.lambda_nm,
        coatings: vec![flarebench_sdk::Coating::None; seq.coatings.len()],
        tables: Vec::new(),
        sensor_reflectance: None,
    }
}

/// The farthest a missed ray is drawn toward the vertex plane it misses: a few times the
/// sequence's own extent.
fn reach(seq: &Sequence<f64>) -> f64 {
    let (lo, hi, semi) = seq.steps.iter().fold(
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64),
        |(lo, hi, semi), s| (lo.min(s.z), hi.max(s.z), semi.max(s.semi)),
    );
    4.0 * ((hi - lo).max(0.0) + 2.0 * semi + 1.0)
}

/// The entrance pupil rays are aimed at: position (mm from the first vertex) and radius.
fn pupil(system: &LensSystem, wavelength_nm: f64) -> (f64, f64) {
    if let Ok(p) = analyse(system, wavelength_nm) {
        let (z, r) = (p.entrance_pupil_z_mm, 0.5 * p.entrance_pupil_diameter_mm);
        if z.is_finite() && r.is_finite() {
            return (z, r.abs());
        }
    }
    let first = system.surfaces.first().map_or(0.0, drawn_semi_diameter);
    (0.0, first)
}

/// Fields and wavelengths a fan can be traced at.
fn usable(field_deg: f64, wavelength_nm: f64) -> bool {
    field_deg.abs() < 90.0 && wavelength_nm.is_finite() && wavelength_nm > 0.0
}

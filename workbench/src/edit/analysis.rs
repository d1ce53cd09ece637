//! What the editor shows about the lens, recomputed after every edit: paraxial data, the lens
//! outline and a fan of traced rays for the side view, the ghost list and the selected ghost's
//! ray path. Pure computation on a `LensSystem`; lengths in mm. The shapes (profiles, rims, the
//! stop's jaws, the sensor, ray fans) come from [`crate::lens_drawing`], at the terminal's
//! coarser resolution.

use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use flarebench_sdk::paraxial::{ParaxialData, analyse};
use flarebench_sdk::trace::Sequence;
use flarebench_sdk::{LensSystem, SurfaceKind};

use crate::lens_drawing::{
    RayPath, SensorMark, StopMark, profile_uniform, pupil_fan, rim, standard_fields,
};

/// A polyline in the meridional plane: points (z, y) in mm.
pub type Polyline = Vec<(f64, f64)>;

/// Rays per fan (per field).
pub const FAN_RAYS: usize = 5;

/// Intervals each surface profile is sampled at (the terminal's resolution needs few).
const PROFILE_INTERVALS: usize = 24;

/// Everything the analysis panel and the side view draw.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// First-order data at the lens's default wavelength, or why there is none.
    pub paraxial: Result<ParaxialData, String>,
    /// Surface profiles (the sag curve over ± the semi-diameter; the stop as two jaws).
    pub surfaces: Vec<Polyline>,
    /// Element edges: lines joining the rims of two surfaces with glass between them.
    pub edges: Vec<Polyline>,
    /// Axial ray fan (parallel to the axis) and a fan at `field_deg`, each ray from a little in
    /// front of the lens to where it ends (sensor, or where it is blocked).
    pub axial_rays: Vec<Polyline>,
    pub field_rays: Vec<Polyline>,
    /// The field angle of the second fan (degrees): 70 % of the half-diagonal field.
    pub field_deg: f64,
    /// Every two-reflection ghost path.
    pub ghosts: Vec<GhostPath>,
    /// The z range (mm) the side view spans, and its half height.
    pub z_range: (f64, f64),
    pub half_height: f64,
}

impl Analysis {
    /// Analyses `system` (assumed valid).
    pub fn compute(system: &LensSystem) -> Analysis {
        let lambda = system.default_wavelength_nm();
        let paraxial = analyse(system, lambda).map_err(|e| e.to_string());
        let z = system.vertex_z();
        let track = system.total_track().max(1e-3);
        let lead = 0.15 * track;
        let mut half_height = system
            .surfaces
            .iter()
            .map(|s| s.semi_diameter)
            .fold(0.0, f64::max);
        if half_height <= 0.0 {
            half_height = 1.0;
        }
        half_height *= 1.15;

        let mut surfaces = Vec::new();
        let mut edges = Vec::new();
        let sensor = system.sensor_index();
        for (i, s) in system.surfaces.iter().enumerate() {
            match s.kind {
                SurfaceKind::Refracting => {
                    surfaces.push(polyline(&profile_uniform(s, z[i], PROFILE_INTERVALS)));
                }
                SurfaceKind::ApertureStop => {
                    for jaw in StopMark::new(system, i).jaws() {
                        surfaces.push(polyline(&jaw));
                    }
                }
                SurfaceKind::Sensor => {
                    let mark = SensorMark::of(system);
                    surfaces.push(polyline(&mark.line()));
                    half_height = half_height.max(mark.half_height * 1.1);
                }
            }
            if i + 1 < sensor
                && !s.medium.is_air()
                && s.kind == SurfaceKind::Refracting
                && system.surfaces[i + 1].kind == SurfaceKind::Refracting
            {
                let [za, ya] = rim(s, z[i]);
                let [zb, yb] = rim(&system.surfaces[i + 1], z[i + 1]);
                edges.push(vec![(za, ya), (zb, yb)]);
                edges.push(vec![(za, -ya), (zb, -yb)]);
            }
        }

        let mut axial_rays = Vec::new();
        let mut field_rays = Vec::new();
        let mut field_deg = 0.0;
        if let Ok(p) = &paraxial {
            let seq = Sequence::forward(system, lambda);
            field_deg = standard_fields(system).map_or(0.0, |f| f[1]);
            let r_ep = 0.5 * p.entrance_pupil_diameter_mm;
            axial_rays = fan(&seq, 0.0, p.entrance_pupil_z_mm, r_ep, lead);
            field_rays = fan(&seq, field_deg, p.entrance_pupil_z_mm, r_ep, lead);
        }
        Analysis {
            paraxial,
            surfaces,
            edges,
            axial_rays,
            field_rays,
            field_deg,
            ghosts: enumerate_ghosts(system),
            z_range: (-lead, track + 0.05 * track),
            half_height,
        }
    }
}

/// Traces the path of `ghost` for a fan of axial rays across the entrance pupil (at the
/// default wavelength); each polyline ends where the ray stops or at the sensor.
pub fn ghost_rays(system: &LensSystem, ghost: GhostPath, analysis: &Analysis) -> Vec<Polyline> {
    let Ok(p) = &analysis.paraxial else {
        return Vec::new();
    };
    let lambda = system.default_wavelength_nm();
    let Ok(seq) = Sequence::ghost_path(system, lambda, &ghost) else {
        return Vec::new();
    };
    let lead = -analysis.z_range.0;
    let r = 0.5 * p.entrance_pupil_diameter_mm;
    fan(&seq, 0.0, p.entrance_pupil_z_mm, r, lead)
}

/// A point list of the lens drawing as the side view's polyline.
fn polyline(points: &[[f64; 2]]) -> Polyline {
    points.iter().map(|p| (p[0], p[1])).collect()
}

/// `FAN_RAYS` collimated rays at `field_deg` aimed across the entrance pupil (at `ep_z`, radius
/// `r_ep`), each drawn from `lead` mm in front of the first vertex to its last completed
/// interaction (the sensor, or the surface where it is blocked).
fn fan(seq: &Sequence<f64>, field_deg: f64, ep_z: f64, r_ep: f64, lead: f64) -> Vec<Polyline> {
    pupil_fan(seq, field_deg, ep_z, r_ep, lead, FAN_RAYS)
        .iter()
        .map(|r: &RayPath| polyline(r.completed_points()))
        .collect()
}

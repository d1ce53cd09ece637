//! What the editor shows about the lens, recomputed after every edit: paraxial data, the lens
//! outline and a fan of traced rays for the side view, the ghost list and the selected ghost's
//! ray path. Pure computation on a `LensSystem`; lengths in mm.

use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use flarebench_sdk::paraxial::{ParaxialData, analyse};
use flarebench_sdk::trace::{Ray, Sequence};
use flarebench_sdk::{LensSystem, SurfaceKind};

/// A polyline in the meridional plane: points (z, y) in mm.
pub type Polyline = Vec<(f64, f64)>;

/// Rays per fan (per field).
pub const FAN_RAYS: usize = 5;

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
                SurfaceKind::Refracting => surfaces.push(profile(system, i, z[i])),
                SurfaceKind::ApertureStop => {
                    let open = flarebench_sdk::paraxial::stop_opening(system);
                    let outer = s.semi_diameter.max(open) * 1.2;
                    surfaces.push(vec![(z[i], open), (z[i], outer)]);
                    surfaces.push(vec![(z[i], -open), (z[i], -outer)]);
                }
                SurfaceKind::Sensor => {
                    let h = 0.5 * (system.film_width_mm.hypot(system.film_height_mm));
                    surfaces.push(vec![(z[i], -h), (z[i], h)]);
                    half_height = half_height.max(h * 1.1);
                }
            }
            if i + 1 < sensor
                && !s.medium.is_air()
                && s.kind == SurfaceKind::Refracting
                && system.surfaces[i + 1].kind == SurfaceKind::Refracting
            {
                let a = rim(system, i, z[i]);
                let b = rim(system, i + 1, z[i + 1]);
                edges.push(vec![(a.0, a.1), (b.0, b.1)]);
                edges.push(vec![(a.0, -a.1), (b.0, -b.1)]);
            }
        }

        let mut axial_rays = Vec::new();
        let mut field_rays = Vec::new();
        let mut field_deg = 0.0;
        if let Ok(p) = &paraxial {
            let seq = Sequence::forward(system, lambda);
            let half_diag = 0.5 * system.film_width_mm.hypot(system.film_height_mm);
            field_deg = 0.7 * (half_diag / p.efl_mm.abs()).atan().to_degrees();
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

/// The sag curve of surface `i` at vertex `z0`, sampled over ± its semi-diameter.
fn profile(system: &LensSystem, i: usize, z0: f64) -> Polyline {
    let s = &system.surfaces[i];
    const N: usize = 24;
    (0..=N)
        .filter_map(|k| {
            let y = s.semi_diameter * (2.0 * k as f64 / N as f64 - 1.0);
            s.sag(y.abs()).map(|dz| (z0 + dz, y))
        })
        .collect()
}

/// The rim point (z, y > 0) of surface `i`.
fn rim(system: &LensSystem, i: usize, z0: f64) -> (f64, f64) {
    let s = &system.surfaces[i];
    (z0 + s.sag(s.semi_diameter).unwrap_or(0.0), s.semi_diameter)
}

/// `FAN_RAYS` collimated rays at `field_deg` aimed across the entrance pupil (at `ep_z`, radius
/// `r_ep`), each drawn from `lead` mm in front of the first vertex.
fn fan(seq: &Sequence<f64>, field_deg: f64, ep_z: f64, r_ep: f64, lead: f64) -> Vec<Polyline> {
    let tan = field_deg.to_radians().tan();
    let mut hits = Vec::new();
    (0..FAN_RAYS)
        .map(|k| {
            let t = 0.95 * (2.0 * k as f64 / (FAN_RAYS - 1) as f64 - 1.0);
            // Height at z = 0 of the ray that crosses the pupil plane at t·r_ep.
            let h = t * r_ep - tan * ep_z;
            let ray = Ray::collimated(field_deg.to_radians(), 0.0, h);
            hits.clear();
            seq.trace_with_hits(&ray, &mut hits);
            let mut line = vec![(-lead, h - tan * lead)];
            for hit in &hits {
                line.push((hit.position.z, hit.position.y));
                // Blocked here: outside this surface's clear semi-diameter.
                if hit.relative_radius > 1.0 {
                    break;
                }
            }
            line
        })
        .collect()
}

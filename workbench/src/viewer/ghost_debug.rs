//! What the debug views show of one ghost (as OpenLensFlare's debug views show it): the ghost
//! traced alone for one light, at one of its bands, on the grid its plan gives it — the
//! entrance rectangle and grid, where each ray crosses the aperture stop, each ray's relative
//! radius, and the ghost's triangles on the image with their irradiance. Computed on the render
//! thread ([`super::flare_worker`]) from the frame's own plan, so it is the ghost as drawn.
//!
//! The rays and triangles are those of the renderer (`flarebench_sdk::ghost::grid`, the rules
//! of `flarebench_sdk::ghost::triangles`): the same sequence (the stop's last pass unclipped,
//! its shape applied from the recorded crossing), the same f32 grid, the same triangles left
//! out, the same irradiance — the flux through half a grid cell spread over the triangle's area
//! on the sensor, grown to the Airy disc where it collapses.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::triangles::{edge_feathers, max_feather};
use flarebench_sdk::ghost::{GhostPath, GridTrace, Rect, trace_grid};
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::trace::Sequence;
use ghost_raytrace::plan::{BOUNDS_LAMBDA_NM, LightPlan};

/// How a grid ray fares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayFate {
    /// It reaches the sensor inside every clear aperture and the stop's opening.
    Passes,
    /// It reaches the sensor, but crosses the stop outside its opening (the aperture's shape).
    ClippedAtStop,
    /// It crosses the stop inside its opening but another clear aperture (or an earlier pass
    /// through the stop) clips it.
    ClippedElsewhere,
    /// It stopped: missed a surface or was totally reflected (its other values mean nothing).
    Stopped,
}

/// One ray of the ghost's grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DebugRay {
    /// Where it starts on the entrance plane (mm, the light's meridional frame: light in the
    /// y–z plane).
    pub entrance: [f64; 2],
    /// Where it crosses the aperture stop on its last pass (mm, the lens's frame, where the
    /// aperture's shape is fixed).
    pub stop: [f64; 2],
    /// `hypot(stop) / stop radius`: 1 on the circular stop's edge.
    pub stop_relative_radius: f64,
    /// The largest r / semi-diameter at every other surface of the path (> 1: clipped there).
    pub path_relative_radius: f64,
    pub fate: RayFate,
}

impl DebugRay {
    /// The ray's relative radius: the larger of the stop's and the rest of the path's, so 1
    /// at the edge of whatever clips it first (the circular stop's edge or a rim; for an iris,
    /// the circle through its blade tips).
    pub fn relative_radius(&self) -> f64 {
        self.stop_relative_radius.max(self.path_relative_radius)
    }
}

/// One of the ghost's triangles as the renderer makes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DebugTriangle {
    /// Corners in pixels of the full-resolution image (x right, y down; grown to the Airy
    /// disc where the triangle collapsed).
    pub pixels: [[f32; 2]; 3],
    /// Irradiance (image units per pixel², for a light of unit irradiance, before the ghost's
    /// colour at this band): the flux through half a grid cell over the triangle's area on the
    /// sensor, times its corners' mean Fresnel/coating throughput.
    pub irradiance: f32,
    /// Each corner's relative radius ([`DebugRay::relative_radius`]).
    pub relative_radius: [f32; 3],
    /// Whether each corner's ray passes ([`RayFate::Passes`]).
    pub corner_passes: [bool; 3],
}

impl DebugTriangle {
    /// True when some corner's ray passes every aperture: some of the triangle is drawn.
    /// (Triangles clipped at every corner are still made when the clip is at the stop: the
    /// renderer cuts them per pixel, to nothing.)
    pub fn lit(&self) -> bool {
        self.corner_passes.iter().any(|&p| p)
    }

    /// The triangle's relative radius: its corners' largest (≤ 1 when all of it is inside
    /// every clear aperture and the stop's circle).
    pub fn max_relative_radius(&self) -> f32 {
        self.relative_radius.into_iter().fold(0.0, f32::max)
    }
}

/// The debug data of one ghost (module docs).
#[derive(Clone, Debug)]
pub struct GhostDebug {
    pub path: GhostPath,
    /// The light it was traced for: angle to the axis and azimuth (degrees).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// The band traced (nm): the ghost's band nearest the bounds' wavelength.
    pub lambda_nm: f64,
    /// The ghost's energy share in the plan.
    pub energy_share: f64,
    /// Grid vertices per side.
    pub n: usize,
    /// The coarse frame the ghost is drawn into (pixels a side per coarse pixel; the
    /// triangles here are in full-resolution pixels all the same).
    pub downscale: usize,
    /// The entrance-plane rectangle the grid spans (mm, meridional frame).
    pub entrance: Rect,
    /// The front element's clear semi-diameter (mm).
    pub front_semi_diameter: f64,
    /// The stop's working radius (mm, from the f-number).
    pub stop_radius: f64,
    /// The stop's shape (unit circle = the working radius).
    pub aperture: Aperture,
    /// `n × n` rays, vertex `(i, j)` (i along x) at `j * n + i`.
    pub rays: Vec<DebugRay>,
    /// The triangles the renderer makes of the grid, in grid order.
    pub triangles: Vec<DebugTriangle>,
    /// The image the triangles are in (pixels).
    pub image_size: (usize, usize),
}

impl GhostDebug {
    /// How many rays fare each way: passes, clipped at the stop, clipped elsewhere, stopped.
    pub fn fate_counts(&self) -> [usize; 4] {
        let mut c = [0; 4];
        for r in &self.rays {
            c[r.fate as usize] += 1;
        }
        c
    }

    /// The largest irradiance of a lit triangle, if any is lit.
    pub fn max_irradiance(&self) -> Option<f32> {
        self.triangles
            .iter()
            .filter(|t| t.lit())
            .map(|t| t.irradiance)
            .filter(|v| v.is_finite())
            .reduce(f32::max)
    }
}

/// Traces `path` alone for `plan`'s light, at its band nearest [`BOUNDS_LAMBDA_NM`], on the
/// grid and entrance rectangle the plan gives it; its triangles in pixels of `frame`. An
/// error says why there is nothing to show (the ghost is not drawn at this light).
pub fn compute(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plan: &LightPlan,
    path: GhostPath,
) -> Result<GhostDebug, String> {
    let Some(job) = plan.ghosts.iter().find(|g| g.path == path) else {
        return Err(match plan.dropped.iter().find(|d| d.path == path) {
            Some(d) => format!(
                "ghost {path} is not drawn at this light: left out ({:?}, energy share {:.2e})",
                d.reason, d.energy_share
            ),
            None => format!("ghost {path} is not drawn at this light"),
        });
    };
    let band = job
        .bands
        .iter()
        .map(|b| &plan.bands[b.band])
        .min_by(|a, b| {
            (a.lambda_nm - BOUNDS_LAMBDA_NM)
                .abs()
                .total_cmp(&(b.lambda_nm - BOUNDS_LAMBDA_NM).abs())
        })
        .ok_or_else(|| format!("ghost {path} has no band to trace"))?;
    let seq = Sequence::ghost_path(system, band.lambda_nm, &path)
        .map_err(|e| format!("ghost {path}: {e}"))?
        .with_tables_from(&band.tables)
        .aperture_by_mask()
        .cast::<f32>();
    let stop_radius = stop_opening(system);
    let f_number = analyse(system, LAMBDA_D_NM)
        .map_err(|e| format!("{e}"))?
        .f_number;
    let theta = plan.light.theta_deg.to_radians();
    let phi = plan.light.phi_deg.to_radians();
    let mut grid = GridTrace::default();
    trace_grid(
        &seq,
        theta,
        job.bounds.entrance,
        job.grid,
        stop_radius,
        &mut grid,
    );
    let n = grid.n;
    let (sphi, cphi) = phi.sin_cos();
    let rotate = |[x, y]: [f64; 2]| [x * cphi - y * sphi, x * sphi + y * cphi];
    let sampler = aperture.sampler();

    let r = grid.rect;
    let d = (n - 1) as f64;
    let rays: Vec<DebugRay> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            // The grid's own vertex positions (`push_grid_rays`).
            let entrance = [
                r.x0 + r.width() * i as f64 / d,
                r.y0 + r.height() * j as f64 / d,
            ];
            let uv = rotate(grid.stop_uv[k].map(f64::from));
            let stop = uv.map(|c| c * stop_radius);
            let stop_relative_radius = stop[0].hypot(stop[1]) / stop_radius;
            let path_relative_radius = f64::from(grid.max_rel[k]);
            let fate = if !grid.completed[k] {
                RayFate::Stopped
            } else if sampler.transmission(uv[0] as f32, uv[1] as f32) < 0.5 {
                RayFate::ClippedAtStop
            } else if path_relative_radius > 1.0 {
                RayFate::ClippedElsewhere
            } else {
                RayFate::Passes
            };
            DebugRay {
                entrance,
                stop,
                stop_relative_radius,
                path_relative_radius,
                fate,
            }
        })
        .collect();

    // The renderer's triangles (`BandTriangles` in flarebench_sdk::ghost::triangles).
    let widest = f64::from(max_feather(n));
    let airy = 1.22 * band.lambda_nm * 1e-6 * f_number;
    let min_area = std::f64::consts::PI * airy * airy;
    let half_cell = 0.5 * grid.cell_area() * theta.cos();
    let px_area = frame.pixel_area_mm2();
    let cells = n - 1;
    let mut triangles = Vec::with_capacity(2 * cells * cells);
    for c in 0..cells * cells {
        let k00 = (c / cells) * n + c % cells;
        let quad = [k00, k00 + 1, k00 + n + 1, k00 + n];
        for tri in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
            if !tri.iter().all(|&k| grid.completed[k]) {
                continue;
            }
            let radius = tri.map(|k| f64::from(grid.max_rel[k]));
            if radius.iter().all(|&x| x > 1.0 + widest) {
                continue;
            }
            let mut p = tri.map(|k| rotate(grid.sensor[k].map(f64::from)));
            let area = 0.5
                * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                    - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                    .abs();
            if !area.is_finite() {
                continue;
            }
            let uv = tri.map(|k| rotate(grid.stop_uv[k].map(f64::from)));
            let clip = edge_feathers(p, radius, uv, frame.pixel_mm(), widest).clip;
            if radius.iter().all(|&x| x > 1.0 + f64::from(clip)) {
                continue;
            }
            let centre = [
                (p[0][0] + p[1][0] + p[2][0]) / 3.0,
                (p[0][1] + p[1][1] + p[2][1]) / 3.0,
            ];
            let area = if area >= min_area {
                area
            } else if area > 0.0 {
                let s = (min_area / area).sqrt();
                for q in &mut p {
                    *q = [
                        centre[0] + (q[0] - centre[0]) * s,
                        centre[1] + (q[1] - centre[1]) * s,
                    ];
                }
                min_area
            } else {
                let a = airy;
                p = [
                    [centre[0] - a, centre[1] - a],
                    [centre[0] + a, centre[1] - a],
                    [centre[0], centre[1] + a],
                ];
                2.0 * a * a
            };
            let weight = tri.iter().map(|&k| f64::from(grid.weight[k])).sum::<f64>() / 3.0;
            triangles.push(DebugTriangle {
                pixels: p.map(|q| frame.to_pixel(q[0], q[1])),
                irradiance: (half_cell / area * px_area * weight) as f32,
                relative_radius: tri.map(|k| rays[k].relative_radius() as f32),
                corner_passes: tri.map(|k| rays[k].fate == RayFate::Passes),
            });
        }
    }
    Ok(GhostDebug {
        path,
        theta_deg: plan.light.theta_deg,
        phi_deg: plan.light.phi_deg,
        lambda_nm: band.lambda_nm,
        energy_share: job.energy_share,
        n,
        downscale: job.downscale,
        entrance: r,
        front_semi_diameter: system.surfaces.first().map_or(0.0, |s| s.semi_diameter),
        stop_radius,
        aperture: aperture.clone(),
        rays,
        triangles,
        image_size: (frame.width, frame.height),
    })
}

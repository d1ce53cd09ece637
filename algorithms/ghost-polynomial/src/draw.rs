//! The polynomial render: each planned ghost's grid ([`crate::plan`]: the entrance
//! rectangle and grid size of the bounds table, as the ray-traced renderer's) evaluated by its
//! fit instead of traced, and the cells drawn as the renderer draws them — two triangles a
//! cell, each carrying the flux through its half cell, `A_cell/2 · cos θ`, spread over its
//! area on the sensor (grown to the Airy disc `π (1.22 λ N)²` where it collapses) and weighted
//! by the fitted throughput at its corners.
//!
//! **Clipping.** The host draws a plugin's triangles whole, so the plugin cuts them itself:
//! a triangle is clipped to where two functions interpolated linearly over it are ≥ 0 —
//! `1 − max_rel` (the other surfaces' rims) and minus the aperture's signed distance at the
//! fitted stop crossing — and the part left is drawn as a fan at the triangle's irradiance.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{Mesh, Scene};
use flarebench_sdk::abi::v1::MeshVertex;
use flarebench_sdk::aperture::ApertureSampler;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use rayon::prelude::*;

use crate::cache::FitMap;
use crate::error::PolyError;
use crate::plan::GhostJob;
use crate::sample::{MAX_REL, SENSOR_X, SENSOR_Y, STOP_U, STOP_V, THROUGHPUT};

/// What a render drew.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrawStats {
    /// Ghosts (per light) with at least one triangle.
    pub ghosts_drawn: u32,
    /// Grid vertices evaluated (over every band).
    pub evaluations: usize,
}

/// A corner of a triangle being clipped: sensor position (mm), colour, and the two clip
/// functions (drawn where both are ≥ 0).
#[derive(Clone, Copy, Debug)]
struct Corner {
    p: [f64; 2],
    rgb: [f64; 3],
    f: [f64; 2],
}

fn lerp(a: &Corner, b: &Corner, t: f64) -> Corner {
    let m = |x: f64, y: f64| x + t * (y - x);
    Corner {
        p: [m(a.p[0], b.p[0]), m(a.p[1], b.p[1])],
        rgb: [
            m(a.rgb[0], b.rgb[0]),
            m(a.rgb[1], b.rgb[1]),
            m(a.rgb[2], b.rgb[2]),
        ],
        f: [m(a.f[0], b.f[0]), m(a.f[1], b.f[1])],
    }
}

/// The part of the polygon `poly` where clip function `k` is ≥ 0 (Sutherland–Hodgman).
fn clip(poly: &[Corner], k: usize, out: &mut Vec<Corner>) {
    out.clear();
    for i in 0..poly.len() {
        let (a, b) = (&poly[i], &poly[(i + 1) % poly.len()]);
        let (fa, fb) = (a.f[k], b.f[k]);
        if fa >= 0.0 {
            out.push(*a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            out.push(lerp(a, b, fa / (fa - fb)));
        }
    }
}

/// Per ghost and band, what its triangles need.
struct BandDraw<'a> {
    frame: Frame,
    px_area: f64,
    min_area: f64,
    airy: f64,
    half_cell: f64,
    rgb: [f32; 3],
    aperture: &'a ApertureSampler<'a>,
}

impl BandDraw<'_> {
    /// Appends the triangle of grid corners `c` (sensor mm, throughput, clip functions) to
    /// `mesh`; true when something was drawn.
    fn push(&self, mut c: [Corner; 3], mesh: &mut Mesh, scratch: &mut [Vec<Corner>; 2]) -> bool {
        if c.iter().all(|k| k.f[0] < 0.0) || c.iter().all(|k| k.f[1] < 0.0) {
            return false;
        }
        let [p0, p1, p2] = [c[0].p, c[1].p, c[2].p];
        let area =
            0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1])).abs();
        if !area.is_finite() {
            return false;
        }
        let centre = [(p0[0] + p1[0] + p2[0]) / 3.0, (p0[1] + p1[1] + p2[1]) / 3.0];
        let area = if area >= self.min_area {
            area
        } else if area > 0.0 {
            let s = (self.min_area / area).sqrt();
            for k in &mut c {
                k.p = [
                    centre[0] + (k.p[0] - centre[0]) * s,
                    centre[1] + (k.p[1] - centre[1]) * s,
                ];
            }
            self.min_area
        } else {
            let r = self.airy;
            let q = [
                [centre[0] - r, centre[1] - r],
                [centre[0] + r, centre[1] - r],
                [centre[0], centre[1] + r],
            ];
            for (k, q) in c.iter_mut().zip(q) {
                k.p = q;
            }
            2.0 * r * r
        };
        let irr = self.half_cell / area * self.px_area;
        for k in &mut c {
            let e = irr * k.rgb[0];
            k.rgb = self.rgb.map(|v| f64::from(v) * e);
        }
        let [a, b] = scratch;
        a.clear();
        a.extend_from_slice(&c);
        clip(a, 0, b);
        clip(b, 1, a);
        if a.len() < 3 {
            return false;
        }
        let base = mesh.vertices.len() as u32;
        for k in a.iter() {
            let [x, y] = self.frame.to_pixel(k.p[0], k.p[1]);
            mesh.vertices.push(MeshVertex {
                x,
                y,
                rgb: k.rgb.map(|v| v as f32),
            });
        }
        let n = a.len() as u32;
        mesh.triangles
            .extend((1..n - 1).map(|i| [base, base + i, base + i + 1]));
        true
    }
}

/// The ghosts of `jobs` evaluated with `fits` and meshed for `scene`'s frame and aperture;
/// the mesh and what was drawn.
pub fn mesh_jobs(
    system: &LensSystem,
    fits: &FitMap,
    scene: &Scene,
    jobs: &[GhostJob],
) -> Result<(Mesh, DrawStats), PolyError> {
    let f_number = analyse(system, LAMBDA_D_NM)?.f_number;
    let aperture = scene.aperture.sampler();
    let parts: Vec<(Mesh, bool, usize)> = jobs
        .par_iter()
        .map(|job| {
            let theta_deg = job.theta_deg;
            let mut mesh = Mesh::default();
            let Some(fit) = fits.get(&job.path) else {
                return (mesh, false, 0);
            };
            let n = job.bounds.grid.max(2);
            let rect = job.bounds.entrance;
            let (theta, phi) = (theta_deg.to_radians(), job.phi_deg.to_radians());
            let (sphi, cphi) = phi.sin_cos();
            let d = (n - 1) as f64;
            let cell = rect.width() / d * (rect.height() / d);
            let mut corners = Vec::with_capacity(n * n);
            let mut scratch = [Vec::with_capacity(8), Vec::with_capacity(8)];
            let mut any = false;
            let mut evaluations = 0;
            for &(lambda, rgb) in &job.bands {
                let airy = 1.22 * lambda * 1e-6 * f_number;
                let draw = BandDraw {
                    frame: scene.frame,
                    px_area: scene.frame.pixel_area_mm2(),
                    min_area: std::f64::consts::PI * airy * airy,
                    airy,
                    half_cell: 0.5 * cell * theta.cos(),
                    rgb,
                    aperture: &aperture,
                };
                corners.clear();
                for j in 0..n {
                    let y = rect.y0 + rect.height() * j as f64 / d;
                    for i in 0..n {
                        let x = rect.x0 + rect.width() * i as f64 / d;
                        let o = fit.eval(x, y, theta_deg, lambda);
                        let turn = |a: f64, b: f64| [a * cphi - b * sphi, a * sphi + b * cphi];
                        let p = turn(o[SENSOR_X], o[SENSOR_Y]);
                        let [u, v] = turn(o[STOP_U], o[STOP_V]);
                        let sd = f64::from(draw.aperture.signed_distance(u as f32, v as f32));
                        corners.push(Corner {
                            p,
                            // The throughput rides in the colour until the triangle's
                            // irradiance is known.
                            rgb: [o[THROUGHPUT], 0.0, 0.0],
                            f: [1.0 - o[MAX_REL], -sd],
                        });
                    }
                }
                evaluations += n * n;
                for cy in 0..n - 1 {
                    for cx in 0..n - 1 {
                        let k = cy * n + cx;
                        let q = [k, k + 1, k + n + 1, k + n];
                        for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                            any |= draw.push(tri.map(|t| corners[t]), &mut mesh, &mut scratch);
                        }
                    }
                }
            }
            (mesh, any, evaluations)
        })
        .collect();
    let mut mesh = Mesh::default();
    let mut stats = DrawStats::default();
    mesh.vertices
        .reserve(parts.iter().map(|p| p.0.vertices.len()).sum());
    mesh.triangles
        .reserve(parts.iter().map(|p| p.0.triangles.len()).sum());
    for (m, drawn, evals) in parts {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend(m.vertices);
        mesh.triangles
            .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        stats.ghosts_drawn += u32::from(drawn);
        stats.evaluations += evals;
    }
    Ok((mesh, stats))
}

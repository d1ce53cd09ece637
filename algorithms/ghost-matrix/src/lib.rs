//! Ghosts from paraxial ray-transfer matrices (after Lee & Eisemann 2013, "Practical
//! real-time lens-flare rendering"): along each two-reflection path (the plugin draws those
//! only; [`matrix::ghost`] takes four-reflection paths too, whose chain is just longer, but
//! the plugin has no energy cull and N⁴/8 of them would each be drawn), the 2×2 matrices from the
//! entrance plane to the stop and to the sensor ([`matrix`]) make the ghost an affine image of
//! the aperture — the stop's opening scaled by `m = A_sensor / A_stop`, centred at
//! `(B_sensor − m·B_stop) · tan θ` — drawn as a polygon of uniform radiance carrying the flux
//! `E · cos θ · S / A_stop² · T(λ)` (S the opening's area, T the path's Fresnel/coating
//! throughput at normal incidence), per wavelength band.
//!
//! What it leaves out, by construction: aberrations (every ghost is a sharp, uniformly lit
//! copy of the aperture), vignetting by the other surfaces' rims, and the angle dependence
//! of the coatings. It is fast and a second, independent algorithm to compare the traced
//! renderer with. The polygons go to the host as a mesh, which it rasterizes exactly.

pub mod matrix;

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{
    FlarePlugin, Mesh, Output, ParamSpec, Params, PluginError, PluginInfo, PluginKind, Scene,
};
use flarebench_sdk::abi::v1::MeshVertex;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::SpectralSampling;
use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use flarebench_sdk::paraxial::stop_opening;

/// Sides of the polygon standing for a circular stop; the polygon's own area is used for the
/// flux, so the energy is exact and only the outline is approximated.
pub const CIRCLE_SIDES: usize = 64;
/// Points per blade edge of a rounded iris.
const ARC_POINTS: usize = 8;
/// Smallest drawn radius of a ghost (pixels): a ghost focused to a point is drawn this size
/// with its energy kept, so its radiance stays bounded.
pub const MIN_RADIUS_PX: f64 = 0.5;

/// The aperture's outline in stop coordinates normalised by the working radius (the sdk's
/// [`Aperture`] convention: iris tips on the unit circle at `rotation + 2πk/blades`).
pub fn outline(aperture: &Aperture) -> Vec<[f64; 2]> {
    match *aperture {
        Aperture::Iris {
            blades,
            rotation_rad,
            roundness,
        } if blades >= 3 => {
            let n = blades as usize;
            let tip = |k: usize| {
                let a = rotation_rad + std::f64::consts::TAU * k as f64 / n as f64;
                [a.cos(), a.sin()]
            };
            let mut pts = Vec::with_capacity(n * ARC_POINTS);
            for k in 0..n {
                let (p, q) = (tip(k), tip(k + 1));
                // The edge is an arc of radius 1/roundness bulging outward between the tips.
                let mid = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
                let len = (mid[0] * mid[0] + mid[1] * mid[1]).sqrt();
                let normal = [mid[0] / len, mid[1] / len];
                let half = (std::f64::consts::PI / n as f64).sin();
                for j in 0..ARC_POINTS {
                    let t = j as f64 / ARC_POINTS as f64;
                    let bulge = if roundness > 0.0 {
                        let r = 1.0 / roundness;
                        let x = half * (2.0 * t - 1.0);
                        (r * r - x * x).sqrt() - (r * r - half * half).sqrt()
                    } else {
                        0.0
                    };
                    pts.push([
                        p[0] + t * (q[0] - p[0]) + bulge * normal[0],
                        p[1] + t * (q[1] - p[1]) + bulge * normal[1],
                    ]);
                }
            }
            pts
        }
        _ => (0..CIRCLE_SIDES)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / CIRCLE_SIDES as f64;
                [a.cos(), a.sin()]
            })
            .collect(),
    }
}

pub use flarebench_sdk::aperture::polygon_area;

/// Every ghost of every light of `scene` as polygons (triangle fans) with their radiance per
/// pixel², in `bands` wavelength bands; returns the mesh and the number of ghosts drawn (a
/// ghost counts once however many bands it has).
pub fn ghost_mesh(
    system: &LensSystem,
    paths: &[GhostPath],
    scene: &Scene,
    bands: usize,
) -> Result<(Mesh, u32), PluginError> {
    let frame = scene.frame;
    let px_mm = frame.film_width_mm / frame.width as f64;
    let px_area = frame.pixel_area_mm2();
    let stop_r = stop_opening(system);
    let unit = outline(&scene.aperture);
    let unit_area = polygon_area(&unit);
    let mut mesh = Mesh::default();
    let mut drawn = 0;
    for light in &scene.lights {
        let sampling = SpectralSampling::new(bands, light.spectrum)?;
        let (theta, phi) = (light.theta_deg.to_radians(), light.phi_deg.to_radians());
        let (sphi, cphi) = phi.sin_cos();
        for &path in paths {
            let mut any = false;
            for (&lambda, w) in sampling.wavelengths_nm().iter().zip(sampling.weights()) {
                let Some(g) = matrix::ghost(system, path, lambda) else {
                    continue;
                };
                let yc = g.centre_per_tan * theta.tan();
                // The meridional centre (0, yc) turned by φ; the aperture itself does not turn.
                let centre = [-yc * sphi, yc * cphi];
                let stop_area = unit_area * stop_r * stop_r;
                let flux = light.intensity
                    * theta.cos()
                    * stop_area
                    * g.entrance_area_scale
                    * g.throughput;
                let mut r = g.magnification * stop_r;
                if r.abs() < MIN_RADIUS_PX * px_mm {
                    r = MIN_RADIUS_PX * px_mm * if r < 0.0 { -1.0 } else { 1.0 };
                }
                let sensor_area_px = unit_area * r * r / px_area;
                let radiance = flux / sensor_area_px;
                if !(radiance.is_finite() && radiance > 0.0) {
                    continue;
                }
                let pts: Vec<[f32; 2]> = unit
                    .iter()
                    .map(|u| frame.to_pixel(centre[0] + r * u[0], centre[1] + r * u[1]))
                    .collect();
                let off = pts.iter().all(|p| p[0] < 0.0)
                    || pts.iter().all(|p| p[1] < 0.0)
                    || pts.iter().all(|p| p[0] > frame.width as f32)
                    || pts.iter().all(|p| p[1] > frame.height as f32);
                if off {
                    continue;
                }
                let rgb = w.map(|c| (c as f64 * radiance) as f32);
                let c = frame.to_pixel(centre[0], centre[1]);
                let base = mesh.vertices.len() as u32;
                mesh.vertices.push(MeshVertex {
                    x: c[0],
                    y: c[1],
                    rgb,
                });
                mesh.vertices.extend(pts.iter().map(|p| MeshVertex {
                    x: p[0],
                    y: p[1],
                    rgb,
                }));
                let n = pts.len() as u32;
                mesh.triangles
                    .extend((0..n).map(|k| [base, base + 1 + k, base + 1 + (k + 1) % n]));
                any = true;
            }
            drawn += u32::from(any);
        }
    }
    Ok((mesh, drawn))
}

/// The plugin: the lens and its ghost paths.
#[derive(Debug, Default)]
pub struct GhostMatrix {
    lens: Option<(LensSystem, Vec<GhostPath>)>,
}

impl FlarePlugin for GhostMatrix {
    fn info() -> PluginInfo {
        PluginInfo {
            name: "ghost-matrix",
            version: env!("CARGO_PKG_VERSION"),
            description: "ghosts as affine images of the aperture from paraxial ray-transfer matrices (Lee & Eisemann 2013); unaberrated, unvignetted",
            kind: PluginKind::Ghosts,
            params: vec![ParamSpec::int(
                "bands",
                "wavelength bands (each ghost drawn once per band)",
                1,
                31,
                7,
            )],
        }
    }

    fn create() -> Result<Self, PluginError> {
        Ok(GhostMatrix::default())
    }

    fn prepare(&mut self, lens: &LensSystem) -> Result<(), PluginError> {
        self.lens = Some((lens.clone(), enumerate_ghosts(lens)));
        Ok(())
    }

    fn render(
        &mut self,
        scene: &Scene,
        params: &Params<'_>,
        out: &mut Output<'_>,
    ) -> Result<(), PluginError> {
        let (lens, paths) = self
            .lens
            .as_ref()
            .ok_or_else(|| PluginError::new("no lens prepared"))?;
        let bands = params.get_int("bands")? as usize;
        let (mesh, drawn) = ghost_mesh(lens, paths, scene, bands)?;
        out.mesh = mesh;
        out.items_drawn = drawn;
        Ok(())
    }
}

flarebench_sdk::export_plugin!(GhostMatrix);

//! What a render draws: per light, every fitted ghost that has light at the light's angle
//! and reaches the frame, with its entrance rectangle and grid size from the bounds table
//! (as the ray-traced renderer looks them up in a precomputed table) and its wavelength
//! bands. Nothing is culled for being dim.
//!
//! **Colours.** A band's colour is the light's over the band, integrated in sub-bands of at
//! most [`FINE_NM`] with the ghost's throughput relative to the band's centre,
//! `Σ_j w_j · T(λ_j) / T(λ_band)` — so that, multiplied by the throughput at the band's centre
//! at each grid vertex, the band carries the whole band's light (the ray-traced renderer's
//! convention). `T` here is the fitted throughput at the middle of the ghost's entrance
//! rectangle.

use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::color::SpectralSampling;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::ghost::{GhostBounds, GhostPath};

use crate::cache::FitMap;
use crate::error::PolyError;
use crate::sample::THROUGHPUT;

/// Widest sub-band a band's colour is integrated over (nm).
pub const FINE_NM: f64 = 5.0;
/// Wavelength bands drawn when the parameter is 0: the ray-traced renderer's default.
pub const DEFAULT_BANDS: usize = 7;

/// One ghost of one light to draw.
#[derive(Clone, Debug)]
pub struct GhostJob {
    pub path: GhostPath,
    pub bounds: GhostBounds,
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Each band's centre (nm) and colour (linear RGB per unit throughput, the light's
    /// intensity included).
    pub bands: Vec<(f64, [f32; 3])>,
}

/// The scene's ghosts to draw, and how many were left out because their light lies beyond
/// the fitted angles.
pub fn plan_scene(
    table: &BoundsTable,
    fits: &FitMap,
    scene: &Scene,
    bands: usize,
) -> Result<(Vec<GhostJob>, u32), PolyError> {
    let bands = if bands == 0 { DEFAULT_BANDS } else { bands };
    let frame = scene.frame;
    let mut jobs = Vec::new();
    let mut beyond = 0;
    for light in &scene.lights {
        let coarse = SpectralSampling::new(bands, light.spectrum)?;
        let m = (coarse.bin_width_nm() / FINE_NM).ceil().max(1.0) as usize;
        let fine = SpectralSampling::new(bands * m, light.spectrum)?;
        let theta = light.theta_deg;
        let phi = light.phi_deg.to_radians();
        for (g, &path) in table.ghosts.iter().enumerate() {
            let Some(fit) = fits.get(&path) else { continue };
            let Some(b) = table.lookup(g, theta) else {
                if theta > fit.domain.theta_max_deg {
                    beyond += 1;
                }
                continue;
            };
            // Off the frame: the sensor rectangle, turned by φ, misses it.
            let s = b.sensor.rotated(phi);
            let corners = [[s.x0, s.y0], [s.x1, s.y0], [s.x0, s.y1], [s.x1, s.y1]]
                .map(|[x, y]| frame.to_pixel(x, y));
            let (w, h) = (frame.width as f32, frame.height as f32);
            if corners.iter().all(|p| p[0] < 0.0)
                || corners.iter().all(|p| p[0] > w)
                || corners.iter().all(|p| p[1] < 0.0)
                || corners.iter().all(|p| p[1] > h)
            {
                continue;
            }
            let yc = 0.5 * (b.entrance.y0 + b.entrance.y1);
            let t = |lambda: f64| fit.eval(0.0, yc, theta, lambda)[THROUGHPUT];
            let colours = coarse
                .wavelengths_nm()
                .iter()
                .enumerate()
                .map(|(k, &centre)| {
                    let t0 = t(centre);
                    let mut c = [0.0_f64; 3];
                    for j in k * m..(k + 1) * m {
                        let ratio = if t0 > 0.0 {
                            t(fine.wavelengths_nm()[j]) / t0
                        } else {
                            1.0
                        };
                        for (v, w) in c.iter_mut().zip(fine.weights()[j]) {
                            *v += f64::from(w) * ratio;
                        }
                    }
                    (centre, c.map(|v| (v * light.intensity) as f32))
                })
                .collect();
            jobs.push(GhostJob {
                path,
                bounds: b,
                theta_deg: theta,
                phi_deg: light.phi_deg,
                bands: colours,
            });
        }
    }
    Ok((jobs, beyond))
}

//! The render report: what was traced, what was left out and what it cost.

use serde::Serialize;

use crate::flare::backend::BackendReport;
use crate::flare::compose::StarburstLine;

use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::ghost::context::GhostStats;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::plan::{
    DrawMethod, DropReason, FourReflectionSummary, LightPlan, MethodPrediction,
};

/// Time spent per stage (milliseconds).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    pub load_ms: f64,
    pub plan_ms: f64,
    pub render_ms: f64,
    /// Starbursts: patterns (transforms and spectral sums) and adding them.
    pub starburst_ms: f64,
    pub write_ms: f64,
    pub reference_ms: Option<f64>,
}

/// Error of the image against the reference renderer.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ErrorReport {
    /// sqrt(Σ|a − b|²) / sqrt(Σ|b|²) over every channel.
    pub relative_rmse: f64,
    /// Σ|a − b| / Σ|b|.
    pub relative_l1: f64,
    /// (Σa − Σb) / Σb.
    pub energy_error: f64,
}

impl ErrorReport {
    /// The error of `img` against `reference` (the same size).
    pub fn between(img: &HdrImage, reference: &HdrImage) -> anyhow::Result<ErrorReport> {
        let c = img.compare(reference)?;
        Ok(ErrorReport {
            relative_rmse: c.relative_rmse,
            relative_l1: c.relative_l1,
            energy_error: c.energy_error,
        })
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct GhostLine {
    pub ghost: String,
    pub grid: usize,
    /// Coarse-frame factor the ghost was drawn at (1: full resolution).
    pub downscale: usize,
    pub spectral: bool,
    /// Wavelengths the ghost was traced at.
    pub bands: usize,
    pub energy_share: f64,
    pub rays: usize,
    pub triangles: usize,
    /// How the ghost was drawn, and what the plan predicted of each way (its time meshed and
    /// splatted, the error splatting adds to the ghost and its share of the frame's squared
    /// relative RMSE: `ghost_raytrace::method`).
    pub method: DrawMethod,
    pub prediction: MethodPrediction,
}

#[derive(Clone, Debug, Serialize)]
pub struct DroppedLine {
    pub ghost: String,
    pub reason: DropReason,
    pub energy_share: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct LightReport {
    pub theta_deg: f64,
    pub phi_deg: f64,
    pub intensity: f64,
    pub ghosts_total: usize,
    pub ghosts_traced: usize,
    pub ghosts_dropped: usize,
    /// Sum of the ghosts' energy shares (of the direct image).
    pub ghost_energy_share: f64,
    /// Part of that left out by planning (fraction of the ghost energy): ghosts off the
    /// frame, without light, or culled as dim.
    pub dropped_energy_fraction: f64,
    /// What the image loses by culling: the share of the frame's ghost energy in the ghosts
    /// left out as dim (`LightPlan::culled_share`).
    pub culled_energy_fraction: f64,
    pub bands: usize,
    pub ghosts: Vec<GhostLine>,
    /// Every ghost left out, four-reflection ghosts culled by their energy bound included
    /// (reason `bound`, the bound as their energy share).
    pub dropped: Vec<DroppedLine>,
    /// With `--reflections 4`: what became of the four-reflection ghosts (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub four_reflections: Option<FourReflectionSummary>,
    /// With `--precomputed`: the ghosts the table does not hold, whose bounds were traced for
    /// this light (absent when there are none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bounds_not_in_table: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    pub lens: String,
    pub width: usize,
    pub height: usize,
    pub quality: ghost_raytrace::scene::Quality,
    pub output: String,
    pub timings: Timings,
    pub rays_traced: usize,
    pub triangles: usize,
    /// Σ of each channel over the image.
    pub image_sum_rgb: [f64; 3],
    pub image_max: f32,
    /// Exposure applied to a PNG (stops).
    pub exposure_ev: f32,
    pub lights: Vec<LightReport>,
    /// One entry per light when starbursts are on (`compose::StarburstLine`).
    pub starbursts: Vec<StarburstLine>,
    pub error: Option<ErrorReport>,
    /// Where the ghosts were drawn (`crate::backend`).
    pub backend: BackendReport,
}

impl LightReport {
    pub fn new(lp: &LightPlan, stats: &[GhostStats]) -> Self {
        let (total, dropped) = lp.energy();
        let mut ghosts: Vec<GhostLine> = lp
            .ghosts
            .iter()
            .zip(stats)
            .map(|(g, s)| GhostLine {
                ghost: g.path.to_string(),
                grid: g.grid,
                downscale: g.downscale,
                spectral: g.spectral(),
                bands: g.bands.len(),
                energy_share: g.energy_share,
                rays: s.rays,
                triangles: s.triangles,
                method: g.method,
                prediction: g.prediction,
            })
            .collect();
        ghosts.sort_by(|a, b| b.energy_share.total_cmp(&a.energy_share));
        LightReport {
            theta_deg: lp.light.theta_deg,
            phi_deg: lp.light.phi_deg,
            intensity: lp.light.intensity,
            ghosts_total: lp.ghosts.len() + lp.dropped.len(),
            ghosts_traced: lp.ghosts.len(),
            ghosts_dropped: lp.dropped.len(),
            ghost_energy_share: total,
            dropped_energy_fraction: if total > 0.0 { dropped / total } else { 0.0 },
            culled_energy_fraction: lp.culled_share,
            bands: lp.sampled,
            ghosts,
            dropped: lp
                .dropped
                .iter()
                .map(|d| DroppedLine {
                    ghost: d.path.to_string(),
                    reason: d.reason,
                    energy_share: d.energy_share,
                })
                .collect(),
            four_reflections: (lp.reflections == ReflectionOrder::Four)
                .then(|| lp.four_reflection_summary()),
            bounds_not_in_table: lp.not_in_table.iter().map(|p| p.to_string()).collect(),
        }
    }
}

impl RenderReport {
    /// The report as readable text.
    pub fn text(&self) -> String {
        let t = &self.timings;
        let mut s = format!(
            "{} → {} ({}×{}, quality {:?})\n",
            self.lens, self.output, self.width, self.height, self.quality
        );
        s += &format!(
            "time: load {:.1} ms, plan {:.1} ms, render {:.1} ms, starburst {:.1} ms, write {:.1} ms{}\n",
            t.load_ms,
            t.plan_ms,
            t.render_ms,
            t.starburst_ms,
            t.write_ms,
            t.reference_ms
                .map_or(String::new(), |r| format!(", reference {r:.1} ms"))
        );
        s += &format!(
            "rays traced {}, triangles {}\n",
            self.rays_traced, self.triangles
        );
        s += &self.backend.text();
        for (i, l) in self.lights.iter().enumerate() {
            s += &format!(
                "light {i} at θ {}°, φ {}°: {} of {} ghosts traced, {} left out ({:.3}% of the ghost energy; culling took {:.3}% of the frame's); ghosts carry {:.3e} of the direct image's energy\n",
                l.theta_deg,
                l.phi_deg,
                l.ghosts_traced,
                l.ghosts_total,
                l.ghosts_dropped,
                100.0 * l.dropped_energy_fraction,
                100.0 * l.culled_energy_fraction,
                l.ghost_energy_share
            );
            if let Some(f) = &l.four_reflections {
                s += &format!(
                    "  four-reflection ghosts: {} paths, {} left out by the energy bound (≤ {:.3e} of the direct image's energy), {} left out after their bounds were found ({:.3e}), {} traced carrying {:.3e}\n",
                    f.paths,
                    f.bounded_out,
                    f.bounded_out_energy_share,
                    f.dropped_after_bounds,
                    f.dropped_energy_share,
                    f.traced,
                    f.traced_energy_share
                );
            }
            if !l.bounds_not_in_table.is_empty() {
                s += &format!(
                    "  bounds traced for {} ghosts not in the precomputed table: {}\n",
                    l.bounds_not_in_table.len(),
                    l.bounds_not_in_table.join(" ")
                );
            }
            let splatted: Vec<&GhostLine> = l
                .ghosts
                .iter()
                .filter(|g| g.method == DrawMethod::Splat)
                .collect();
            if !splatted.is_empty() {
                let added2: f64 = splatted.iter().map(|g| g.prediction.frame_error2).sum();
                s += &format!(
                    "  {} ghosts splatted (sub-pixel triangles as boxes), predicted to add {:.3}% relative RMSE\n",
                    splatted.len(),
                    100.0 * added2.sqrt()
                );
            }
            for g in l.ghosts.iter().take(5) {
                s += &format!(
                    "  ghost {:>6}: energy {:.3e}, grid {}², {} band{}, drawn at 1/{}{}\n",
                    g.ghost,
                    g.energy_share,
                    g.grid,
                    g.bands,
                    if g.bands == 1 { "" } else { "s" },
                    g.downscale,
                    if g.method == DrawMethod::Splat {
                        ", splatted"
                    } else {
                        ""
                    }
                );
            }
        }
        for b in &self.starbursts {
            s += &match (&b.left_out, b.position_px) {
                (Some(why), _) => format!("starburst of light {}: left out ({why})\n", b.light),
                (None, Some([x, y])) => format!(
                    "starburst of light {} at pixel ({x:.1}, {y:.1}): flux {:.4e}, {:.3}% in the frame, reach {:.0} px\n",
                    b.light,
                    b.flux,
                    if b.flux > 0.0 {
                        100.0 * b.added / b.flux
                    } else {
                        0.0
                    },
                    b.reach_px
                ),
                (None, None) => String::new(),
            };
        }
        if let Some(e) = &self.error {
            s += &format!(
                "error against the reference: relative RMSE {:.3}%, relative L1 {:.3}%, energy {:+.3}%\n",
                100.0 * e.relative_rmse,
                100.0 * e.relative_l1,
                100.0 * e.energy_error
            );
        }
        s
    }
}

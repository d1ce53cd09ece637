//! Three estimates of every ghost side by side: the independent Monte-Carlo reference
//! (`flarebench_sdk::ghost::monte_carlo`: random rays, no grids, meshes or rasterizer), the
//! dense mesh reference ([`crate::reference`]) and the renderer ([`crate::ghosts`] at a
//! quality preset).
//!
//! Per ghost: its energy share at [`BOUNDS_LAMBDA_NM`] (the flux over the on-axis direct
//! image's, the figure the plan reports and culls by) from the Monte-Carlo tracer and from the
//! bounds search; and its image — each ghost drawn alone — as each of the three draws it: the
//! luminance summed over the frame, the flux-weighted centroid and the central second moments.
//! The Monte-Carlo reference traces each ghost at the mesh reference's bands, in the same
//! colours; its centroid and moments are those of the rays' landing points in the frame
//! (exact positions), the images' those of pixel centres (which adds 1/12 px² to each
//! variance); the Monte-Carlo image's own moments are given too. Its pixels sum the rays
//! landing in them, as the rasterizer's exact coverage does the triangles, so the three images
//! are compared pixel for pixel, ghost by ghost and all together.
//!
//! The Monte-Carlo image's rays are shared among the ghosts evenly (the same error bar on each
//! ghost's energy) or in proportion to their flux in the frame ([`Allot`]: the least noise in
//! the whole image); `McSettings::outside_weight` gathers each ghost's rays on the entry cells
//! whose light lands in the frame.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::bounds::reference_flux;
use flarebench_sdk::ghost::monte_carlo::{
    GhostRays, McBand, McEstimate, McGhost, McImages, McSettings, estimate, path_flux,
};
use flarebench_sdk::ghost::{GhostPath, GridTrace};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::trace::{InterfaceTableSet, Sequence};
use serde::Serialize;

use crate::GhostRenderError;
use crate::colour::{Bin, GhostColours};
use crate::ghosts::{self, RenderOptions};
use crate::plan::{self, BOUNDS_LAMBDA_NM, DropReason, GhostJob, LightPlan, PlanOptions};
use crate::reference;
use crate::scene::{LightSpec, Quality};

/// What to compare.
#[derive(Clone, Debug)]
pub struct CrosscheckOptions {
    pub mc: McSettings,
    /// The renderer's preset.
    pub quality: Quality,
    /// Render the mesh reference too (slow on lenses of many ghosts).
    pub reference: bool,
    /// Only these ghosts (all when empty).
    pub ghosts: Vec<GhostPath>,
    /// How the Monte-Carlo image estimate's rays are shared among the ghosts.
    pub allot: Allot,
}

/// How the Monte-Carlo image estimate shares its rays (`mc.rays` times the ghosts) among the
/// ghosts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Allot {
    /// `mc.rays` each: every ghost's energy gets the same relative error bar, whatever its
    /// flux (the figure for comparing ghost by ghost).
    #[default]
    Even,
    /// In proportion to each ghost's flux in the frame, measured by a pilot run of an eighth of
    /// the rays (at least one ray a band and batch each): a ghost of flux `F` drawn with `N`
    /// rays adds about `F²/N` to the image's summed squared noise, least for a given total at
    /// `N ∝ F`. The whole image's noise falls; dim ghosts' own error bars grow.
    Flux,
}

/// The pilot run's seed, apart from the estimate's streams.
const PILOT_SEED: u64 = 0x9170_7a11_07ed;

/// A ghost's image as one renderer drew it (alone in the frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ImageMoments {
    /// Luminance summed over the frame (image units).
    pub energy: f64,
    /// Flux-weighted centroid of the luminance (pixels; pixel centres at half-integers).
    pub centroid_px: [f64; 2],
    /// Central second moments (px²): xx, xy, yy.
    pub moments_px2: [f64; 3],
}

impl ImageMoments {
    /// The luminance moments of `img`.
    pub fn of(img: &HdrImage) -> ImageMoments {
        let mut s = [0.0_f64; 6];
        for (k, p) in img.pixels.iter().enumerate() {
            let l = 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
            let x = (k % img.width) as f64 + 0.5;
            let y = (k / img.width) as f64 + 0.5;
            s[0] += l;
            s[1] += l * x;
            s[2] += l * y;
            s[3] += l * x * x;
            s[4] += l * x * y;
            s[5] += l * y * y;
        }
        if s[0] <= 0.0 {
            return ImageMoments::default();
        }
        let c = [s[1] / s[0], s[2] / s[0]];
        ImageMoments {
            energy: s[0],
            centroid_px: c,
            moments_px2: [
                s[3] / s[0] - c[0] * c[0],
                s[4] / s[0] - c[0] * c[1],
                s[5] / s[0] - c[1] * c[1],
            ],
        }
    }
}

/// One ghost's row.
#[derive(Clone, Debug, Serialize)]
pub struct GhostRow {
    pub path: String,
    /// Energy share at 550 nm: Monte-Carlo (its error bar propagated from the ghost's and the
    /// direct flux's) and the bounds search's (`None`: reported as having no light).
    pub mc_share: McEstimate,
    pub bounds_share: Option<f64>,
    /// The Monte-Carlo image estimate (`None` for a ghost without a sequence).
    #[serde(skip)]
    pub mc: Option<McGhost>,
    pub mc_energy: McEstimate,
    pub mc_centroid_px: [f64; 2],
    pub mc_centroid_err_px: [f64; 2],
    pub mc_moments_px2: [f64; 3],
    /// Rays the Monte-Carlo image estimate traced.
    pub mc_rays: usize,
    /// The Monte-Carlo image's moments, from pixel centres as the other two images' are (the
    /// like-for-like figure for a ghost a few pixels across, where the exact moments above
    /// differ from any image's by the pixels' own 1/12 px² and more).
    pub mc_image: ImageMoments,
    /// The mesh reference's image of the ghost (`None` when not rendered, or it has no job).
    pub reference: Option<ImageMoments>,
    /// The renderer's (`None` when the plan left it out: `dropped` says why).
    pub renderer: Option<ImageMoments>,
    pub dropped: Option<DropReason>,
    /// This ghost's image against its Monte-Carlo image: relative RMSE of the mesh reference's
    /// and of the renderer's, and the Monte-Carlo image's own noise (each over the ghost's own
    /// Monte-Carlo image; `None` where there is no image or it is black).
    pub image: GhostImageErrors,
}

/// One ghost's image errors against its Monte-Carlo image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GhostImageErrors {
    /// Relative RMSE over the ghost's own Monte-Carlo image.
    pub reference_rmse: Option<f64>,
    pub renderer_rmse: Option<f64>,
    pub mc_noise: Option<f64>,
    /// √Σ(a − b)² of this ghost's image over √Σb² of all the compared ghosts' Monte-Carlo
    /// image: what it adds to the whole image's error (exactly, where ghosts do not overlap).
    pub reference_share: Option<f64>,
    pub renderer_share: Option<f64>,
}

/// The whole comparison for one light.
#[derive(Debug, Serialize)]
pub struct Crosscheck {
    pub ghosts: Vec<GhostRow>,
    /// The on-axis direct flux at 550 nm (mm², unit irradiance): Monte-Carlo and the bounds'
    /// `reference_flux`.
    pub direct_mc: McEstimate,
    pub direct_bounds: f64,
    /// All compared ghosts together: relative RMSE of the mesh reference's and the renderer's
    /// images against the Monte-Carlo image, and that image's own noise (relative RMSE).
    pub reference_rmse: Option<f64>,
    pub renderer_rmse: f64,
    pub mc_noise: f64,
    #[serde(skip)]
    pub images: CrosscheckImages,
}

/// The three images of the compared ghosts.
#[derive(Debug)]
pub struct CrosscheckImages {
    pub mc: McImages,
    pub reference: Option<HdrImage>,
    pub renderer: HdrImage,
}

impl Default for CrosscheckImages {
    fn default() -> Self {
        CrosscheckImages {
            mc: McImages::new(&Frame::across_film(1, 1, 1.0)),
            reference: None,
            renderer: HdrImage::new(1, 1),
        }
    }
}

/// A plan of one ghost of `lp`.
fn alone(lp: &LightPlan, job: &GhostJob) -> LightPlan {
    LightPlan {
        light: lp.light.clone(),
        bands: lp.bands.clone(),
        sampled: lp.sampled,
        ghosts: vec![job.clone()],
        dropped: Vec::new(),
        reflections: lp.reflections,
        not_in_table: Vec::new(),
        culled_share: 0.0,
    }
}

/// `job` drawn alone with `options`.
fn draw_alone(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lp: &LightPlan,
    job: &GhostJob,
    options: RenderOptions,
) -> Result<HdrImage, GhostRenderError> {
    Ok(ghosts::render_with(system, aperture, frame, &[alone(lp, job)], options)?.0)
}

/// Compares the three estimates of every ghost of `light`.
pub fn crosscheck(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    light: &LightSpec,
    opts: &CrosscheckOptions,
) -> Result<Crosscheck, GhostRenderError> {
    let lights = std::slice::from_ref(light);
    let theta = light.theta_deg.to_radians();
    let phi = light.phi_deg.to_radians();
    let chosen = |p: GhostPath| opts.ghosts.is_empty() || opts.ghosts.contains(&p);
    // The mesh reference's plan: every ghost with light, at its bands and colours, which the
    // Monte-Carlo reference traces too.
    let ref_plan = reference::reference_plans(system, lights, &frame, 1.0)?
        .pop()
        .expect("one plan per light");
    let preset = plan::plan(
        system,
        lights,
        &frame,
        &PlanOptions::for_quality(opts.quality, None),
    )?
    .pop()
    .expect("one plan per light");
    let tables = InterfaceTableSet::for_system(system, BOUNDS_LAMBDA_NM);
    let direct_bounds = reference_flux(system, &tables, &mut GridTrace::default());
    let direct_mc = path_flux(
        system,
        &Sequence::forward(system, BOUNDS_LAMBDA_NM),
        0.0,
        &opts.mc,
    );
    // Ghosts the plans found no light in are traced in the colours of 31 equal bins.
    let colours = GhostColours::new(system, light.spectrum, light.intensity as f32)?;
    let fallback_bins: Vec<Bin> = (0..31).map(|i| Bin::new(system, 31, i)).collect();
    let mut images = CrosscheckImages {
        mc: McImages::new(&frame),
        reference: opts
            .reference
            .then(|| HdrImage::new(frame.width, frame.height)),
        renderer: HdrImage::new(frame.width, frame.height),
    };
    let band_by_band = RenderOptions {
        band_by_band: true,
        ..RenderOptions::default()
    };
    let mut rows = Vec::new();
    let mut ghost_errors = Vec::new();
    let paths: Vec<GhostPath> = ref_plan
        .ghosts
        .iter()
        .map(|g| g.path)
        .chain(ref_plan.dropped.iter().map(|d| d.path))
        .filter(|&p| chosen(p))
        .collect();
    let light_beam = (theta, phi, 1.0);
    let mc_settings = McSettings {
        batches: opts.mc.batches.max(2),
        ..opts.mc
    };
    // Every ghost's bands (the mesh reference's, in its colours) and its rays.
    let mut traced: Vec<(GhostPath, Vec<McBand>, Option<GhostRays<'_>>)> = paths
        .iter()
        .map(|&path| {
            let bands: Vec<McBand> = match ref_plan.ghosts.iter().find(|g| g.path == path) {
                Some(job) => job
                    .bands
                    .iter()
                    .map(|b| McBand {
                        lambda_nm: ref_plan.bands[b.band].lambda_nm,
                        rgb: b.rgb,
                    })
                    .collect(),
                None => fallback_bins
                    .iter()
                    .map(|bin| McBand {
                        lambda_nm: bin.centre_nm,
                        rgb: colours.bin_colour(path, bin),
                    })
                    .collect(),
            };
            let lambdas: Vec<f64> = bands.iter().map(|b| b.lambda_nm).collect();
            let rays = GhostRays::new(
                system,
                aperture,
                &frame,
                path,
                light_beam,
                &lambdas,
                &mc_settings,
            );
            (path, bands, rays)
        })
        .collect();
    if opts.allot == Allot::Flux {
        allot_by_flux(&mut traced, &frame, &mc_settings);
    }
    for (path, bands, rays) in &traced {
        let path = *path;
        let ref_job = ref_plan.ghosts.iter().find(|g| g.path == path);
        let mut mc_images = McImages::new(&frame);
        let mc = rays
            .as_ref()
            .map(|r| estimate(r, bands, &frame, Some(&mut mc_images)));
        images.mc.add(&mc_images);
        let mc_share = match Sequence::ghost_path(system, BOUNDS_LAMBDA_NM, &path) {
            Ok(seq) => {
                let g = path_flux(system, &seq, theta, &opts.mc);
                let mean = g.mean / direct_mc.mean;
                let rel = (g.relative_error().powi(2) + direct_mc.relative_error().powi(2)).sqrt();
                McEstimate {
                    mean,
                    std_error: if g.mean > 0.0 {
                        rel * mean
                    } else {
                        g.std_error / direct_mc.mean
                    },
                }
            }
            Err(_) => McEstimate::default(),
        };
        let bounds_share = ref_job.map(|g| g.energy_share);
        let mut errors = ImageErrors::new(&mc_images);
        let reference = match (ref_job, images.reference.as_mut()) {
            (Some(job), Some(all)) => {
                let img = draw_alone(system, aperture, frame, &ref_plan, job, band_by_band)?;
                add_into(all, &img);
                errors.reference = Some(sum_sq(&img, Some(&mc_images.image)));
                Some(ImageMoments::of(&img))
            }
            _ => None,
        };
        let preset_job = preset.ghosts.iter().find(|g| g.path == path);
        let renderer = match preset_job {
            Some(job) => {
                let img = draw_alone(
                    system,
                    aperture,
                    frame,
                    &preset,
                    job,
                    RenderOptions::default(),
                )?;
                add_into(&mut images.renderer, &img);
                errors.renderer = Some(sum_sq(&img, Some(&mc_images.image)));
                Some(ImageMoments::of(&img))
            }
            None => None,
        };
        let dropped = preset
            .dropped
            .iter()
            .find(|d| d.path == path)
            .map(|d| d.reason);
        rows.push(GhostRow {
            path: path.to_string(),
            mc_share,
            bounds_share,
            mc_energy: mc.as_ref().map(|m| m.flux_in_frame).unwrap_or_default(),
            mc_centroid_px: mc.as_ref().map_or([f64::NAN; 2], |m| m.centroid_px),
            mc_centroid_err_px: mc.as_ref().map_or([f64::NAN; 2], |m| m.centroid_err_px),
            mc_moments_px2: mc.as_ref().map_or([f64::NAN; 3], |m| m.moments_px2),
            mc_rays: mc.as_ref().map_or(0, |m| m.rays),
            mc_image: ImageMoments::of(&mc_images.image),
            mc,
            reference,
            renderer,
            dropped,
            image: GhostImageErrors::default(),
        });
        ghost_errors.push(errors);
    }
    // Each ghost's share of the whole image's error, now that the whole is known.
    let whole = sum_sq(&images.mc.image, None).sqrt();
    for (row, e) in rows.iter_mut().zip(&ghost_errors) {
        row.image = e.summary(whole);
    }
    let rmse = |img: &HdrImage| {
        img.relative_rmse(&images.mc.image)
            .expect("images of the same frame")
    };
    let reference_rmse = images.reference.as_ref().map(rmse);
    let renderer_rmse = rmse(&images.renderer);
    let mc_noise = images.mc.relative_noise();
    Ok(Crosscheck {
        ghosts: rows,
        direct_mc,
        direct_bounds,
        reference_rmse,
        renderer_rmse,
        mc_noise,
        images,
    })
}

/// Shares `settings.rays` times the ghosts among `traced` in proportion to each one's flux in
/// the frame, as a pilot run of an eighth of the rays (from its own random streams) measures
/// it ([`Allot::Flux`]).
fn allot_by_flux(
    traced: &mut [(GhostPath, Vec<McBand>, Option<GhostRays<'_>>)],
    frame: &Frame,
    settings: &McSettings,
) {
    let pilot = (settings.rays / 8).max(1);
    let flux: Vec<f64> = traced
        .iter_mut()
        .map(|(_, bands, rays)| {
            rays.as_mut().map_or(0.0, |r| {
                r.set_rays(pilot, settings.seed ^ PILOT_SEED);
                estimate(r, bands, frame, None).flux_in_frame.mean.max(0.0)
            })
        })
        .collect();
    let total_flux: f64 = flux.iter().sum();
    let total_rays = (settings.rays * traced.len()) as f64;
    for ((_, _, rays), f) in traced.iter_mut().zip(flux) {
        if let Some(r) = rays {
            let share = if total_flux > 0.0 {
                f / total_flux
            } else {
                0.0
            };
            r.set_rays((total_rays * share).round() as usize, settings.seed);
        }
    }
}

/// One ghost's squared image differences against its Monte-Carlo image.
struct ImageErrors {
    /// Σb² of the Monte-Carlo image, and Σ(a − b)² of the mesh reference's and renderer's.
    mc2: f64,
    noise: Option<f64>,
    reference: Option<f64>,
    renderer: Option<f64>,
}

impl ImageErrors {
    fn new(mc: &McImages) -> Self {
        let mc2 = sum_sq(&mc.image, None);
        ImageErrors {
            mc2,
            noise: (mc2 > 0.0).then(|| mc.relative_noise()),
            reference: None,
            renderer: None,
        }
    }

    /// Relative figures, `whole` = √Σb² of every compared ghost's Monte-Carlo image.
    fn summary(&self, whole: f64) -> GhostImageErrors {
        let own = |d2: Option<f64>| d2.filter(|_| self.mc2 > 0.0).map(|d| (d / self.mc2).sqrt());
        let share = |d2: Option<f64>| d2.filter(|_| whole > 0.0).map(|d| d.sqrt() / whole);
        GhostImageErrors {
            reference_rmse: own(self.reference),
            renderer_rmse: own(self.renderer),
            mc_noise: self.noise,
            reference_share: share(self.reference),
            renderer_share: share(self.renderer),
        }
    }
}

/// Σa² over every pixel and channel, or Σ(a − b)² with `b`.
fn sum_sq(a: &HdrImage, b: Option<&HdrImage>) -> f64 {
    match b {
        None => a
            .pixels
            .iter()
            .flatten()
            .map(|&v| f64::from(v).powi(2))
            .sum(),
        Some(b) => a
            .pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
            .sum(),
    }
}

fn add_into(all: &mut HdrImage, img: &HdrImage) {
    for (p, q) in all.pixels.iter_mut().zip(&img.pixels) {
        for c in 0..3 {
            p[c] += q[c];
        }
    }
}

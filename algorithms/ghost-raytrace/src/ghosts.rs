//! Carrying out a plan: every planned ghost of every light rendered into one linear HDR
//! image, ghosts spread over the cores.
//!
//! Ghosts are grouped by their coarse-frame factor ([`GhostJob::downscale`]): each group is
//! drawn into a coarse copy of the frame (full resolution for factor 1) and added to the
//! output by bilinear upsampling (`flarebench_sdk::image::add_upsampled`). Within a group,
//! ghosts are spread over the cores, each chunk of ghosts drawing into its own accumulator.
//!
//! [`GhostJob::downscale`]: crate::plan::GhostJob::downscale

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::render::{
    BandRef, Frame, GhostContext, GhostLight, GhostScratch, GhostStats, render_ghost,
};
use flarebench_sdk::image::{CoarseGrid, HdrImage, add_upsampled_into};
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use rayon::prelude::*;

use crate::GhostRenderError;
use crate::plan::LightPlan;

/// How to carry out a plan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Trace the ghosts' grids in f64 rather than f32.
    pub trace_f64: bool,
}

/// Renders every planned ghost; returns the image and, per light, each ghost's statistics in
/// plan order.
pub fn render(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
) -> Result<(HdrImage, Vec<Vec<GhostStats>>), GhostRenderError> {
    render_with(system, aperture, frame, plans, RenderOptions::default())
}

/// [`render`] with options.
pub fn render_with(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
) -> Result<(HdrImage, Vec<Vec<GhostStats>>), GhostRenderError> {
    let mut img = HdrImage::new(frame.width, frame.height);
    let stats = render_into(system, aperture, frame, plans, options, &mut img.pixels)?;
    Ok((img, stats))
}

/// [`render_with`] adding into `out`, a row-major buffer of `frame`'s size (a plugin host's
/// buffer, say), so that no image of the frame's size is allocated for the result.
pub fn render_into(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    out: &mut [[f32; 3]],
) -> Result<Vec<Vec<GhostStats>>, GhostRenderError> {
    if out.len() != frame.width * frame.height {
        return Err(GhostRenderError::OutputSize {
            width: frame.width,
            height: frame.height,
            len: out.len(),
        });
    }
    let p = analyse(system, LAMBDA_D_NM)?;
    let mut jobs: Vec<(usize, usize, usize)> = plans
        .iter()
        .enumerate()
        .flat_map(|(l, lp)| {
            lp.ghosts
                .iter()
                .enumerate()
                .map(move |(g, job)| (job.downscale.max(1), l, g))
        })
        .collect();
    jobs.sort_unstable();
    let mut stats = Vec::with_capacity(jobs.len());
    for group in jobs.chunk_by(|a, b| a.0 == b.0) {
        let grid = CoarseGrid::for_frame(frame.width, frame.height, group[0].0);
        let ctx = GhostContext {
            system,
            aperture,
            frame: frame.coarse(&grid),
            stop_radius: stop_opening(system),
            f_number: p.f_number,
            trace_f64: options.trace_f64,
        };
        let coarse = render_group(&ctx, plans, group, &mut stats);
        add_upsampled_into(out, frame.width, &coarse, &grid);
    }
    stats.sort_by_key(|&(l, g, _)| (l, g));
    let mut per_light: Vec<Vec<GhostStats>> = plans
        .iter()
        .map(|lp| vec![GhostStats::default(); lp.ghosts.len()])
        .collect();
    for (l, g, s) in stats {
        per_light[l][g] = s;
    }
    Ok(per_light)
}

/// Draws the ghosts `group` (`(factor, light, ghost)`) into one image of `ctx.frame`'s size,
/// appending each ghost's statistics to `stats`.
fn render_group(
    ctx: &GhostContext<'_>,
    plans: &[LightPlan],
    group: &[(usize, usize, usize)],
    stats: &mut Vec<(usize, usize, GhostStats)>,
) -> HdrImage {
    let frame = ctx.frame;
    // One accumulator image per chunk of jobs: few chunks, so few images.
    let chunk = (group.len() / (2 * rayon::current_num_threads())).max(1);
    let (img, group_stats) = group
        .par_iter()
        .with_min_len(chunk)
        .fold(
            || {
                (
                    HdrImage::new(frame.width, frame.height),
                    Vec::new(),
                    GhostScratch::default(),
                )
            },
            |(mut img, mut stats, mut scratch), &(_, l, g)| {
                let lp = &plans[l];
                let job = &lp.ghosts[g];
                let light = GhostLight {
                    theta: lp.light.theta_deg.to_radians(),
                    phi: lp.light.phi_deg.to_radians(),
                    irradiance: 1.0,
                };
                let bands: Vec<BandRef<'_>> = job
                    .bands
                    .iter()
                    .map(|b| BandRef {
                        rgb: b.rgb,
                        ..lp.bands[b.band].as_ref()
                    })
                    .collect();
                let s = render_ghost(
                    ctx,
                    job.path,
                    &job.bounds,
                    job.grid,
                    &light,
                    &bands,
                    &mut scratch,
                    &mut img,
                );
                stats.push((l, g, s));
                (img, stats, scratch)
            },
        )
        .map(|(img, stats, _)| (img, stats))
        .reduce(
            || (HdrImage::new(frame.width, frame.height), Vec::new()),
            |(mut a, mut sa), (b, sb)| {
                a.add_image(&b)
                    .expect("every accumulator has the frame's size");
                sa.extend(sb);
                (a, sa)
            },
        );
    stats.extend(group_stats);
    img
}

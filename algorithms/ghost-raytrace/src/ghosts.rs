//! Carrying out a plan: every planned ghost of every light rendered into one linear HDR
//! image, ghosts spread over the cores.
//!
//! Ghosts are grouped by their coarse-frame factor ([`GhostJob::downscale`]): each group is
//! drawn into a coarse copy of the frame and added to the output by bilinear upsampling, all
//! coarse frames in one pass (`flarebench_sdk::image::upsample_levels_into`, which may also
//! replace what the output held); full-resolution ghosts are then drawn straight into the
//! output. Within a group, each ghost's bands are traced and meshed in
//! parallel, and each batch of meshes is rasterized in one pass, its tiles spread over the
//! cores.
//!
//! [`GhostJob::downscale`]: crate::plan::GhostJob::downscale

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::fringe::mesh_ghost_fringed;
use flarebench_sdk::ghost::render::{
    BandRef, Frame, GhostContext, GhostLight, GhostMesh, GhostStats, mesh_ghost,
    rasterize_ghost_mesh_into,
};
use flarebench_sdk::image::{Blend, CoarseGrid, HdrImage, upsample_levels_into};
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use rayon::prelude::*;

use crate::GhostRenderError;
use crate::colour::bin_edge_nm;
use crate::plan::{GhostJob, LightPlan};

/// How to carry out a plan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Trace the ghosts' grids in f64 rather than f32.
    pub trace_f64: bool,
    /// Draw every band of a dispersive ghost on its own, rather than groups of up to
    /// [`FRINGE_GROUP`] bands as one mesh whose colour fringes are shaded per pixel
    /// (`flarebench_sdk::ghost::fringe`; the default, and where the model does not hold a ghost
    /// is drawn band by band anyway). The reference renderer draws band by band.
    pub band_by_band: bool,
    /// Discard what the output buffer held instead of adding to it ([`render_into`]): the
    /// upsampling pass writes every pixel, so a buffer kept from frame to frame (a live
    /// preview's, the bench's) needs no clearing first. The image is the same, bit for bit.
    pub replace: bool,
}

/// Buffers a renderer keeps from frame to frame ([`render_into_reusing`]): the coarse frames,
/// so that rendering frame after frame does not fault fresh pages in for them.
#[derive(Debug, Default)]
pub struct RenderScratch {
    coarse: Vec<HdrImage>,
}

impl RenderScratch {
    /// A black image of `width × height`: a kept one of that size, cleared, or a new one.
    fn take(&mut self, width: usize, height: usize) -> HdrImage {
        match self
            .coarse
            .iter()
            .position(|i| (i.width, i.height) == (width, height))
        {
            Some(k) => {
                let mut img = self.coarse.swap_remove(k);
                img.fill_black();
                img
            }
            None => HdrImage::new(width, height),
        }
    }
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

/// [`render_with`] adding into `out` (or replacing it, [`RenderOptions::replace`]), a
/// row-major buffer of `frame`'s size (a plugin host's buffer, say), so that no image of the
/// frame's size is allocated for the result.
pub fn render_into(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    out: &mut [[f32; 3]],
) -> Result<Vec<Vec<GhostStats>>, GhostRenderError> {
    let mut scratch = RenderScratch::default();
    render_into_reusing(system, aperture, frame, plans, options, &mut scratch, out)
}

/// [`render_into`] with the coarse frames kept in `scratch` for the next call.
pub fn render_into_reusing(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    scratch: &mut RenderScratch,
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
    let stop_radius = stop_opening(system);
    let ctx_at = |grid: &CoarseGrid| GhostContext {
        system,
        aperture,
        frame: frame.coarse(grid),
        stop_radius,
        f_number: p.f_number,
        trace_f64: options.trace_f64,
    };
    // The coarse groups first, each into its coarse frame; then every coarse frame added to
    // (or replacing) the output in one pass; then the full-resolution group straight into the
    // output. (The same order either way, so replacing gives what adding to black does.)
    let groups: Vec<&[(usize, usize, usize)]> = jobs.chunk_by(|a, b| a.0 == b.0).collect();
    let mut coarse = Vec::new();
    for group in groups.iter().filter(|g| g[0].0 > 1) {
        let grid = CoarseGrid::for_frame(frame.width, frame.height, group[0].0);
        let mut img = scratch.take(grid.width, grid.height);
        render_group(
            &ctx_at(&grid),
            plans,
            group,
            options,
            &mut stats,
            &mut img.pixels,
            grid.width,
        );
        coarse.push((img, grid));
    }
    let levels: Vec<(&HdrImage, &CoarseGrid)> = coarse.iter().map(|(i, g)| (i, g)).collect();
    let blend = if options.replace {
        Blend::Replace
    } else {
        Blend::Add
    };
    upsample_levels_into(out, frame.width, &levels, blend);
    scratch
        .coarse
        .extend(coarse.into_iter().map(|(img, _)| img));
    if let Some(group) = groups.iter().find(|g| g[0].0 == 1) {
        let grid = CoarseGrid::for_frame(frame.width, frame.height, 1);
        render_group(
            &ctx_at(&grid),
            plans,
            group,
            options,
            &mut stats,
            out,
            frame.width,
        );
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

/// Most bands of a ghost drawn as one fringed mesh. A ghost is traced at about two bands per
/// drawn pixel of dispersion, so a group spans up to about 4 drawn pixels: what shifts inside
/// the ghost (its caustic lines, its shading) stays where a group's bands meet. Measured
/// (docs/performance.md): with all bands in one group the Heliar's error at 1920 × 1080 rose
/// from 1.72% to 1.89%; with 8, 1.75% (3: 1.75%, 12: 1.88%).
pub const FRINGE_GROUP: usize = 8;

/// Drawn pixels (of the ghost's sensor rectangle) per grid triangle below which a ghost is
/// drawn band by band: there the fringed meshing (each band's triangle extended to the mean
/// one, the lines fitted, in f64) costs more than the pixels it saves. Measured
/// (docs/performance.md): with every dispersive ghost fringed, the Nikon zoom's fast frame
/// took 72–114 ms against 65–70 ms band by band; from 16 to 64 pixels a triangle, 58–68 ms,
/// with the default frames' gains kept (at 256 they were lost).
pub const FRINGE_MIN_PIXELS: f64 = 32.0;

/// Triangles (about) made before they are rasterized: bounds the memory a group's meshes
/// take (about 40 bytes a vertex, 30 MB at this size) while keeping rasterizer calls few.
const BATCH_TRIANGLES: usize = 1 << 18;

/// Adds the ghosts `group` (`(factor, light, ghost)`) into `pixels`, a row-major buffer of
/// `ctx.frame`'s size (`width` pixels wide), appending each ghost's statistics to `stats`.
/// Each ghost's bands are traced and turned into triangles in parallel, in batches of about
/// [`BATCH_TRIANGLES`]; each batch is rasterized in one pass (tiles in parallel), in plan
/// order, so the image does not depend on the number of threads.
fn render_group(
    ctx: &GhostContext<'_>,
    plans: &[LightPlan],
    group: &[(usize, usize, usize)],
    options: RenderOptions,
    stats: &mut Vec<(usize, usize, GhostStats)>,
    pixels: &mut [[f32; 3]],
    width: usize,
) {
    // Units of work: (index in `group`, a range of that ghost's bands), with their triangle
    // counts: a group of a fringed ghost's bands (split evenly), or one band.
    let px = ctx.frame.pixel_mm();
    let fringed = |job: &GhostJob, triangles: usize| {
        // Worth it where a band's drawn area outweighs the extra meshing of its triangles.
        !options.band_by_band
            && job.spectral()
            && matches!(ctx.aperture, Aperture::Circular)
            && job.bounds.sensor.area() / (px * px) >= FRINGE_MIN_PIXELS * triangles as f64
    };
    let units: Vec<(usize, std::ops::Range<usize>, usize)> = group
        .iter()
        .enumerate()
        .flat_map(|(k, &(_, l, g))| {
            let job = &plans[l].ghosts[g];
            let triangles = 2 * (job.grid.max(2) - 1).pow(2);
            let m = job.bands.len();
            let groups = if fringed(job, triangles) {
                m.div_ceil(FRINGE_GROUP)
            } else {
                m
            };
            (0..groups).map(move |i| (k, i * m / groups..(i + 1) * m / groups, triangles))
        })
        .collect();
    let mut per_ghost = vec![GhostStats::default(); group.len()];
    let mut all = GhostMesh::default();
    let mut start = 0;
    while start < units.len() {
        let mut end = start + 1;
        let mut triangles = units[start].2;
        while end < units.len() && triangles + units[end].2 <= BATCH_TRIANGLES {
            triangles += units[end].2;
            end += 1;
        }
        let meshes: Vec<(GhostMesh, GhostStats)> = units[start..end]
            .par_iter()
            .map_init(
                || (GridTrace::default(), Vec::new()),
                |(grid, grids), (k, range, triangles)| {
                    let (k, triangles) = (*k, *triangles);
                    let (_, l, g) = group[k];
                    let lp = &plans[l];
                    let job = &lp.ghosts[g];
                    let light = GhostLight {
                        theta: lp.light.theta_deg.to_radians(),
                        phi: lp.light.phi_deg.to_radians(),
                        irradiance: 1.0,
                    };
                    // Most triangles open (or fringed); the rest on an edge, band by band.
                    let mut mesh = GhostMesh::default();
                    mesh.open.reserve(triangles);
                    let band = |b: usize| BandRef {
                        rgb: job.bands[b].rgb,
                        ..lp.bands[job.bands[b].band].as_ref()
                    };
                    let s = if range.len() > 1 {
                        mesh.fringe.reserve(triangles / 2);
                        let bands: Vec<BandRef<'_>> = range.clone().map(band).collect();
                        let m = job.bands.len();
                        let edges: Vec<f64> = (range.start..=range.end)
                            .map(|i| bin_edge_nm(m, i))
                            .collect();
                        mesh_ghost_fringed(
                            ctx,
                            job.path,
                            &job.bounds,
                            job.grid,
                            &light,
                            &bands,
                            &edges,
                            grids,
                            &mut mesh,
                        )
                    } else {
                        mesh.edge.reserve(triangles / 2);
                        mesh_ghost(
                            ctx,
                            job.path,
                            &job.bounds,
                            job.grid,
                            &light,
                            &[band(range.start)],
                            grid,
                            &mut mesh,
                        )
                    };
                    (mesh, s)
                },
            )
            .collect();
        all.clear();
        all.reserve(meshes.iter().map(|(m, _)| m));
        for ((mesh, s), &(k, _, _)) in meshes.iter().zip(&units[start..end]) {
            all.append(mesh);
            let t = &mut per_ghost[k];
            t.rays += s.rays;
            t.triangles += s.triangles;
            t.flux += s.flux;
        }
        drop(meshes);
        rasterize_ghost_mesh_into(pixels, width, &all, ctx.aperture);
        start = end;
    }
    stats.extend(group.iter().zip(per_ghost).map(|(&(_, l, g), s)| (l, g, s)));
}

//! Carrying out a plan: every planned ghost of every light rendered into one linear HDR
//! image, ghosts spread over the cores.
//!
//! Ghosts are grouped by their coarse-frame factor ([`GhostJob::downscale`]): each group is
//! drawn into a coarse copy of the frame and added to the output by bilinear upsampling, all
//! coarse frames in one pass (`flarebench_sdk::image::upsample_spans_into`, which may also
//! replace what the output held; the coarse rows' lit spans it is given are kept with the
//! coarse frames, for the next frame to clear only those); full-resolution ghosts are then
//! drawn straight into the output. Every ghost's bands are traced and meshed in parallel, in
//! batches that take small groups whole (`render_groups`); each group's meshes of a batch are
//! rasterized in one pass, its tiles spread over the cores.
//!
//! [`GhostJob::downscale`]: crate::plan::GhostJob::downscale

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::context::{BandRef, GhostContext, GhostGrid, GhostLight, GhostStats};
use flarebench_sdk::ghost::fringe::mesh_ghost_fringed;
use flarebench_sdk::ghost::mesh::GhostMesh;
use flarebench_sdk::ghost::render::{mesh_ghost, rasterize_ghost_mesh_with, splat_ghost};
use flarebench_sdk::ghost::sink::{FrameLevels, GhostSink};
use flarebench_sdk::image::{
    Blend, CoarseGrid, HdrImage, RowSpans, SpannedLevel, row_spans, upsample_spans_into,
};
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::raster::Coverage;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use rayon::prelude::*;

use crate::GhostRenderError;
use crate::colour::bin_edge_nm;
use crate::plan::{DrawMethod, GhostJob, LightPlan};

/// How to carry out a plan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Trace the ghosts' grids in f64 rather than f32 (lights beyond [`F64_ABOVE_DEG`] are
    /// traced in f64 either way).
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
    /// Rasterize every triangle with exact coverage ([`Coverage::Exact`]) instead of the
    /// renderer's ([`FrameLevels::GHOSTS`]: large triangles point-sampled at pixel centres).
    /// The image is then a continuous function of the meshes' vertices: a pixel centre lying
    /// within a hair of an edge shared by two triangles of different brightness does not
    /// change owner when a vertex moves by a rounding. `stability` compares f32 with f64
    /// traces this way, so that the comparison measures the trace.
    pub exact_coverage: bool,
}

/// Buffers a renderer keeps from frame to frame ([`render_into_reusing`]): the coarse frames,
/// so that rendering frame after frame does not fault fresh pages in for them (those of the
/// last frame's size, one per coarse factor), each with the spans of its rows that frame lit
/// (found by its upsampling pass), which are all the next frame clears.
#[derive(Debug, Default)]
pub struct RenderScratch {
    coarse: Vec<(HdrImage, RowSpans)>,
}

impl RenderScratch {
    /// A black image of `width × height`: a kept one of that size, cleared where its last
    /// frame lit it, or a new one.
    fn take(&mut self, width: usize, height: usize) -> HdrImage {
        match self
            .coarse
            .iter()
            .position(|(i, _)| (i.width, i.height) == (width, height))
        {
            Some(k) => {
                let (mut img, spans) = self.coarse.swap_remove(k);
                img.clear_spans(&spans);
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
    let mut targets = Targets::new(scratch, aperture, out, frame.width, options.replace);
    let stats = draw_into(system, aperture, frame, plans, options, &mut targets)?;
    targets.keep(frame);
    Ok(stats)
}

/// Each light's plan without its ghosts (nothing drawn, nothing dropped): the base a single
/// ghost's own plan is made from.
pub(crate) fn without_ghosts(plans: &[LightPlan]) -> Vec<LightPlan> {
    plans
        .iter()
        .map(|p| LightPlan {
            ghosts: Vec::new(),
            dropped: Vec::new(),
            light: p.light.clone(),
            bands: p.bands.clone(),
            not_in_table: Vec::new(),
            ..*p
        })
        .collect()
}

/// Renders every planned ghost alone, each into a black image of the frame's size, and hands
/// it to `each` with its light's index and its job: what a per-ghost comparison (`flarebench
/// sweep`) measures. Ghosts are rendered in parallel; returns what `each` returned, in plan
/// order, and the sum of the ghosts' images (the frame's image but for the order of the f32
/// additions).
pub fn render_each_ghost<R: Send>(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    each: impl Fn(usize, &GhostJob, &HdrImage) -> R + Sync,
) -> Result<(Vec<R>, HdrImage), GhostRenderError> {
    let options = RenderOptions {
        replace: false,
        ..options
    };
    // Each light's plan without its ghosts: a ghost's own plan is this with the ghost added.
    let empty = without_ghosts(plans);
    let jobs: Vec<(usize, usize, &GhostJob)> = plans
        .iter()
        .enumerate()
        .flat_map(|(li, p)| p.ghosts.iter().map(move |g| (li, g)))
        .enumerate()
        .map(|(i, (li, g))| (i, li, g))
        .collect();
    type Acc<R> = (Option<HdrImage>, Vec<(usize, R)>);
    let new_acc = || -> Result<Acc<R>, GhostRenderError> { Ok((None, Vec::new())) };
    let (sum, mut out) = jobs
        .par_iter()
        .fold(
            || {
                (
                    new_acc(),
                    HdrImage::new(frame.width, frame.height),
                    RenderScratch::default(),
                )
            },
            |(acc, mut image, mut scratch), &(i, li, job)| {
                let acc = acc.and_then(|(sum, mut out)| {
                    let mut plan = empty[li].clone();
                    plan.ghosts.push(job.clone());
                    image.fill_black();
                    render_into_reusing(
                        system,
                        aperture,
                        frame,
                        std::slice::from_ref(&plan),
                        options,
                        &mut scratch,
                        &mut image.pixels,
                    )?;
                    out.push((i, each(li, job, &image)));
                    let mut sum = sum.unwrap_or_else(|| HdrImage::new(frame.width, frame.height));
                    add_into(&mut sum, &image);
                    Ok((Some(sum), out))
                });
                (acc, image, scratch)
            },
        )
        .map(|(acc, _, _)| acc)
        .reduce(new_acc, |a, b| {
            let ((sa, mut oa), (sb, ob)) = (a?, b?);
            oa.extend(ob);
            let sum = match (sa, sb) {
                (Some(mut x), Some(y)) => {
                    add_into(&mut x, &y);
                    Some(x)
                }
                (x, y) => x.or(y),
            };
            Ok((sum, oa))
        })?;
    out.sort_by_key(|(i, _)| *i);
    Ok((
        out.into_iter().map(|(_, r)| r).collect(),
        sum.unwrap_or_else(|| HdrImage::new(frame.width, frame.height)),
    ))
}

/// `sum += img`, pixel by pixel.
fn add_into(sum: &mut HdrImage, img: &HdrImage) {
    for (o, p) in sum.pixels.iter_mut().zip(&img.pixels) {
        for c in 0..3 {
            o[c] += p[c];
        }
    }
}

/// Keeps `coarse` (with their lit `spans`) in `scratch`, and only what a frame of `frame`'s
/// size can use again (factors 2 to 64, the largest a plan may ask for): a resized frame's
/// are let go.
fn scratch_keep(
    scratch: &mut RenderScratch,
    coarse: Vec<HdrImage>,
    spans: Vec<RowSpans>,
    frame: Frame,
) {
    scratch.coarse.extend(coarse.into_iter().zip(spans));
    scratch.coarse.retain(|(img, _)| {
        (1..=6).any(|k| {
            let g = CoarseGrid::for_frame(frame.width, frame.height, 1 << k);
            (g.width, g.height) == (img.width, img.height)
        })
    });
}

/// Makes every planned ghost's triangles and hands them to `sink`
/// (`flarebench_sdk::ghost::sink`): the levels first (the coarse frames the plan's coarse
/// factors ask for, then the full-resolution frame if some ghost is drawn there), then each
/// level's meshes, in batches, in plan order. Returns, per light, each ghost's statistics in
/// plan order. The CPU renderer ([`render_into_reusing`]) and the GPU backend both draw
/// through this.
pub fn draw_into(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    plans: &[LightPlan],
    options: RenderOptions,
    sink: &mut dyn GhostSink,
) -> Result<Vec<Vec<GhostStats>>, GhostRenderError> {
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
    let stop_radius = stop_opening(system);
    // The coarse groups first, then the full-resolution one (factor 1 sorts first).
    let mut groups: Vec<&[(usize, usize, usize)]> = jobs.chunk_by(|a, b| a.0 == b.0).collect();
    let full_first = groups.first().is_some_and(|g| g[0].0 == 1);
    groups.rotate_left(usize::from(full_first));
    let grids: Vec<CoarseGrid> = groups
        .iter()
        .map(|g| CoarseGrid::for_frame(frame.width, frame.height, g[0].0))
        .collect();
    let ctxs: Vec<GhostContext<'_>> = grids
        .iter()
        .map(|grid| GhostContext {
            system,
            aperture,
            frame: frame.coarse(grid),
            stop_radius,
            f_number: p.f_number,
            trace_f64: options.trace_f64,
        })
        .collect();
    sink.begin(FrameLevels {
        frame,
        grids: &grids,
        aperture,
        coverage: if options.exact_coverage {
            Coverage::Exact
        } else {
            FrameLevels::GHOSTS
        },
    });
    let per_ghost = render_groups(&ctxs, plans, &groups, options, sink);
    sink.finish();
    let mut per_light: Vec<Vec<GhostStats>> = plans
        .iter()
        .map(|lp| vec![GhostStats::default(); lp.ghosts.len()])
        .collect();
    for (group, stats) in groups.iter().zip(per_ghost) {
        for (&(_, l, g), s) in group.iter().zip(stats) {
            per_light[l][g] = s;
        }
    }
    Ok(per_light)
}

/// Lights farther off axis than this (degrees) have their ghosts traced in f64 whatever
/// [`RenderOptions::trace_f64`] says: at grazing incidence the f32 trace is no longer close
/// (`flarebench stability`: the Kreitzer telephoto's one ghost at 89° differed from f64 by
/// 1.3% relative RMSE, where every lens inside its field agrees to 4e-4 or better), and such
/// lights have few ghosts.
pub const F64_ABOVE_DEG: f64 = 80.0;

/// Most bands of a ghost drawn as one fringed mesh. A ghost is traced at about two bands per
/// drawn pixel of dispersion, so a group spans up to about 4 drawn pixels: what shifts inside
/// the ghost (its caustic lines, its shading) stays where a group's bands meet. Measured on
/// the Heliar at 1920 × 1080 (1.72% band by band): all bands in one group 1.89%, groups of 12
/// 1.88%, of 8 or of 3 1.75%; 8 is the largest that keeps the error.
pub const FRINGE_GROUP: usize = 8;

/// Drawn pixels (of the ghost's sensor rectangle) per grid triangle below which a ghost is
/// drawn band by band: there the fringed meshing (each band's triangle extended to the mean
/// one, the lines fitted, in f64) costs more than the pixels it saves. Measured on the Nikon
/// zoom's fast frame: with every dispersive ghost fringed it takes 72–114 ms against 65–70 ms
/// band by band; with a threshold from 16 to 64 pixels a triangle, 58–68 ms, and the default
/// frames keep their gain from the fringe (at 256 they lose it).
pub const FRINGE_MIN_PIXELS: f64 = 32.0;

/// Triangles (about) made before they are rasterized: bounds the memory a batch's meshes
/// take (about 40 bytes a vertex, 30 MB at this size) while keeping rasterizer calls few.
const BATCH_TRIANGLES: usize = 1 << 18;

/// The CPU rasterizer as a [`GhostSink`]: each coarse level drawn into its coarse frame
/// (taken from the scratch); those added to (or replacing) the output in one pass once every
/// coarse ghost is drawn; the full-resolution level then straight into the output. (The same
/// order either way, so replacing gives what adding to black does.)
pub(crate) struct Targets<'a> {
    scratch: &'a mut RenderScratch,
    grids: Vec<CoarseGrid>,
    coarse: Vec<HdrImage>,
    aperture: &'a Aperture,
    out: &'a mut [[f32; 3]],
    width: usize,
    blend: Blend,
    /// How the frame's triangles cover pixels (from [`FrameLevels::coverage`]).
    coverage: Coverage,
    /// Each coarse frame's lit rows, once the upsampling pass has found them.
    spans: Option<Vec<RowSpans>>,
}

impl<'a> Targets<'a> {
    /// Targets drawing into `out` (`width` pixels a row), adding to it or, with `replace`,
    /// replacing it, with coarse frames taken from `scratch`.
    pub(crate) fn new(
        scratch: &'a mut RenderScratch,
        aperture: &'a Aperture,
        out: &'a mut [[f32; 3]],
        width: usize,
        replace: bool,
    ) -> Targets<'a> {
        Targets {
            scratch,
            grids: Vec::new(),
            coarse: Vec::new(),
            aperture,
            out,
            width,
            blend: if replace { Blend::Replace } else { Blend::Add },
            coverage: FrameLevels::GHOSTS,
            spans: None,
        }
    }

    /// Once the frame is drawn: the coarse frames go back to the scratch with the spans their
    /// upsampling found.
    pub(crate) fn keep(mut self, frame: Frame) {
        let spans = self.spans.take().unwrap_or_default();
        let coarse = std::mem::take(&mut self.coarse);
        scratch_keep(self.scratch, coarse, spans, frame);
    }

    /// The upsampling pass, once.
    fn upsample(&mut self) {
        if self.spans.is_none() {
            let spans: Vec<RowSpans> = self.coarse.iter().map(row_spans).collect();
            let levels: Vec<SpannedLevel<'_>> = self
                .coarse
                .iter()
                .zip(&self.grids)
                .zip(&spans)
                .map(|((img, grid), spans)| (img, grid, spans.as_slice()))
                .collect();
            upsample_spans_into(self.out, self.width, &levels, self.blend);
            self.spans = Some(spans);
        }
    }
}

impl GhostSink for Targets<'_> {
    fn begin(&mut self, levels: FrameLevels<'_>) {
        self.grids = levels.grids.to_vec();
        self.coverage = levels.coverage;
        let coarse_count = levels.coarse_count();
        self.coarse = self.grids[..coarse_count]
            .iter()
            .map(|g| self.scratch.take(g.width, g.height))
            .collect();
        self.spans = None;
    }

    fn draw(&mut self, level: usize, mesh: &GhostMesh) {
        if level < self.coarse.len() {
            let width = self.grids[level].width;
            let pixels = &mut self.coarse[level].pixels;
            rasterize_ghost_mesh_with(pixels, width, mesh, self.aperture, self.coverage);
        } else {
            // Every coarse ghost is drawn.
            self.upsample();
            rasterize_ghost_mesh_with(self.out, self.width, mesh, self.aperture, self.coverage);
        }
    }

    fn finish(&mut self) {
        self.upsample();
    }
}

/// Draws the ghosts of `groups` (each `(factor, light, ghost)`, coarse groups first; their
/// contexts `ctxs`) into `targets`, returning each group's ghosts' statistics in its order.
/// The ghosts' bands of every group are traced and turned into triangles in parallel, in
/// batches of about [`BATCH_TRIANGLES`]; each group's meshes of a batch are joined and
/// rasterized, its tiles in parallel, its triangles in plan order, so the image does not
/// depend on the number of threads. (Drawing a batch's coarse groups side by side, each
/// rasterized in parallel, is slower: the Heliar's default frame 25 against 21 ms.)
fn render_groups(
    ctxs: &[GhostContext<'_>],
    plans: &[LightPlan],
    groups: &[&[(usize, usize, usize)]],
    options: RenderOptions,
    sink: &mut dyn GhostSink,
) -> Vec<Vec<GhostStats>> {
    // Units of work, group by group: (group, index in it, a range of that ghost's bands, its
    // triangle count): a group of a fringed ghost's bands (split evenly), or one band.
    let fringed = |ctx: &GhostContext<'_>, job: &GhostJob, triangles: usize| {
        // Worth it where a band's drawn area outweighs the extra meshing of its triangles.
        let px = ctx.frame.pixel_mm();
        !options.band_by_band
            && job.method == DrawMethod::Mesh
            && job.spectral()
            && job.bounds.sensor.area() / (px * px) >= FRINGE_MIN_PIXELS * triangles as f64
    };
    let units: Vec<(usize, usize, std::ops::Range<usize>, usize)> = groups
        .iter()
        .enumerate()
        .flat_map(|(gi, group)| {
            let ctx = &ctxs[gi];
            group.iter().enumerate().flat_map(move |(k, &(_, l, g))| {
                let job = &plans[l].ghosts[g];
                let triangles = 2 * (job.grid.max(2) - 1).pow(2);
                let m = job.bands.len();
                let parts = if fringed(ctx, job, triangles) {
                    m.div_ceil(FRINGE_GROUP)
                } else {
                    m
                };
                (0..parts).map(move |i| (gi, k, i * m / parts..(i + 1) * m / parts, triangles))
            })
        })
        .collect();
    let mut per_ghost: Vec<Vec<GhostStats>> = groups
        .iter()
        .map(|g| vec![GhostStats::default(); g.len()])
        .collect();
    // Each group's triangles: a batch takes in a next group only whole (the small groups of a
    // frame meshed together, their work spread over the cores at once; a large group split
    // into batches of its own: on the Nikon zoom, batches across groups are 5–7% slower).
    let mut group_triangles = vec![0; groups.len()];
    for u in &units {
        group_triangles[u.0] += u.3;
    }
    let mut all = GhostMesh::default();
    let mut start = 0;
    while start < units.len() {
        let mut end = start + 1;
        let mut triangles = units[start].3;
        while end < units.len() {
            let next = &units[end];
            let fits = if next.0 == units[end - 1].0 {
                triangles + next.3 <= BATCH_TRIANGLES
            } else {
                triangles + group_triangles[next.0] <= BATCH_TRIANGLES
            };
            if !fits {
                break;
            }
            triangles += next.3;
            end += 1;
        }
        let meshes: Vec<(GhostMesh, GhostStats)> = units[start..end]
            .par_iter()
            .map_init(
                || (GridTrace::default(), Vec::new()),
                |(grid, grids), (gi, k, range, triangles)| {
                    let (_, l, g) = groups[*gi][*k];
                    let lp = &plans[l];
                    let grazing = GhostContext {
                        trace_f64: true,
                        ..ctxs[*gi]
                    };
                    let ctx = if lp.light.theta_deg > F64_ABOVE_DEG {
                        &grazing
                    } else {
                        &ctxs[*gi]
                    };
                    let triangles = *triangles;
                    let job = &lp.ghosts[g];
                    let light = GhostLight {
                        theta: lp.light.theta_deg.to_radians(),
                        phi: lp.light.phi_deg.to_radians(),
                        irradiance: 1.0,
                    };
                    let ghost = GhostGrid {
                        path: job.path,
                        bounds: &job.bounds,
                        n: job.grid,
                        light,
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
                        mesh_ghost_fringed(ctx, &ghost, &bands, &edges, grids, &mut mesh)
                    } else {
                        mesh.edge.reserve(triangles / 2);
                        let draw = match job.method {
                            DrawMethod::Mesh => mesh_ghost,
                            DrawMethod::Splat => splat_ghost,
                        };
                        draw(ctx, &ghost, &[band(range.start)], grid, &mut mesh)
                    };
                    (mesh, s)
                },
            )
            .collect();
        for ((_, s), &(gi, k, _, _)) in meshes.iter().zip(&units[start..end]) {
            let t = &mut per_ghost[gi][k];
            t.rays += s.rays;
            t.triangles += s.triangles;
            t.flux += s.flux;
        }
        // Group by group (the units are in group order), its meshes of the batch in plan
        // order, into one mesh and rasterized.
        let mut i = 0;
        while i < meshes.len() {
            let gi = units[start + i].0;
            let j = i + units[start + i..end].partition_point(|u| u.0 == gi);
            all.clear();
            all.reserve(meshes[i..j].iter().map(|(m, _)| m));
            for (mesh, _) in &meshes[i..j] {
                all.append(mesh);
            }
            sink.draw(gi, &all);
            i = j;
        }
        drop(meshes);
        start = end;
    }
    per_ghost
}

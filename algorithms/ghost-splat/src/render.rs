//! The splat render: every two-reflection ghost of every light, its rays traced by the sdk's
//! Monte-Carlo tracer ([`GhostRays`]) and splatted with the [`Kernel`] into the frame.
//!
//! **Rays.** Per light, wavelength band and ghost, the rays are those of
//! `flarebench_sdk::ghost::monte_carlo`: a pilot grid of [`PILOT`]² entrance points finds the
//! ghost's active cells; the `rays` rays per ghost, shared among its bands, are stratified
//! over them, gathered on the cells whose light lands in the frame ([`OUTSIDE_WEIGHT`]: the
//! others are sampled at that density, each of their rays weighed up by its inverse, so the
//! image stays unbiased). A ray's flux (its stratum's area × cos θ × the light's intensity ×
//! exact Fresnel/coating throughput × aperture transmission at the stop) times its band's
//! colour ([`crate::colour`]) is its energy, in the ray-traced renderer's image units. Above [`MAX_JOB_RAYS`] rays per band the rays are
//! split into independent batches of that size, each at `1/batches` weight.
//!
//! **Order.** Jobs (ghost, band, batch) are traced in parallel a wave at a time, each into its
//! own list of landed rays (reserved to its ray count: no allocation per ray); the lists
//! are then splatted in job order, in parallel over strips of rows, into an f64 frame. Each
//! pixel receives its rays in the same order whatever the thread count, so the image is the
//! same bit for bit for a seed.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::monte_carlo::{GhostRays, McSettings};
use rayon::prelude::*;

use crate::colour::BandSampling;
use crate::error::SplatError;
use crate::kernel::Kernel;

/// Pilot grid vertices a side over the entry square (the Monte-Carlo reference's default is
/// 129; 65 keeps a ghost's pilot at 2 × 65² traces).
pub const PILOT: usize = 65;
/// Sampling density of the entry cells whose light lands outside the frame, relative to the
/// others (`McSettings::outside_weight`).
pub const OUTSIDE_WEIGHT: f64 = 1.0 / 16.0;
/// Most rays of one band in one batch: more are split into batches, bounding the lists a
/// wave holds (16 bytes of position and 24 of energy a ray).
pub const MAX_JOB_RAYS: usize = 1 << 16;
/// Most wavelength bands.
pub const MAX_BANDS: usize = 64;

/// What a splat render traces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatSettings {
    /// Rays per ghost and light, over all its bands (at least one per band is traced).
    pub rays: usize,
    pub kernel: Kernel,
    /// Wavelength bands, `1..=MAX_BANDS`.
    pub bands: usize,
    /// Seed of every random stream.
    pub seed: u64,
}

impl SplatSettings {
    /// Checked settings from the plugin's parameter values: `rays` and `bands` at least 1
    /// (`bands` at most [`MAX_BANDS`]), `kernel_px` as [`Kernel::new`] takes it, `seed` not
    /// negative.
    pub fn new(rays: i64, kernel_px: f64, bands: i64, seed: i64) -> Result<Self, SplatError> {
        let positive = |v: i64, what: &'static str| match usize::try_from(v) {
            Ok(n) if n >= 1 => Ok(n),
            _ => Err(SplatError::Zero { what }),
        };
        let bands = positive(bands, "bands")?;
        if bands > MAX_BANDS {
            return Err(SplatError::TooManyBands(bands));
        }
        Ok(SplatSettings {
            rays: positive(rays, "rays")?,
            kernel: Kernel::new(kernel_px)?,
            bands,
            seed: u64::try_from(seed).map_err(|_| SplatError::Seed(seed))?,
        })
    }
}

/// What a render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplatStats {
    /// Ghosts (per light) of which at least one ray reached the sensor with light.
    pub ghosts_drawn: u32,
    /// Rays traced.
    pub rays: usize,
}

/// A ray that landed: where (pixels) and its energy (linear RGB, image units).
#[derive(Clone, Copy, Debug)]
struct Landed {
    px: [f64; 2],
    energy: [f64; 3],
}

/// Buffers kept between renders: the landed rays of a wave's jobs and the f64 frame.
#[derive(Debug, Default)]
pub struct SplatScratch {
    lists: Vec<Vec<Landed>>,
    total: Vec<[f64; 3]>,
}

/// The seed of light `light`'s streams.
fn light_seed(seed: u64, light: usize) -> u64 {
    seed ^ (light as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

/// Adds every ghost of `paths` for every light of `scene` into `out` (the frame's pixels, row
/// 0 at the top), splatted with `settings`.
pub fn render_into(
    system: &LensSystem,
    paths: &[GhostPath],
    scene: &Scene,
    settings: &SplatSettings,
    scratch: &mut SplatScratch,
    out: &mut [[f32; 3]],
) -> Result<SplatStats, SplatError> {
    let frame = scene.frame;
    let n = frame.width * frame.height;
    if out.len() != n {
        return Err(SplatError::OutputSize {
            got: out.len(),
            want: n,
        });
    }
    let mut stats = SplatStats::default();
    if n == 0 {
        return Ok(stats);
    }
    scratch.total.clear();
    scratch.total.resize(n, [0.0; 3]);
    let wave = (2 * rayon::current_num_threads()).max(8);
    for (li, light) in scene.lights.iter().enumerate() {
        let sampling = BandSampling::new(settings.bands, light.spectrum)?;
        let batches = settings.rays.div_ceil(settings.bands * MAX_JOB_RAYS).max(1);
        let mc = McSettings {
            rays: settings.rays,
            batches,
            seed: light_seed(settings.seed, li),
            pilot: PILOT,
            outside_weight: OUTSIDE_WEIGHT,
        };
        let beam = (
            light.theta_deg.to_radians(),
            light.phi_deg.to_radians(),
            light.intensity,
        );
        // Each ghost's rays and band colours; each batch alone estimates the whole image:
        // each at 1/batches.
        let lambdas = sampling.coarse.wavelengths_nm();
        let ghosts: Vec<(GhostRays<'_>, Vec<[f64; 3]>)> = paths
            .iter()
            .filter_map(|&p| {
                let rays = GhostRays::new(system, &scene.aperture, &frame, p, beam, lambdas, &mc)?;
                (rays.rays() > 0).then(|| {
                    let mut c = sampling.colours(system, p);
                    for v in c.iter_mut().flatten() {
                        *v /= batches as f64;
                    }
                    (rays, c)
                })
            })
            .collect();
        let jobs: Vec<(usize, usize, usize)> = ghosts
            .iter()
            .enumerate()
            .flat_map(|(g, (r, _))| {
                (0..r.bands()).flat_map(move |b| (0..r.batches()).map(move |k| (g, b, k)))
            })
            .collect();
        let mut drawn = vec![false; ghosts.len()];
        for wave_jobs in jobs.chunks(wave) {
            if scratch.lists.len() < wave_jobs.len() {
                scratch.lists.resize_with(wave_jobs.len(), Vec::new);
            }
            let lists = &mut scratch.lists[..wave_jobs.len()];
            lists.par_iter_mut().zip(wave_jobs).for_each_init(
                || Vec::with_capacity(64),
                |hits, (list, &(g, b, k))| {
                    let (rays, colours) = &ghosts[g];
                    list.clear();
                    list.reserve(rays.rays() / (rays.bands() * rays.batches()));
                    let c = colours[b];
                    rays.trace(b, k, hits, |ray| {
                        list.push(Landed {
                            px: ray.px,
                            energy: c.map(|v| v * ray.flux),
                        });
                    });
                },
            );
            for (list, &(g, _, _)) in lists.iter().zip(wave_jobs) {
                drawn[g] |= !list.is_empty();
            }
            splat_lists(&mut scratch.total, frame.width, settings.kernel, lists);
        }
        stats.ghosts_drawn += drawn.iter().filter(|&&d| d).count() as u32;
        stats.rays += ghosts.iter().map(|(r, _)| r.rays()).sum::<usize>();
    }
    for (o, t) in out.iter_mut().zip(&scratch.total) {
        for c in 0..3 {
            o[c] += t[c] as f32;
        }
    }
    Ok(stats)
}

/// Splats `lists` in order into `total` (`width` pixels a row), in parallel over strips of
/// rows: each strip takes, from every ray, the part of its splat in its rows.
fn splat_lists(total: &mut [[f64; 3]], width: usize, kernel: Kernel, lists: &[Vec<Landed>]) {
    let height = total.len() / width;
    let strips = (4 * rayon::current_num_threads()).clamp(1, height);
    let rows = height.div_ceil(strips);
    total
        .par_chunks_mut(rows * width)
        .enumerate()
        .for_each(|(s, strip)| {
            let y0 = s * rows;
            let span = (y0, y0 + strip.len() / width);
            for l in lists.iter().flatten() {
                kernel.splat_rows(strip, width, span, l.px, l.energy);
            }
        });
}

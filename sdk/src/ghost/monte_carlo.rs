//! An independent reference for ghost energies and images: forward Monte-Carlo splatting.
//!
//! It shares neither the grids and meshing ([`super::grid`], [`super::triangles`]) nor the
//! rasterizer nor the bounds search ([`super::bounds`]) with the renderer; only the lens model
//! and the scalar f64 tracer ([`Sequence::trace_with_hits`], whose Fresnel/coating factors are
//! evaluated exactly per ray, without the interface tables).
//!
//! **Where rays start.** A pilot grid of `pilot × pilot` vertices over the square that holds
//! every ray entering the front element ([`entry_square`]) is traced at the shortest and the
//! longest wavelength asked for. Each vertex has an excess `e = max(r/semi − 1, ρ_stop/ρ_open −
//! 1)` (its largest relative radius along the path, and its stop crossing over the aperture's
//! farthest open point); it passes where `e ≤ 0`. A cell is *active* when a corner passes, or
//! when its smallest corner excess is at most twice the largest change of `e` along its
//! edges (so a region that falls between the vertices, where `e` dips below 0 between them,
//! is kept), or when a corner's ray stopped (missed a surface, total internal reflection) next
//! to one of those; active cells are then grown by one cell all round. Flux outside the active
//! cells is not sampled: that is the estimator's one assumption, and the pilot's resolution
//! and the slack above are what it rests on.
//!
//! **Sampling.** The rays asked for are shared equally among the bands and batches. When a
//! batch of a band has at least as many rays as there are active cells, every cell is split
//! into `q × q` strata (`q` the largest that keeps to the rays) and each stratum gets one ray
//! at a uniformly jittered point; with fewer rays than cells, the cells (in row order) are
//! split into runs of nearly equal length, one per ray, and each ray starts at a uniform point
//! of a uniformly chosen cell of its run, its stratum the whole run ([`Strata`]). Either way
//! every batch of every band traces at least one ray, and the estimate is unbiased whatever
//! the count: a caller may give a dim ghost a hundredth of a bright one's rays (the image's
//! noise is least with rays in proportion to flux). A ray that completes the path inside
//! every clear semi-diameter carries the flux `E · cos θ · A_stratum · T · τ(stop)`: `T` the exact product of the
//! Fresnel/coating factors along its path, `τ` the aperture's (hard-edged) transmission at its
//! last stop crossing (the renderer's convention, `docs/physics.md`), and `E` the light's
//! irradiance. The flux is added where it lands: to sums for the energy, the centroid and the
//! second moments (in pixels of the frame, exactly where the ray lands) and to the pixel it
//! lands in of an image, in the band's colour (the pixel's flux, as the rasterizer's exact
//! coverage gives it) — the same image units as the renderer (an image's sum is
//! `Σ_band rgb · Φ_band`).
//!
//! **The rays themselves.** [`GhostRays`] (`rays.rs`) prepares one ghost's sequences, active
//! region, strata and random streams and traces any (band, batch), handing each ray that
//! carries light to a closure with its flux and landing pixel: [`ghost_monte_carlo`] sums them,
//! and a splatting renderer (`algorithms/ghost-splat`) draws them.
//!
//! **Error bar.** The `batches` batches are independent estimates (each has one ray per
//! stratum, from its own random stream); the standard error of their mean is `s / √B`, `s` the
//! batches' sample standard deviation. The random streams are seeded from the settings' seed,
//! the ghost path, the band and the batch, so results do not depend on the thread count.

use glam::DVec3;
use rayon::prelude::*;

use crate::aperture::Aperture;
use crate::frame::Frame;
use crate::image::HdrImage;
use crate::system::LensSystem;
use crate::trace::{Hit, Ray, Sequence};

use crate::ghost_path::GhostPath;
use crate::rect::Rect;

/// Luminance weights of linear sRGB (Rec. 709), as the renderer counts a band's flux.
const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// How many rays, in how many batches, from which seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McSettings {
    /// Rays per ghost, over all its bands and batches (at least one per band and batch).
    pub rays: usize,
    /// Independent batches the error bar is measured from (at least 2).
    pub batches: usize,
    /// Seed of every random stream.
    pub seed: u64,
    /// Pilot grid vertices a side over the entry square.
    pub pilot: usize,
    /// Sampling density, relative to the rest, of the active cells whose corners' rays all land
    /// well outside the frame (1: every cell alike). Below 1, rays gather where the image is,
    /// each weighed by the inverse of its density, so every estimate stays unbiased: the
    /// image's and the in-frame flux's noise fall, the whole flux's grows.
    pub outside_weight: f64,
}

impl Default for McSettings {
    fn default() -> Self {
        McSettings {
            rays: 1 << 20,
            batches: 16,
            seed: 0x5eed,
            pilot: 129,
            outside_weight: 1.0,
        }
    }
}

/// A wavelength and the colour it adds (linear sRGB per unit flux, the renderer's band colour).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McBand {
    pub lambda_nm: f64,
    pub rgb: [f32; 3],
}

/// A mean and its standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct McEstimate {
    pub mean: f64,
    pub std_error: f64,
}

impl McEstimate {
    /// The mean and standard error of independent estimates `values` (at least two).
    pub fn of(values: &[f64]) -> McEstimate {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        McEstimate {
            mean,
            std_error: (var / n).sqrt(),
        }
    }

    /// The standard error relative to the mean (∞ for a zero mean).
    pub fn relative_error(&self) -> f64 {
        if self.mean != 0.0 {
            (self.std_error / self.mean).abs()
        } else {
            f64::INFINITY
        }
    }
}

/// The cells of a pilot grid whose rays may carry the ghost's light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct McRegion {
    /// The square the pilot grid spans (entrance plane, meridional frame, mm).
    pub square: Rect,
    /// Vertices a side of the pilot grid (cells a side: `pilot − 1`).
    pub pilot: usize,
    /// Active cells `(i, j)` (i along x).
    pub cells: Vec<(u32, u32)>,
}

impl McRegion {
    /// Size of one cell (mm).
    pub fn cell(&self) -> (f64, f64) {
        let d = (self.pilot.max(2) - 1) as f64;
        (self.square.width() / d, self.square.height() / d)
    }

    /// The entrance-plane area the active cells cover (mm²).
    pub fn area(&self) -> f64 {
        let (cw, ch) = self.cell();
        self.cells.len() as f64 * cw * ch
    }
}

/// One ghost's Monte-Carlo estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct McGhost {
    pub path: GhostPath,
    /// Rays traced (over every band and batch).
    pub rays: usize,
    /// Active pilot cells, and how each batch of each band laid its rays over them.
    pub cells: usize,
    pub strata: Strata,
    /// Luminance-weighted flux of every ray that reaches the sensor (image units: an image of
    /// the ghost alone sums to this, uncropped).
    pub flux: McEstimate,
    /// The same over the rays that land inside the frame.
    pub flux_in_frame: McEstimate,
    /// Flux-weighted centroid (pixels of the frame, x right, y down) of the rays in the frame,
    /// and its standard error per axis.
    pub centroid_px: [f64; 2],
    pub centroid_err_px: [f64; 2],
    /// Central second moments of the in-frame flux (px²): xx, xy, yy.
    pub moments_px2: [f64; 3],
    /// The bounding box of the entrance points of the rays that reached the sensor (meridional
    /// frame, mm); `None` when none did.
    pub entrance_span: Option<Rect>,
}

/// The image a Monte-Carlo run splats into, and the same from its even and odd batches apart
/// (each of those at twice the weight, so each alone estimates the image): their difference
/// measures the noise.
#[derive(Clone, Debug)]
pub struct McImages {
    pub image: HdrImage,
    pub halves: [HdrImage; 2],
}

impl McImages {
    /// Black images of `frame`'s size.
    pub fn new(frame: &Frame) -> McImages {
        let black = || HdrImage::new(frame.width, frame.height);
        McImages {
            image: black(),
            halves: [black(), black()],
        }
    }

    /// Adds `o`'s images to these.
    pub fn add(&mut self, o: &McImages) {
        add_pixels(&mut self.image, &o.image);
        add_pixels(&mut self.halves[0], &o.halves[0]);
        add_pixels(&mut self.halves[1], &o.halves[1]);
    }

    /// The noise of `image`: the relative RMSE between the two halves over two (each half has
    /// twice the variance of the whole, their difference four times).
    pub fn relative_noise(&self) -> f64 {
        let (mut d2, mut b2) = (0.0_f64, 0.0_f64);
        for ((p, a), b) in self
            .image
            .pixels
            .iter()
            .zip(&self.halves[0].pixels)
            .zip(&self.halves[1].pixels)
        {
            for c in 0..3 {
                let d = f64::from(a[c]) - f64::from(b[c]);
                d2 += d * d;
                b2 += f64::from(p[c]).powi(2);
            }
        }
        if b2 > 0.0 {
            0.5 * (d2 / b2).sqrt()
        } else {
            0.0
        }
    }
}

fn add_pixels(a: &mut HdrImage, b: &HdrImage) {
    for (p, q) in a.pixels.iter_mut().zip(&b.pixels) {
        for c in 0..3 {
            p[c] += q[c];
        }
    }
}

/// The square on the entrance plane (z = 0) holding every ray that can meet the front element
/// at `theta`: its semi-diameter grown by 5% and by how far an oblique ray moves across the
/// front surface's sag.
pub fn entry_square(system: &LensSystem, theta: f64) -> Rect {
    let s0 = &system.surfaces[0];
    let sag = s0.sag(s0.semi_diameter).unwrap_or(0.0).abs();
    let h = s0.semi_diameter * 1.05 + sag * theta.tan().abs();
    Rect::square(0.0, 0.0, h)
}

/// The largest normalised stop radius the aperture is open at: 1 for the circle and an iris
/// (inscribed in it), √2 for a mask over [-1, 1]².
fn aperture_reach(aperture: &Aperture) -> f64 {
    match aperture {
        Aperture::Mask(_) => std::f64::consts::SQRT_2,
        _ => 1.0,
    }
}

/// Index into a trace's hits of `seq`'s recorded stop crossing (its last pass), if any.
fn stop_hit(seq: &Sequence<f64>) -> Option<usize> {
    seq.steps.iter().rposition(|s| s.record_stop)
}

/// Pilot grids laid again over the active cells ([`active_region`]) while these span less
/// than a quarter of the square across, each over the cells' box (with the cells' one-cell
/// margin): a small pupil behind a large front element (the fisheye at f/64: a 0.16 mm
/// pupil, a 60 mm entry square) covers a cell or two of the first pilot, and its stratified
/// rays would then sample it with a handful of cells' resolution.
pub fn zoomed_region(
    seqs: &[Sequence<f64>],
    theta: f64,
    square: Rect,
    pilot: usize,
    stop_radius: f64,
    reach: f64,
) -> McRegion {
    let mut region = active_region(seqs, theta, square, pilot, stop_radius, reach);
    for _ in 0..PILOT_ZOOMS {
        let (cw, ch) = region.cell();
        let Some(b) = Rect::bounding(region.cells.iter().flat_map(|&(i, j)| {
            let x = region.square.x0 + f64::from(i) * cw;
            let y = region.square.y0 + f64::from(j) * ch;
            [[x, y], [x + cw, y + ch]]
        })) else {
            break;
        };
        if b.width() > 0.25 * region.square.width() || b.height() > 0.25 * region.square.height() {
            break;
        }
        let zoomed = active_region(seqs, theta, b, pilot, stop_radius, reach);
        if zoomed.cells.is_empty() {
            break;
        }
        region = zoomed;
    }
    region
}

/// How many times [`zoomed_region`] may lay its pilot again.
const PILOT_ZOOMS: usize = 3;

/// The active cells of the pilot grids of `seqs` (one per wavelength, each with its stop
/// unclipped at the recorded crossing, which is tested against `reach` × the stop radius
/// instead) at `theta`.
pub fn active_region(
    seqs: &[Sequence<f64>],
    theta: f64,
    square: Rect,
    pilot: usize,
    stop_radius: f64,
    reach: f64,
) -> McRegion {
    let n = pilot.max(3);
    let cells = n - 1;
    let mut active = vec![false; cells * cells];
    let (s, c) = theta.sin_cos();
    let d = (n - 1) as f64;
    for seq in seqs {
        let stop = stop_hit(seq);
        // One pilot row per task: no shared state but the row's excesses.
        let excess: Vec<f64> = (0..n * n)
            .into_par_iter()
            .map_init(Vec::new, |hits: &mut Vec<Hit>, k| {
                let (i, j) = (k % n, k / n);
                let x = square.x0 + square.width() * i as f64 / d;
                let y = square.y0 + square.height() * j as f64 / d;
                hits.clear();
                let r = seq.trace_with_hits(
                    &Ray::new(DVec3::new(x, y, 0.0), DVec3::new(0.0, s, c)),
                    hits,
                );
                if !r.completed {
                    return f64::INFINITY;
                }
                let rho = stop
                    .and_then(|h| hits.get(h))
                    .map_or(0.0, |h| h.position.truncate().length() / stop_radius);
                (r.max_relative_radius - 1.0).max(rho / reach - 1.0)
            })
            .collect();
        for j in 0..cells {
            for i in 0..cells {
                let k = [
                    j * n + i,
                    j * n + i + 1,
                    (j + 1) * n + i,
                    (j + 1) * n + i + 1,
                ];
                let e = k.map(|v| excess[v]);
                let min = e.iter().copied().fold(f64::INFINITY, f64::min);
                // The largest change of e along the cell's edges (finite corners only).
                let edges = [(0, 1), (2, 3), (0, 2), (1, 3)];
                let slope = edges
                    .iter()
                    .filter(|(a, b)| e[*a].is_finite() && e[*b].is_finite())
                    .map(|(a, b)| (e[*a] - e[*b]).abs())
                    .fold(0.0, f64::max);
                let stopped = e.iter().any(|v| !v.is_finite());
                let near = min <= 2.0 * slope || (stopped && min <= 0.5);
                if min <= 0.0 || near {
                    active[j * cells + i] = true;
                }
            }
        }
    }
    // Grown by one cell all round.
    let mut grown = active.clone();
    for j in 0..cells {
        for i in 0..cells {
            if !active[j * cells + i] {
                continue;
            }
            for jj in j.saturating_sub(1)..=(j + 1).min(cells - 1) {
                for ii in i.saturating_sub(1)..=(i + 1).min(cells - 1) {
                    grown[jj * cells + ii] = true;
                }
            }
        }
    }
    McRegion {
        square,
        pilot: n,
        cells: (0..cells * cells)
            .filter(|&k| grown[k])
            .map(|k| ((k % cells) as u32, (k / cells) as u32))
            .collect(),
    }
}

/// What one batch of one band adds up (image units, pixels).
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    flux: f64,
    flux_in: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy: f64,
    yy: f64,
}

/// The Monte-Carlo estimate of ghost `path` lit by a light at `theta`, `phi` (radians) of
/// irradiance `irradiance`, at `bands` (each traced, in its colour), seen through `aperture`
/// in `frame`; splatted into `images` when given (added to what they hold).
#[allow(
    clippy::too_many_arguments,
    reason = "the scene, the ghost and the settings"
)]
pub fn ghost_monte_carlo(
    system: &LensSystem,
    aperture: &Aperture,
    frame: &Frame,
    path: GhostPath,
    light: (f64, f64, f64),
    bands: &[McBand],
    settings: &McSettings,
    images: Option<&mut McImages>,
) -> Option<McGhost> {
    let lambdas: Vec<f64> = bands.iter().map(|b| b.lambda_nm).collect();
    let rays = GhostRays::new(
        system,
        aperture,
        frame,
        path,
        light,
        &lambdas,
        &McSettings {
            batches: settings.batches.max(2),
            ..*settings
        },
    )?;
    Some(estimate(&rays, bands, frame, images))
}

/// The Monte-Carlo estimate from `rays` (prepared at `bands`' wavelengths, with at least two
/// batches), each band in its colour; splatted into `images` when given (added to what they
/// hold).
///
/// # Panics
/// If `bands` is not as long as `rays`' bands (a programming error).
pub fn estimate(
    rays: &GhostRays<'_>,
    bands: &[McBand],
    frame: &Frame,
    images: Option<&mut McImages>,
) -> McGhost {
    assert_eq!(bands.len(), rays.bands(), "one colour per traced band");
    let batches = rays.batches();
    let (w, h) = (frame.width as f64, frame.height as f64);
    let want_images = images.is_some();
    let jobs: Vec<(usize, usize)> = (0..bands.len())
        .flat_map(|b| (0..batches).map(move |k| (b, k)))
        .collect();
    // Each task: one band's batch; per thread, its hit buffer, images and the span of the
    // entrance points that carried light.
    type Acc = (Vec<(usize, Sums)>, Option<McImages>, Option<Rect>, Vec<Hit>);
    let init = || -> Acc {
        (
            Vec::new(),
            want_images.then(|| McImages::new(frame)),
            None,
            Vec::with_capacity(64),
        )
    };
    let (sums, img, span, _) = jobs
        .par_iter()
        .fold(init, |mut acc, &(b, k)| {
            let band = &bands[b];
            let rgb = band.rgb.map(f64::from);
            let lum = LUMINANCE[0] * rgb[0] + LUMINANCE[1] * rgb[1] + LUMINANCE[2] * rgb[2];
            let mut s = Sums::default();
            let (list, images, span, hits) = &mut acc;
            rays.trace(b, k, hits, |ray| {
                let e = ray.entrance;
                let p = Rect {
                    x0: e[0],
                    y0: e[1],
                    x1: e[0],
                    y1: e[1],
                };
                *span = Some(span.map_or(p, |r| r.union(&p)));
                let flux = ray.flux;
                let f = flux * lum;
                s.flux += f;
                let [px, py] = ray.px;
                if px >= 0.0 && px < w && py >= 0.0 && py < h {
                    s.flux_in += f;
                    s.x += f * px;
                    s.y += f * py;
                    s.xx += f * px * px;
                    s.xy += f * px * py;
                    s.yy += f * py * py;
                }
                if let Some(im) = images.as_mut() {
                    let scale = 1.0 / batches as f64;
                    let e = rgb.map(|c| c * flux * scale);
                    splat(&mut im.image, px, py, e);
                    splat(&mut im.halves[k % 2], px, py, e.map(|c| 2.0 * c));
                }
            });
            list.push((b * batches + k, s));
            acc
        })
        .reduce(init, |mut a, b| {
            a.0.extend(b.0);
            match (&mut a.1, &b.1) {
                (Some(x), Some(y)) => x.add(y),
                (None, Some(_)) => a.1 = b.1,
                _ => {}
            }
            a.2 = match (a.2, b.2) {
                (Some(x), Some(y)) => Some(x.union(&y)),
                (x, y) => x.or(y),
            };
            a
        });
    if let (Some(out), Some(img)) = (images, img) {
        out.add(&img);
    }
    // Per batch, summed over bands in band order (the same bits however the tasks ran).
    let mut sums = sums;
    sums.sort_by_key(|(idx, _)| *idx);
    let mut per_batch = vec![Sums::default(); batches];
    for (idx, s) in sums {
        let t = &mut per_batch[idx % batches];
        t.flux += s.flux;
        t.flux_in += s.flux_in;
        t.x += s.x;
        t.y += s.y;
        t.xx += s.xx;
        t.xy += s.xy;
        t.yy += s.yy;
    }
    let total = per_batch.iter().fold(Sums::default(), |mut t, s| {
        t.flux += s.flux;
        t.flux_in += s.flux_in;
        t.x += s.x;
        t.y += s.y;
        t.xx += s.xx;
        t.xy += s.xy;
        t.yy += s.yy;
        t
    });
    let est = |f: fn(&Sums) -> f64| McEstimate::of(&per_batch.iter().map(f).collect::<Vec<_>>());
    let (centroid, centroid_err, moments) = if total.flux_in > 0.0 {
        let c = [total.x / total.flux_in, total.y / total.flux_in];
        let err = |f: fn(&Sums) -> f64| {
            let v: Vec<f64> = per_batch
                .iter()
                .filter(|s| s.flux_in > 0.0)
                .map(|s| f(s) / s.flux_in)
                .collect();
            if v.len() >= 2 {
                McEstimate::of(&v).std_error
            } else {
                f64::INFINITY
            }
        };
        (
            c,
            [err(|s| s.x), err(|s| s.y)],
            [
                total.xx / total.flux_in - c[0] * c[0],
                total.xy / total.flux_in - c[0] * c[1],
                total.yy / total.flux_in - c[1] * c[1],
            ],
        )
    } else {
        ([f64::NAN; 2], [f64::NAN; 2], [f64::NAN; 3])
    };
    // Each batch estimates the whole flux: their mean and its standard error.
    let flux = est(|s| s.flux);
    let flux_in = est(|s| s.flux_in);
    McGhost {
        path: rays.path(),
        rays: rays.rays(),
        cells: rays.region().cells.len(),
        strata: rays.strata(),
        flux,
        flux_in_frame: flux_in,
        centroid_px: centroid,
        centroid_err_px: centroid_err,
        moments_px2: moments,
        entrance_span: span,
    }
}

/// Adds `e` to the pixel that holds the point (`px`, `py`) (pixel `(i, j)` spans `[i, i + 1)
/// × [j, j + 1)`); a point outside the image is dropped. A pixel then sums the flux of the rays
/// landing in its square: the same quantity as the rasterizer's exact coverage (a triangle's
/// irradiance integrated over the pixel), estimated without bias. (A bilinear splat would
/// estimate the irradiance blurred by a tent one pixel wide: wider than the rasterized image
/// by 1/12 px² per axis, which on a ghost of a pixel or two is most of its size.)
fn splat(img: &mut HdrImage, px: f64, py: f64, e: [f64; 3]) {
    if !(px >= 0.0 && py >= 0.0 && px < img.width as f64 && py < img.height as f64) {
        return;
    }
    let p = &mut img.pixels[py as usize * img.width + px as usize];
    for c in 0..3 {
        p[c] += e[c] as f32;
    }
}

/// The flux (mm², for unit irradiance) that `seq` carries to the sensor at `theta`, at its
/// wavelength, through the stop clipped at its working radius (no aperture shape: the
/// convention of the bounds' energy shares), with every Fresnel/coating factor exact: the
/// Monte-Carlo counterpart of `bounds::direct_flux` (with `Sequence::forward`) and of a
/// ghost's flux behind its energy share (with `Sequence::ghost_path`).
pub fn path_flux(
    system: &LensSystem,
    seq: &Sequence<f64>,
    theta: f64,
    settings: &McSettings,
) -> McEstimate {
    let stop_radius = crate::paraxial::stop_opening(system);
    let region = zoomed_region(
        std::slice::from_ref(seq),
        theta,
        entry_square(system, theta),
        settings.pilot,
        stop_radius,
        1.0,
    );
    let batches = settings.batches.max(2);
    let strata = Strata::for_rays(settings.rays / batches, region.cells.len());
    let cos = theta.cos();
    let key = seq.steps.len() as u64;
    let values: Vec<f64> = (0..batches)
        .into_par_iter()
        .map_init(
            || Vec::with_capacity(64),
            |hits, k| {
                let mut rng = SplitMix64::stream(&[settings.seed, key, u64::MAX, k as u64]);
                let mut sum = 0.0;
                sample_batch(
                    seq,
                    None,
                    stop_radius,
                    theta,
                    &region,
                    &[],
                    strata,
                    &mut rng,
                    hits,
                    |l| {
                        sum += cos * l.area * l.throughput;
                    },
                );
                sum
            },
        )
        .collect();
    McEstimate::of(&values)
}

mod rays;
#[cfg(test)]
mod tests;

pub use rays::{GhostRays, McRay, Strata};
use rays::{SplitMix64, sample_batch};

//! One ghost's rays as the Monte-Carlo reference draws them (the module documentation of
//! [`super`] says how): the sequences per band, the active region, the strata and the random
//! streams, prepared once ([`GhostRays::new`]); then every (band, batch) traced on its own
//! ([`GhostRays::trace`]), handing each ray that carries light to the caller with its flux and
//! where it lands. [`super::ghost_monte_carlo`] sums them into its estimates; a splatting
//! renderer adds them into an image.

use glam::DVec3;
use rayon::prelude::*;

use crate::aperture::{Aperture, ApertureSampler};
use crate::frame::Frame;
use crate::system::LensSystem;
use crate::trace::{Hit, Ray, Sequence};

use super::{McRegion, McSettings, aperture_reach, entry_square, stop_hit, zoomed_region};
use crate::ghost::GhostPath;

/// How far (pixels) outside the frame a cell's corners may land and still count as landing in
/// it ([`McSettings::outside_weight`]): what lands between the corners may spread a little
/// beyond their box.
const FRAME_MARGIN_PX: f64 = 2.0;

/// A small, fast generator (SplitMix64, Steele, Lea & Flood 2014): good enough for jitter,
/// and seeded per stream so that results do not depend on scheduling.
#[derive(Clone, Copy, Debug)]
pub(super) struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// The stream for these keys.
    pub(super) fn stream(keys: &[u64]) -> SplitMix64 {
        let mut g = SplitMix64(0);
        for &k in keys {
            g.0 ^= k;
            g.0 = g.next_u64();
        }
        g
    }
}

/// How one batch of one band lays its rays over the active cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strata {
    /// Every active cell split into `q × q` strata, one ray in each.
    PerCell(usize),
    /// This many rays, stratified along the active cells in row order laid end to end, each
    /// cell as long as its sampling weight (all 1 unless the region weighs them): ray `r` starts
    /// at `(r + ξ)/n` of the whole length, at a uniform point of the cell found there, and
    /// stands for `W / (n w)` cells' area (`W` the summed weight, `w` its cell's). Used for
    /// fewer rays than cells, and whenever the cells are weighed.
    Runs(usize),
}

impl Strata {
    /// The strata for `rays` a batch of one band over `cells` active cells: as many `q × q`
    /// strata per cell as fit (`q ≥ 1`) when there are at least as many rays as cells, else a
    /// run of cells per ray (at least one ray).
    pub fn for_rays(rays: usize, cells: usize) -> Strata {
        let cells = cells.max(1);
        if rays >= cells {
            Strata::PerCell(((rays as f64 / cells as f64).sqrt().floor() as usize).max(1))
        } else {
            Strata::Runs(rays.max(1))
        }
    }

    /// The strata for `rays` a batch of one band over `cells` cells, `weighed` or not: runs
    /// whenever they are.
    fn for_weighed_rays(rays: usize, cells: usize, weighed: bool) -> Strata {
        if weighed {
            Strata::Runs(rays.max(1))
        } else {
            Strata::for_rays(rays, cells)
        }
    }

    /// Rays it traces over `cells` active cells (none over none).
    pub fn rays(&self, cells: usize) -> usize {
        match *self {
            Strata::PerCell(q) => cells * q * q,
            Strata::Runs(n) if cells > 0 => n,
            Strata::Runs(_) => 0,
        }
    }
}

/// A ray that carries light: its entrance point, the entrance area its stratum stands for
/// (mm²), landing (sensor mm, meridional frame), stop crossing over the stop radius
/// (meridional frame) and throughput.
#[derive(Clone, Copy, Debug)]
pub(super) struct Landed {
    pub(super) entrance: [f64; 2],
    pub(super) area: f64,
    pub(super) sensor: [f64; 2],
    pub(super) stop_uv: [f64; 2],
    pub(super) throughput: f64,
}

/// Traces the strata of `region` for one batch of `seq`, calling `f` for every ray that
/// completes the path inside every clear semi-diameter; `hits` is the caller's buffer.
/// `cumulative` holds the running sums of the cells' sampling weights (empty: all 1), which
/// only [`Strata::Runs`] uses.
#[allow(
    clippy::too_many_arguments,
    reason = "one batch's whole description, private"
)]
pub(super) fn sample_batch(
    seq: &Sequence<f64>,
    stop: Option<usize>,
    stop_radius: f64,
    theta: f64,
    region: &McRegion,
    cumulative: &[f64],
    strata: Strata,
    rng: &mut SplitMix64,
    hits: &mut Vec<Hit>,
    mut f: impl FnMut(Landed),
) {
    let (s, c) = theta.sin_cos();
    let dir = DVec3::new(0.0, s, c);
    let (cw, ch) = region.cell();
    let mut shoot = |x: f64, y: f64, area: f64, hits: &mut Vec<Hit>| {
        hits.clear();
        let r = seq.trace_with_hits(&Ray::new(DVec3::new(x, y, 0.0), dir), hits);
        if !r.completed || r.max_relative_radius > 1.0 {
            return;
        }
        let stop_uv = stop.and_then(|h| hits.get(h)).map_or([0.0, 0.0], |h| {
            [h.position.x / stop_radius, h.position.y / stop_radius]
        });
        f(Landed {
            entrance: [x, y],
            area,
            sensor: [r.ray.origin.x, r.ray.origin.y],
            stop_uv,
            throughput: r.throughput,
        });
    };
    let corner = |(i, j): (u32, u32)| {
        (
            region.square.x0 + f64::from(i) * cw,
            region.square.y0 + f64::from(j) * ch,
        )
    };
    match strata {
        Strata::PerCell(q) => {
            let (sw, sh) = (cw / q as f64, ch / q as f64);
            for &cell in &region.cells {
                let (x0, y0) = corner(cell);
                for sj in 0..q {
                    for si in 0..q {
                        let x = x0 + (si as f64 + rng.next_f64()) * sw;
                        let y = y0 + (sj as f64 + rng.next_f64()) * sh;
                        shoot(x, y, sw * sh, hits);
                    }
                }
            }
        }
        Strata::Runs(n) => {
            let cells = region.cells.len();
            if cells == 0 {
                return;
            }
            let total = cumulative.last().copied().unwrap_or(cells as f64);
            let run = total / n as f64;
            for r in 0..n {
                let u = (r as f64 + rng.next_f64()) * run;
                let (k, w) = if cumulative.is_empty() {
                    ((u as usize).min(cells - 1), 1.0)
                } else {
                    let k = cumulative.partition_point(|&c| c <= u).min(cells - 1);
                    (
                        k,
                        cumulative[k] - if k > 0 { cumulative[k - 1] } else { 0.0 },
                    )
                };
                let (x0, y0) = corner(region.cells[k]);
                let x = x0 + rng.next_f64() * cw;
                let y = y0 + rng.next_f64() * ch;
                shoot(x, y, cw * ch * run / w, hits);
            }
        }
    }
}

/// A ray of a ghost that reaches the sensor with light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McRay {
    /// Where it enters (entrance plane z = 0, meridional frame, mm).
    pub entrance: [f64; 2],
    /// Where it lands, in pixels of the frame (x right, y down, pixel centres at
    /// half-integers); it may lie outside the frame.
    pub px: [f64; 2],
    /// Its flux at its band's wavelength (mm² × the light's irradiance): the stratum's area ×
    /// cos θ × irradiance × the exact Fresnel/coating throughput × the aperture's transmission
    /// at its stop crossing (the rays of one batch of one band together estimate the ghost's
    /// whole flux at that wavelength).
    pub flux: f64,
}

/// One ghost under one light, prepared for tracing band by band and batch by batch.
#[derive(Clone, Debug)]
pub struct GhostRays<'a> {
    /// One sequence per band (stop unclipped at its recorded crossing) and that crossing.
    seqs: Vec<(Sequence<f64>, Option<usize>)>,
    path: GhostPath,
    region: McRegion,
    /// Running sums of the active cells' sampling weights (empty: all 1).
    cumulative: Vec<f64>,
    /// How each batch of each band lays its rays.
    strata: Strata,
    batches: usize,
    /// Flux per entrance area (mm²) of unit throughput: cos θ × the irradiance.
    unit_flux: f64,
    theta: f64,
    /// sin φ, cos φ.
    phi: (f64, f64),
    stop_radius: f64,
    sampler: ApertureSampler<'a>,
    frame: Frame,
    /// Seeds of the random streams: the settings' and the ghost path's.
    seed: u64,
    key: u64,
}

impl<'a> GhostRays<'a> {
    /// Ghost `path` lit by a light at `theta`, `phi` (radians) of irradiance `irradiance`, at
    /// the wavelengths `lambdas_nm`, seen through `aperture` in `frame`, with `settings`
    /// (`settings.batches` taken as at least 1); `None` when the path has no sequence at one
    /// of the wavelengths, or no wavelength is given.
    pub fn new(
        system: &LensSystem,
        aperture: &'a Aperture,
        frame: &Frame,
        path: GhostPath,
        light: (f64, f64, f64),
        lambdas_nm: &[f64],
        settings: &McSettings,
    ) -> Option<GhostRays<'a>> {
        let (theta, phi, irradiance) = light;
        let stop_radius = crate::paraxial::stop_opening(system);
        let seqs: Vec<Sequence<f64>> = lambdas_nm
            .iter()
            .map(|&l| {
                Sequence::ghost_path(system, l, &path)
                    .ok()
                    .map(Sequence::aperture_by_mask)
            })
            .collect::<Option<_>>()?;
        if seqs.is_empty() {
            return None;
        }
        // The pilot at the band ends (the ghost's entry region moves with the wavelength).
        let ends: Vec<Sequence<f64>> = if seqs.len() > 1 {
            vec![seqs[0].clone(), seqs[seqs.len() - 1].clone()]
        } else {
            vec![seqs[0].clone()]
        };
        let region = zoomed_region(
            &ends,
            theta,
            entry_square(system, theta),
            settings.pilot,
            stop_radius,
            aperture_reach(aperture),
        );
        let batches = settings.batches.max(1);
        let key = path
            .reflections()
            .iter()
            .fold(0u64, |k, &s| k.wrapping_mul(131).wrapping_add(s as u64 + 1));
        let mut rays = GhostRays {
            seqs: seqs
                .into_iter()
                .map(|s| {
                    let stop = stop_hit(&s);
                    (s, stop)
                })
                .collect(),
            path,
            cumulative: Vec::new(),
            strata: Strata::PerCell(1),
            batches,
            unit_flux: theta.cos() * irradiance,
            region,
            theta,
            phi: phi.sin_cos(),
            stop_radius,
            sampler: aperture.sampler(),
            frame: *frame,
            seed: settings.seed,
            key,
        };
        if settings.outside_weight < 1.0 {
            rays.cumulative = rays.weigh_cells(&ends, settings.outside_weight.max(1e-6));
        }
        rays.set_rays(settings.rays, settings.seed);
        Some(rays)
    }

    /// Running sums of the active cells' sampling weights: 1 for a cell whose corners' landing
    /// points (traced at `ends`, vignetted or not) have a bounding box, grown by two pixels,
    /// that meets the frame, or whose corners all stop on the way; `outside` for the others.
    fn weigh_cells(&self, ends: &[Sequence<f64>], outside: f64) -> Vec<f64> {
        let region = &self.region;
        let n = region.pilot;
        let (cw, ch) = region.cell();
        let (s, c) = self.theta.sin_cos();
        let dir = DVec3::new(0.0, s, c);
        let mut used = vec![false; n * n];
        for &(i, j) in &region.cells {
            let (i, j) = (i as usize, j as usize);
            for v in [
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i,
                (j + 1) * n + i + 1,
            ] {
                used[v] = true;
            }
        }
        // Each used vertex's landing points (pixels), one per end wavelength.
        let landings: Vec<Vec<[f64; 2]>> = used
            .par_iter()
            .enumerate()
            .map_init(Vec::new, |hits: &mut Vec<Hit>, (v, &u)| {
                if !u {
                    return Vec::new();
                }
                let x = region.square.x0 + (v % n) as f64 * cw;
                let y = region.square.y0 + (v / n) as f64 * ch;
                ends.iter()
                    .filter_map(|seq| {
                        hits.clear();
                        let r = seq.trace_with_hits(&Ray::new(DVec3::new(x, y, 0.0), dir), hits);
                        r.completed
                            .then(|| self.to_px([r.ray.origin.x, r.ray.origin.y]))
                    })
                    .collect()
            })
            .collect();
        let (w, h) = (self.frame.width as f64, self.frame.height as f64);
        let mut total = 0.0;
        region
            .cells
            .iter()
            .map(|&(i, j)| {
                let (i, j) = (i as usize, j as usize);
                let corners = [
                    j * n + i,
                    j * n + i + 1,
                    (j + 1) * n + i,
                    (j + 1) * n + i + 1,
                ];
                let mut b = [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ];
                for p in corners.iter().flat_map(|&v| &landings[v]) {
                    b = [
                        b[0].min(p[0]),
                        b[1].min(p[1]),
                        b[2].max(p[0]),
                        b[3].max(p[1]),
                    ];
                }
                let stopped = b[0] > b[2];
                let meets = b[0] - FRAME_MARGIN_PX < w
                    && b[2] + FRAME_MARGIN_PX >= 0.0
                    && b[1] - FRAME_MARGIN_PX < h
                    && b[3] + FRAME_MARGIN_PX >= 0.0;
                total += if stopped || meets { 1.0 } else { outside };
                total
            })
            .collect()
    }

    /// The active cells rays start in.
    pub fn region(&self) -> &McRegion {
        &self.region
    }

    /// The ghost path.
    pub fn path(&self) -> GhostPath {
        self.path
    }

    /// How each batch of each band lays its rays.
    pub fn strata(&self) -> Strata {
        self.strata
    }

    /// Lays `rays` over every band and batch from now on, from the random streams of `seed`
    /// (the active region is kept: this costs no tracing).
    pub fn set_rays(&mut self, rays: usize, seed: u64) {
        self.strata = Strata::for_weighed_rays(
            rays / (self.seqs.len() * self.batches).max(1),
            self.region.cells.len(),
            !self.cumulative.is_empty(),
        );
        self.seed = seed;
    }

    /// Wavelength bands.
    pub fn bands(&self) -> usize {
        self.seqs.len()
    }

    /// Independent batches (each one ray per stratum and band).
    pub fn batches(&self) -> usize {
        self.batches
    }

    /// Rays traced over every band and batch.
    pub fn rays(&self) -> usize {
        self.strata.rays(self.region.cells.len()) * self.seqs.len() * self.batches
    }

    /// Where a point of the sensor (meridional frame, mm) lies in the frame (pixels).
    fn to_px(&self, p: [f64; 2]) -> [f64; 2] {
        let (sphi, cphi) = self.phi;
        let frame = &self.frame;
        // Meridional frame → the lens's (turned by φ) → pixels (photograph orientation).
        let (x, y) = (p[0] * cphi - p[1] * sphi, p[0] * sphi + p[1] * cphi);
        [
            (0.5 - x / frame.film_width_mm) * frame.width as f64,
            (0.5 + y / frame.film_height_mm) * frame.height as f64,
        ]
    }

    /// Traces batch `batch` of band `band` (one jittered ray per stratum, from the random
    /// stream of the settings' seed, the path, the band and the batch), calling `f` for every
    /// ray that reaches the sensor with a positive flux; `hits` is the caller's buffer (no
    /// allocation per ray once it has grown).
    ///
    /// # Panics
    /// If `band` is not below [`GhostRays::bands`] (a programming error).
    pub fn trace(&self, band: usize, batch: usize, hits: &mut Vec<Hit>, mut f: impl FnMut(McRay)) {
        let (seq, stop) = &self.seqs[band];
        let (sphi, cphi) = self.phi;
        let mut rng = SplitMix64::stream(&[self.seed, self.key, band as u64, batch as u64]);
        sample_batch(
            seq,
            *stop,
            self.stop_radius,
            self.theta,
            &self.region,
            &self.cumulative,
            self.strata,
            &mut rng,
            hits,
            |l| {
                let [u, v] = l.stop_uv;
                let uv = [u * cphi - v * sphi, u * sphi + v * cphi];
                let tau = f64::from(self.sampler.transmission(uv[0] as f32, uv[1] as f32));
                let flux = self.unit_flux * l.area * l.throughput * tau;
                if flux <= 0.0 {
                    return;
                }
                f(McRay {
                    entrance: l.entrance,
                    px: self.to_px(l.sensor),
                    flux,
                });
            },
        );
    }
}

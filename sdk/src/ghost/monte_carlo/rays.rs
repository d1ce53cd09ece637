//! One ghost's rays as the Monte-Carlo reference draws them (the module documentation of
//! [`super`] says how): the sequences per band, the active region, the strata and the random
//! streams, prepared once ([`GhostRays::new`]); then every (band, batch) traced on its own
//! ([`GhostRays::trace`]), handing each ray that carries light to the caller with its flux and
//! where it lands. [`super::ghost_monte_carlo`] sums them into its estimates; a splatting
//! renderer adds them into an image.

use glam::DVec3;

use crate::aperture::{Aperture, ApertureSampler};
use crate::frame::Frame;
use crate::system::LensSystem;
use crate::trace::{Hit, Ray, Sequence};

use super::{McRegion, McSettings, aperture_reach, entry_square, stop_hit, strata, zoomed_region};
use crate::ghost::GhostPath;

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

/// A ray that carries light: its entrance point, landing (sensor mm, meridional frame), stop
/// crossing over the stop radius (meridional frame) and throughput.
#[derive(Clone, Copy, Debug)]
pub(super) struct Landed {
    pub(super) entrance: [f64; 2],
    pub(super) sensor: [f64; 2],
    pub(super) stop_uv: [f64; 2],
    pub(super) throughput: f64,
}

/// Traces the strata of `region` for one batch of `seq`, calling `f` for every ray that
/// completes the path inside every clear semi-diameter; `hits` is the caller's buffer.
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
    q: usize,
    rng: &mut SplitMix64,
    hits: &mut Vec<Hit>,
    mut f: impl FnMut(Landed),
) {
    let (s, c) = theta.sin_cos();
    let dir = DVec3::new(0.0, s, c);
    let (cw, ch) = region.cell();
    let (sw, sh) = (cw / q as f64, ch / q as f64);
    for &(i, j) in &region.cells {
        let x0 = region.square.x0 + i as f64 * cw;
        let y0 = region.square.y0 + j as f64 * ch;
        for sj in 0..q {
            for si in 0..q {
                let x = x0 + (si as f64 + rng.next_f64()) * sw;
                let y = y0 + (sj as f64 + rng.next_f64()) * sh;
                hits.clear();
                let r = seq.trace_with_hits(&Ray::new(DVec3::new(x, y, 0.0), dir), hits);
                if !r.completed || r.max_relative_radius > 1.0 {
                    continue;
                }
                let stop_uv = stop.and_then(|h| hits.get(h)).map_or([0.0, 0.0], |h| {
                    [h.position.x / stop_radius, h.position.y / stop_radius]
                });
                f(Landed {
                    entrance: [x, y],
                    sensor: [r.ray.origin.x, r.ray.origin.y],
                    stop_uv,
                    throughput: r.throughput,
                });
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
    region: McRegion,
    /// Strata per active cell a side.
    q: usize,
    batches: usize,
    /// Flux of a stratum of unit throughput.
    stratum_flux: f64,
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
        let q = strata(settings.rays, region.cells.len(), seqs.len(), batches);
        let (cw, ch) = region.cell();
        let key = path
            .reflections()
            .iter()
            .fold(0u64, |k, &s| k.wrapping_mul(131).wrapping_add(s as u64 + 1));
        Some(GhostRays {
            seqs: seqs
                .into_iter()
                .map(|s| {
                    let stop = stop_hit(&s);
                    (s, stop)
                })
                .collect(),
            q,
            batches,
            stratum_flux: cw * ch / (q * q) as f64 * theta.cos() * irradiance,
            region,
            theta,
            phi: phi.sin_cos(),
            stop_radius,
            sampler: aperture.sampler(),
            frame: *frame,
            seed: settings.seed,
            key,
        })
    }

    /// The active cells rays start in.
    pub fn region(&self) -> &McRegion {
        &self.region
    }

    /// Strata per active cell a side.
    pub fn strata(&self) -> usize {
        self.q
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
        self.region.cells.len() * self.q * self.q * self.seqs.len() * self.batches
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
            self.q,
            &mut rng,
            hits,
            |l| {
                let [u, v] = l.stop_uv;
                let uv = [u * cphi - v * sphi, u * sphi + v * cphi];
                let tau = f64::from(self.sampler.transmission(uv[0] as f32, uv[1] as f32));
                let flux = self.stratum_flux * l.throughput * tau;
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

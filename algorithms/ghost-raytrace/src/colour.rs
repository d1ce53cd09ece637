//! A ghost's colour. Coatings make each ghost's throughput vary steeply with wavelength (a
//! quarter-wave layer reflects least at its design wavelength and more toward the blue), so a
//! few traced bands would alias it. The renderer traces a ghost's geometry at a few bands, and
//! each band's colour is the integral over its wavelength bin of the light's colour weights
//! times the ghost's throughput at normal incidence, relative to the throughput at the band's
//! own wavelength. The integrand is taken as constant over each 5 nm cell and each cell
//! counts by the part of it inside the bin, so bins of any width (a ghost's `m` bins, up to
//! the reference's 160) get their exact share: counting whole cells by their centres instead
//! gave 31 bins of 12.9 nm two or three cells each, a ±20% ripple from band to band that a
//! dispersive ghost shows as stripes in its colour fringe.

use flarebench_sdk::LensSystem;
use flarebench_sdk::color::{LightSpectrum, SAMPLING_MAX_NM, SAMPLING_MIN_NM, SpectralSampling};
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::system::SurfaceKind;

use crate::GhostRenderError;

/// Fine wavelength steps the colours are integrated over (5 nm over 380–780 nm).
const FINE_BANDS: usize = 80;

/// Normal-incidence factors of every surface at one wavelength:
/// `[T forward, R forward, T backward, R backward]` (1, 0, 1, 0 where nothing reflects; the
/// sensor of a sensor stack reflects its spectral reflectance forward).
pub fn surface_factors(system: &LensSystem, lambda_nm: f64) -> Vec<[f64; 4]> {
    let n = system.indices(lambda_nm);
    system
        .surfaces
        .iter()
        .enumerate()
        .map(|(i, s)| {
            if s.kind == SurfaceKind::Sensor
                && let Some(r) = system.sensor_reflectance(lambda_nm)
            {
                return [1.0 - r, r, 1.0, 0.0];
            }
            if s.kind != SurfaceKind::Refracting || n[i] == n[i + 1] {
                return [1.0, 0.0, 1.0, 0.0];
            }
            let rf = s.coating.reflectance(n[i], n[i + 1], 1.0, lambda_nm, true);
            let rb = s.coating.reflectance(n[i + 1], n[i], 1.0, lambda_nm, false);
            [1.0 - rf, rf, 1.0 - rb, rb]
        })
        .collect()
}

/// Throughput of a ghost path at normal incidence from per-surface factors.
pub fn path_throughput(path: GhostPath, f: &[[f64; 4]], sensor: usize) -> f64 {
    // Forward to the first reflection; then back and forward between reflections (two or
    // four of them); then forward to the sensor. Each leg's transmittances are multiplied
    // first, then the legs and reflectances in order (as the two-reflection form always did).
    let r = path.reflections();
    let mut t = 1.0;
    let mut at: Option<usize> = None;
    for (k, &s) in r.iter().enumerate() {
        let leg: f64 = match at {
            None => f[..s].iter().map(|x| x[0]).product(),
            Some(p) if k % 2 == 0 => f[p + 1..s].iter().map(|x| x[0]).product(),
            Some(p) => f[s + 1..p].iter().map(|x| x[2]).product(),
        };
        t = t * leg * f[s][if k % 2 == 0 { 1 } else { 3 }];
        at = Some(s);
    }
    let last = at.unwrap_or(0);
    let forward_out: f64 = f[last + 1..sensor].iter().map(|x| x[0]).product();
    t * forward_out
}

/// Wavelengths (nm) at which the plan measures a ghost's flux for its spectral shape
/// ([`SpectralShape`]): every 50 nm over the sampled range.
pub const SHAPE_NODES_NM: [f64; 9] = [
    380.0, 430.0, 480.0, 530.0, 580.0, 630.0, 680.0, 730.0, 780.0,
];

/// How a ghost's flux departs from its throughput at normal incidence across the spectrum:
/// `G(λ) = F(λ) / T₀(λ)`, the ghost's traced flux over its normal-incidence throughput, at
/// [`SHAPE_NODES_NM`] and linear between them. The colours assume `G` constant over each
/// traced band's bin; where it is not (the stop clipping a ghost whose focus moves with the
/// wavelength, coatings at oblique incidence), a ghost needs more bands than its dispersion
/// asks for: [`GhostColours::bins_error`] says how many.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralShape {
    g: [f64; SHAPE_NODES_NM.len()],
}

impl SpectralShape {
    /// `G` at `lambda_nm` (linear between the nodes, constant beyond them).
    pub fn at(&self, lambda_nm: f64) -> f64 {
        let step = SHAPE_NODES_NM[1] - SHAPE_NODES_NM[0];
        let last = SHAPE_NODES_NM.len() - 1;
        let t = ((lambda_nm - SHAPE_NODES_NM[0]) / step).clamp(0.0, last as f64);
        let i = (t.floor() as usize).min(last - 1);
        let f = t - i as f64;
        self.g[i] * (1.0 - f) + self.g[i + 1] * f
    }
}

/// Per-wavelength data for colouring every ghost of a lens under one light.
#[derive(Debug)]
pub struct GhostColours {
    /// Fine wavelengths, their colour weights (for the light) and the surface factors there.
    fine: Vec<(f64, [f32; 3], Vec<[f64; 4]>)>,
    /// The surface factors at [`SHAPE_NODES_NM`].
    nodes: Vec<Vec<[f64; 4]>>,
    sensor: usize,
    /// The light's intensity, scaling every colour.
    intensity: f32,
}

impl GhostColours {
    /// For `system` under `light`; `intensity` scales every colour.
    pub fn new(
        system: &LensSystem,
        light: LightSpectrum,
        intensity: f32,
    ) -> Result<Self, GhostRenderError> {
        let fine = SpectralSampling::new(FINE_BANDS, light)?;
        Ok(GhostColours {
            fine: fine
                .wavelengths_nm()
                .iter()
                .zip(fine.weights())
                .map(|(&l, &w)| (l, w, surface_factors(system, l)))
                .collect(),
            nodes: SHAPE_NODES_NM
                .iter()
                .map(|&l| surface_factors(system, l))
                .collect(),
            sensor: system.sensor_index(),
            intensity,
        })
    }

    /// The colour of `bin` for `path`, relative to the throughput at the bin's centre, where
    /// the ghost is traced: each fine cell's weight and throughput times the share of the
    /// cell inside the bin.
    pub fn bin_colour(&self, path: GhostPath, bin: &Bin) -> [f32; 3] {
        let t_band = path_throughput(path, &bin.factors, self.sensor);
        if t_band.is_nan() || t_band <= 0.0 {
            return [0.0; 3];
        }
        let cell = bin_width_nm(FINE_BANDS);
        let index = |nm: f64| ((nm - SAMPLING_MIN_NM) / cell).clamp(0.0, FINE_BANDS as f64);
        let (first, last) = (
            index(bin.lo_nm).floor() as usize,
            index(bin.hi_nm).ceil() as usize,
        );
        let mut c = [0f32; 3];
        for (k, (_, w, f)) in self.fine.iter().enumerate().take(last).skip(first) {
            let lo = bin_edge_nm(FINE_BANDS, k).max(bin.lo_nm);
            let hi = bin_edge_nm(FINE_BANDS, k + 1).min(bin.hi_nm);
            let share = ((hi - lo) / cell).clamp(0.0, 1.0);
            if share > 0.0 {
                let r = (path_throughput(path, f, self.sensor) / t_band * share) as f32
                    * self.intensity;
                for i in 0..3 {
                    c[i] += w[i] * r;
                }
            }
        }
        c
    }
}

impl GhostColours {
    /// The light `path` carries over `bin` at normal incidence, per linear-sRGB channel:
    /// `Σ w(λ) T₀(λ)` over the bin's fine cells (each by its share inside the bin), times the
    /// intensity. [`GhostColours::bin_colour`] is this over `T₀` at the bin's centre. A
    /// ghost's traced image at the bin with its colour divided out, times this, is its image
    /// under other coatings of the same surfaces as long as the coatings change the
    /// throughput's variation with the rays' angles little: what a coating fit re-weights.
    pub fn bin_light(&self, path: GhostPath, bin: &Bin) -> [f64; 3] {
        let cell = bin_width_nm(FINE_BANDS);
        let index = |nm: f64| ((nm - SAMPLING_MIN_NM) / cell).clamp(0.0, FINE_BANDS as f64);
        let (first, last) = (
            index(bin.lo_nm).floor() as usize,
            index(bin.hi_nm).ceil() as usize,
        );
        let mut c = [0f64; 3];
        for (k, (_, w, f)) in self.fine.iter().enumerate().take(last).skip(first) {
            let lo = bin_edge_nm(FINE_BANDS, k).max(bin.lo_nm);
            let hi = bin_edge_nm(FINE_BANDS, k + 1).min(bin.hi_nm);
            let share = ((hi - lo) / cell).clamp(0.0, 1.0);
            let t = path_throughput(path, f, self.sensor);
            if share > 0.0 && t > 0.0 {
                for i in 0..3 {
                    c[i] += f64::from(w[i]) * t * share * f64::from(self.intensity);
                }
            }
        }
        c
    }
}

impl GhostColours {
    /// `path`'s spectral shape from its flux measured at each of [`SHAPE_NODES_NM`] (in any
    /// unit: only its variation counts); `None` when the ghost is dark at some node.
    pub fn shape(
        &self,
        path: GhostPath,
        flux: [f64; SHAPE_NODES_NM.len()],
    ) -> Option<SpectralShape> {
        let mut g = [0.0; SHAPE_NODES_NM.len()];
        for (k, (f, factors)) in flux.iter().zip(&self.nodes).enumerate() {
            let t = path_throughput(path, factors, self.sensor);
            if !(t > 0.0 && f.is_finite() && *f > 0.0) {
                return None;
            }
            g[k] = f / t;
        }
        Some(SpectralShape { g })
    }

    /// The relative colour error of tracing `path` at `m` equal bins when its flux varies
    /// over the spectrum as `shape` says: each bin's colour assumes `G` constant over the bin
    /// at its value at the centre, where the band is traced, while the light carries
    /// `∫ w(λ) T₀(λ) G(λ) dλ`. The largest channel's error over the largest channel.
    pub fn bins_error(&self, path: GhostPath, m: usize, shape: &SpectralShape) -> f64 {
        let cell = bin_width_nm(FINE_BANDS);
        let mut exact = [0.0_f64; 3];
        let mut model = [0.0_f64; 3];
        for (k, (nm, w, f)) in self.fine.iter().enumerate() {
            let t = path_throughput(path, f, self.sensor);
            if t.is_nan() || t <= 0.0 {
                continue;
            }
            let g = shape.at(*nm);
            // The cell's share of each bin it overlaps, at that bin's centre's G.
            let (lo, hi) = (bin_edge_nm(FINE_BANDS, k), bin_edge_nm(FINE_BANDS, k + 1));
            let width = bin_width_nm(m);
            let first = (((lo - SAMPLING_MIN_NM) / width).floor().max(0.0) as usize).min(m - 1);
            let mut g_model = 0.0;
            for i in first..m {
                let (blo, bhi) = (bin_edge_nm(m, i), bin_edge_nm(m, i + 1));
                if blo >= hi {
                    break;
                }
                let share = ((hi.min(bhi) - lo.max(blo)) / cell).clamp(0.0, 1.0);
                g_model += share * shape.at(0.5 * (blo + bhi));
            }
            for c in 0..3 {
                let wt = f64::from(w[c]) * t;
                exact[c] += wt * g;
                model[c] += wt * g_model;
            }
        }
        let scale = exact.iter().cloned().fold(0.0, f64::max);
        if scale <= 0.0 {
            return 0.0;
        }
        (0..3)
            .map(|c| (model[c] - exact[c]).abs())
            .fold(0.0, f64::max)
            / scale
    }

    /// The fewest equal bins, from `min` to `max`, whose [`GhostColours::bins_error`] is
    /// within `tolerance` (`max` when none is).
    pub fn bins_for(
        &self,
        path: GhostPath,
        shape: &SpectralShape,
        min: usize,
        max: usize,
        tolerance: f64,
    ) -> usize {
        (min.max(1)..=max)
            .find(|&m| self.bins_error(path, m, shape) <= tolerance)
            .unwrap_or(max)
    }
}

/// Bin `i` of `m` equal bins over 380–780 nm (the bins of an `m`-band [`SpectralSampling`]),
/// with the lens's surface factors at its centre: made once per bin and shared by every
/// ghost traced there.
#[derive(Clone, Debug)]
pub struct Bin {
    pub lo_nm: f64,
    pub hi_nm: f64,
    /// The centre, computed as `SpectralSampling::new(m, …)` computes its wavelengths.
    pub centre_nm: f64,
    factors: Vec<[f64; 4]>,
}

/// Edge `i` (0 to `m`) of `m` equal bins over the sampled range: bin `i` spans edges `i` and
/// `i + 1`.
pub fn bin_edge_nm(m: usize, i: usize) -> f64 {
    SAMPLING_MIN_NM + bin_width_nm(m) * i as f64
}

fn bin_width_nm(m: usize) -> f64 {
    (SAMPLING_MAX_NM - SAMPLING_MIN_NM) / m.max(1) as f64
}

impl Bin {
    /// `path`'s throughput at normal incidence at the bin's centre (the product of its
    /// surfaces' Fresnel or coating factors there).
    pub fn throughput(&self, path: GhostPath, system: &LensSystem) -> f64 {
        path_throughput(path, &self.factors, system.sensor_index())
    }
}

impl Bin {
    /// Bin `i` of `m` for `system`.
    pub fn new(system: &LensSystem, m: usize, i: usize) -> Bin {
        let centre_nm = SAMPLING_MIN_NM + (i as f64 + 0.5) * bin_width_nm(m);
        Bin {
            lo_nm: bin_edge_nm(m, i),
            hi_nm: bin_edge_nm(m, i + 1),
            centre_nm,
            factors: surface_factors(system, centre_nm),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flarebench_sdk::{Coating, Medium, Surface};

    /// A stop and an uncoated, dispersion-free plate: a flat throughput.
    fn plate() -> LensSystem {
        LensSystem::new(
            "plate",
            vec![
                Surface::stop(1.0, 5.0),
                Surface::spherical(0.0, 2.0, Medium::Model { nd: 1.5, vd: None }, 8.0),
                Surface::spherical(0.0, 5.0, Medium::Air, 8.0),
                Surface::sensor(10.0),
            ],
        )
    }

    /// A bin's colour is the sum of its halves' (and of its thirds'), for bins of any width:
    /// each fine cell counts by its share inside a bin, so no band gets two cells where its
    /// neighbour gets three. Without coatings or dispersion the throughput is flat, so the
    /// colours add exactly.
    #[test]
    fn bin_colours_add_up_under_refinement() {
        let sys = plate();
        let path = GhostPath::two(2, 1);
        let c = GhostColours::new(&sys, LightSpectrum::D65, 1.0).unwrap();
        let colour = |m: usize, i: usize| c.bin_colour(path, &Bin::new(&sys, m, i));
        for (m, k) in [(31, 2), (31, 3), (7, 5), (80, 2), (53, 3)] {
            for i in 0..m {
                let whole = colour(m, i);
                let parts = (0..k).fold([0f32; 3], |a, j| {
                    let p = colour(m * k, i * k + j);
                    [a[0] + p[0], a[1] + p[1], a[2] + p[2]]
                });
                for ch in 0..3 {
                    assert!(
                        (whole[ch] - parts[ch]).abs() <= 1e-5 * whole[ch].abs().max(1e-3),
                        "m {m} bin {i} in {k}: {whole:?} vs {parts:?}"
                    );
                }
            }
        }
        // Each of 31 bins (12.9 nm) holds its share of the light's colour: against a 0.1 nm
        // sampling of the same light, within 2% of the brightest bin. (Counting 5 nm cells
        // whole by their centres gave two or three cells a bin: errors of 20–40%.)
        let fine = SpectralSampling::new(4000, LightSpectrum::D65).unwrap();
        let y = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let truth: Vec<f32> = (0..31)
            .map(|i| {
                let (lo, hi) = (bin_edge_nm(31, i), bin_edge_nm(31, i + 1));
                fine.wavelengths_nm()
                    .iter()
                    .zip(fine.weights())
                    .filter(|(l, _)| **l >= lo && **l < hi)
                    .map(|(_, w)| y(*w))
                    .sum()
            })
            .collect();
        let peak = truth.iter().fold(0f32, |a, &b| a.max(b));
        for (i, t) in truth.iter().enumerate() {
            let ours = y(colour(31, i));
            assert!((ours - t).abs() < 0.02 * peak, "bin {i}: {ours} vs {t}");
        }
    }

    /// A flux that follows the normal-incidence throughput (a flat shape) needs one band; a
    /// shape that varies over the spectrum makes few bands wrong by what a direct sum says,
    /// and the error falls to nothing as the bins shrink to the fine cells.
    #[test]
    fn the_spectral_shape_sets_the_bands_a_colour_needs() {
        let sys = plate();
        let path = GhostPath::two(2, 1);
        let c = GhostColours::new(&sys, LightSpectrum::D65, 1.0).unwrap();
        let t = |k: usize| path_throughput(path, &c.nodes[k], c.sensor);
        let flat = c.shape(path, std::array::from_fn(|k| 3.0 * t(k))).unwrap();
        for m in [1, 2, 5, 31] {
            assert!(c.bins_error(path, m, &flat) < 1e-12, "flat, {m} bins");
        }
        assert_eq!(c.bins_for(path, &flat, 1, 31, 1e-3), 1);
        // G rising linearly from 1 at 380 nm to 4 at 780 nm.
        let ramp = c
            .shape(
                path,
                std::array::from_fn(|k| t(k) * (1.0 + 3.0 * k as f64 / 8.0)),
            )
            .unwrap();
        assert!((ramp.at(580.0) - 2.5).abs() < 1e-12 && (ramp.at(405.0) - 1.1875).abs() < 1e-12);
        // One band: G(580) = 2.5 for every wavelength, against the weights' own mean of G.
        let y = |v: [f64; 3]| v.iter().cloned().fold(0.0, f64::max);
        let (mut exact, mut one) = ([0.0; 3], [0.0; 3]);
        for (nm, w, _) in &c.fine {
            for ch in 0..3 {
                exact[ch] += f64::from(w[ch]) * ramp.at(*nm);
                one[ch] += f64::from(w[ch]) * 2.5;
            }
        }
        let direct = (0..3)
            .map(|ch| (one[ch] - exact[ch]).abs())
            .fold(0.0, f64::max)
            / y(exact);
        assert!(
            direct > 0.01,
            "a ramp this steep is coloured wrongly by one band"
        );
        assert!((c.bins_error(path, 1, &ramp) - direct).abs() < 1e-9);
        let errors: Vec<f64> = [1, 2, 4, 8, 16, 80]
            .iter()
            .map(|&m| c.bins_error(path, m, &ramp))
            .collect();
        assert!(errors.windows(2).all(|e| e[1] < e[0]), "{errors:?}");
        assert!(errors[5] < 1e-12, "{errors:?}");
        let m = c.bins_for(path, &ramp, 1, 31, 1e-3);
        assert!(m > 1 && c.bins_error(path, m, &ramp) <= 1e-3);
        assert!(c.bins_error(path, m - 1, &ramp) > 1e-3);
        // A ghost dark at one node has no shape.
        assert!(
            c.shape(
                path,
                std::array::from_fn(|k| if k == 4 { 0.0 } else { 1.0 })
            )
            .is_none()
        );
    }

    /// Without coatings or dispersion a ghost's throughput is the same at every wavelength, so
    /// the band colours are the light's own colour split by bands and sum to it.
    #[test]
    fn flat_throughput_gives_the_light_colour() {
        let mut sys = plate();
        let path = GhostPath::two(2, 1);
        let c = GhostColours::new(&sys, LightSpectrum::D65, 1.0).unwrap();
        let bands: Vec<[f32; 3]> = (0..3)
            .map(|i| c.bin_colour(path, &Bin::new(&sys, 3, i)))
            .collect();
        let total: [f32; 3] = bands
            .iter()
            .fold([0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
        for ch in total {
            assert!((ch - 1.0).abs() < 1e-3, "{total:?}");
        }
        let m = c.bin_colour(path, &Bin::new(&sys, 1, 0));
        assert!(
            (0..3).all(|i| (m[i] - total[i]).abs() < 1e-5),
            "{m:?} vs {total:?}"
        );
        // A red-tuned quarter-wave coating makes the ghost blue.
        for s in &mut sys.surfaces[1..3] {
            s.coating = Coating::SingleLayer {
                design_wavelength_nm: 620.0,
                index: 1.38,
            };
        }
        let c = GhostColours::new(&sys, LightSpectrum::D65, 1.0).unwrap();
        let m = c.bin_colour(path, &Bin::new(&sys, 1, 0));
        assert!(m[2] > m[0] && m[2] > 1.0, "{m:?}");
    }
}

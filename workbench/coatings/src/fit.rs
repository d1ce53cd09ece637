//! Fitting a lens's coatings, and the light's intensity and colour, to a linear image of its
//! flare.
//!
//! The model image is `Σᵢ Sᵢ(x) cᵢ(θ) ∘ g`: every band image `Sᵢ` of the basis
//! (`crate::basis`) times its colour under the coatings `θ` (`crate::model`), times per-channel
//! gains `g` (the light's intensity and colour as the camera saw them). Over the unmasked
//! pixels, per channel, `‖S c − y‖² = cᵀMc − 2cᵀv + yᵀy` with the Gram matrix `M = SᵀS` and
//! `v = Sᵀy`: with `M = LLᵀ` (Cholesky), `‖S c − y‖² = ‖Lᵀc − L⁻¹v‖² + const`. The solver
//! works on those `3 × bands` residuals, exactly the image's least squares but independent of
//! its pixel count: an evaluation costs the colours and one triangular product.
//!
//! The solver is bounded Levenberg–Marquardt (`crate::solve`), from several starts, each first
//! improved surface by surface over a grid of each surface's parameters (`Evaluator::scan`:
//! a layer's reflectance is periodic in its thickness, and a local solver keeps to the valley
//! it starts in). The first pass's best distinct solutions (`FitOptions::candidates`) are each
//! refined: the basis rendered again with the solution's coatings and the fit repeated from it
//! (`FitOptions::passes`), so each is judged under a basis of its own coatings, where the
//! basis's approximations (`crate::basis`) matter least. Each refined solution is then
//! corrected for what its basis leaves out (`correct`): the ghost renderer's image at its
//! coatings, its difference from the basis's taken into the model, and the fit solved again
//! until the parameters stop moving; the best corrected one is kept, and its image and ghost
//! energies are the renderer's. Uncertainties come from the Jacobian there:
//! `cov = s² (JᵀJ)⁺` with `s²` the residual variance per pixel channel; directions `JᵀJ` does not see (singular values under
//! [`NULL_RCOND`] of the largest, in parameters scaled by their ranges) are reported as not
//! constrained, with the parameters they mix.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::scene::Quality;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

use crate::CoatingError;
use crate::basis::{Basis, FIT_NODE_DEG, Rendered, render_ghosts};
use crate::model::{CoatingModel, Family, ModelSurface, ghost_energies};
use crate::reweight::{Colouring, Reweighter, SurfaceTerms};
use crate::solve::{Bound, Minimum, Residuals, jacobian_at, minimise};

/// Singular values of the scaled `JᵀJ` below this fraction of the largest mark directions the
/// image does not constrain.
pub const NULL_RCOND: f64 = 1e-8;
/// A ghost's energy is constrained by the image when its standard error is at most this
/// fraction of it.
pub const CONSTRAINED_ENERGY: f64 = 0.01;

/// Values a parameter takes across its bounds in the surface-by-surface scan of a start: a
/// surface of one parameter takes [`SCAN_STEPS`]², one of two [`SCAN_STEPS`] by
/// [`SCAN_STEPS`] (a single layer's index by its quarter-wave wavelength, 8 × 24).
pub const SCAN_STEPS: usize = 12;
const PRIMES: [u32; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

/// A defect correction that moves no parameter by more than this fraction of its range (or
/// value) ends the corrections.
pub const CORRECTED: f64 = 1e-4;

/// Scan-and-solve rounds after the first solution, while each lowers the cost.
pub const MAX_RESCANS: usize = 2;
/// Rounds of that scan over the surfaces.
pub const SCAN_ROUNDS: usize = 2;

fn surface_params(model: &CoatingModel, s: &ModelSurface) -> usize {
    model
        .surfaces
        .iter()
        .find(|t| t.offset > s.offset)
        .map_or(model.len(), |t| t.offset)
        - s.offset
}

/// The image to fit and which of its pixels count.
#[derive(Clone, Debug)]
pub struct Target {
    /// Linear, the basis frame's size.
    pub image: HdrImage,
    /// True where a pixel counts (unsaturated, not excluded).
    pub mask: Vec<bool>,
}

/// How to fit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub quality: Quality,
    /// Fit the per-channel gains (the light's intensity and colour); otherwise they stay 1.
    pub fit_gains: bool,
    /// Bases rendered: the first with the lens's own coatings, each next with the last fit's.
    pub passes: usize,
    /// Starts of the first pass: (index, quarter-wave nm) of every single layer.
    pub starts: Vec<(f64, f64)>,
    /// Starts spread over the bounds of the coatings' parameters (besides `starts`); every
    /// start is scanned surface by surface before it is solved.
    pub spread_starts: usize,
    /// The first pass's distinct best solutions each refined by the later passes.
    pub candidates: usize,
    /// Start from these parameters (coatings, then the gains when fitted) instead, without
    /// the scan.
    pub initial: Option<Vec<f64>>,
    /// The angles (degrees) of the basis's hat nodes (`crate::basis`).
    pub node_deg: Vec<f64>,
    /// Defect corrections of each refined solution at most: the renderer's image at the
    /// solution's coatings against the basis's, its difference added to the model and the
    /// fit repeated, until the parameters stop moving.
    pub corrections: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            quality: Quality::Default,
            fit_gains: true,
            passes: 3,
            starts: vec![(1.38, 450.0), (1.38, 550.0), (1.38, 650.0), (1.6, 550.0)],
            spread_starts: 8,
            candidates: 3,
            initial: None,
            node_deg: FIT_NODE_DEG.to_vec(),
            corrections: 4,
        }
    }
}

/// One fitted parameter.
#[derive(Clone, Debug, Serialize)]
pub struct FittedParam {
    pub name: String,
    pub value: f64,
    /// Its standard error (`null` when not constrained).
    pub sigma: Option<f64>,
    /// False when the image does not constrain it (alone or in some combination).
    pub constrained: bool,
}

/// One ghost's fitted energy.
#[derive(Clone, Debug, Serialize)]
pub struct FittedGhost {
    pub path: String,
    /// Sum over the frame, per channel.
    pub energy: [f64; 3],
    /// Relative standard error of its energy (sum of channels).
    pub relative_sigma: f64,
    pub constrained: bool,
    /// Its residual: the sum of the image's residual over the pixels where this ghost is at
    /// least half its peak, over its own light there (`null` when it has none unmasked).
    pub residual: Option<f64>,
}

/// A direction in parameter space the image does not see.
#[derive(Clone, Debug, Serialize)]
pub struct Unconstrained {
    /// The parameters it mixes (weight ≥ 0.2 of the direction), with their weights.
    pub params: Vec<(String, f64)>,
    /// Its singular value over the largest.
    pub relative: f64,
}

/// What a fit found.
#[derive(Clone, Debug, Serialize)]
pub struct Fit {
    pub params: Vec<FittedParam>,
    /// Per-channel gains (intensity and colour of the light as the camera saw it).
    pub gains: [f64; 3],
    pub ghosts: Vec<FittedGhost>,
    pub unconstrained: Vec<Unconstrained>,
    /// RMS of the residual over the counted pixels, over the RMS of the image there.
    pub relative_rmse: f64,
    /// The squared residual over the counted pixels and channels.
    pub residual_sq: f64,
    pub pixels_counted: usize,
    pub band_images: usize,
    pub evaluations: usize,
    /// Renders of the basis: the first pass's, then each candidate's refinements.
    pub renders: usize,
    /// Defect corrections made (`FitOptions::corrections`), over every refined solution:
    /// each one render of the ghosts and a solve.
    pub corrections: usize,
    pub converged: bool,
    pub fit_ms: f64,
    pub basis_ms: f64,
    /// Model evaluations per second (colours and the reduced residual).
    pub evaluations_per_s: f64,
    #[serde(skip)]
    pub system: LensSystem,
    #[serde(skip)]
    pub image: HdrImage,
    #[serde(skip)]
    pub basis: Basis,
    #[serde(skip)]
    pub raw: Vec<f64>,
}

/// The Gram system of a basis against a target: `L` (lower triangular) and `L⁻¹v` per
/// channel.
#[derive(Clone, Debug)]
struct Reduced {
    l: DMatrix<f64>,
    z: [DVector<f64>; 3],
    /// `L⁻¹Sᵀd` per channel for the renderer's defect `d` against the basis at the last
    /// correction's coatings (zero before the first): the model is `S(c + M⁻¹Sᵀd)`.
    offset: [Vec<f64>; 3],
    /// `yᵀy − ‖z‖²` per channel: the squared residual no coefficients can remove.
    floor: f64,
    pixels: usize,
}

impl Reduced {
    /// The norm of the defect's offset over the three channels: how far the last correction
    /// moved the reduced residuals.
    fn offset_norm(&self) -> f64 {
        self.offset
            .iter()
            .flatten()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
    }

    /// `Lᵀc` for each channel of the colours `c`: one pass over `L`'s columns (its stored
    /// lower triangle only, each column contiguous), the three channels together.
    fn lt_times(&self, c: &[[f64; 3]]) -> [Vec<f64>; 3] {
        let n = self.l.nrows();
        let l = self.l.as_slice();
        let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for i in 0..n {
            let col = &l[i * n + i..(i + 1) * n];
            let (mut a, mut b, mut d) = (0.0, 0.0, 0.0);
            for (&lji, cj) in col.iter().zip(&c[i..]) {
                a += lji * cj[0];
                b += lji * cj[1];
                d += lji * cj[2];
            }
            out[0][i] = a;
            out[1][i] = b;
            out[2][i] = d;
        }
        out
    }

    /// `Lᵀc` plus the defect's offset: the model's coefficients in the reduced space.
    fn model(&self, c: &[[f64; 3]]) -> [Vec<f64>; 3] {
        let mut lc = self.lt_times(c);
        for (lc, o) in lc.iter_mut().zip(&self.offset) {
            for (a, b) in lc.iter_mut().zip(o) {
                *a += b;
            }
        }
        lc
    }

    /// The residuals `g·lc − L⁻¹v`, channel after channel, from the model's coefficients
    /// `lc` ([`Reduced::model`]).
    fn residuals(&self, lc: &[Vec<f64>; 3], g: [f64; 3]) -> Vec<f64> {
        let mut r = Vec::with_capacity(3 * lc[0].len());
        for ch in 0..3 {
            r.extend(
                lc[ch]
                    .iter()
                    .zip(self.z[ch].iter())
                    .map(|(a, z)| g[ch] * a - z),
            );
        }
        r
    }

    /// Per channel, the gain that fits best for the model's coefficients `lc` (linear least
    /// squares).
    fn best_gains(&self, lc: &[Vec<f64>; 3]) -> [f64; 3] {
        std::array::from_fn(|ch| {
            let num: f64 = lc[ch]
                .iter()
                .zip(self.z[ch].iter())
                .map(|(a, z)| a * z)
                .sum();
            let den: f64 = lc[ch].iter().map(|a| a * a).sum();
            if den > 0.0 && num > 0.0 {
                num / den
            } else {
                1.0
            }
        })
    }
}

/// `Sᵀy` per channel: each band image's product with `y` over the counted pixels.
fn project(basis: &Basis, mask: &[bool], y: &[[f32; 3]]) -> [DVector<f64>; 3] {
    let w = basis.frame.width;
    let bands: Vec<&crate::basis::BandImage> =
        basis.ghosts.iter().flat_map(|g| g.bands.iter()).collect();
    let sums: Vec<[f64; 3]> = bands
        .par_iter()
        .map(|a| {
            let mut s = [0.0; 3];
            for yy in a.y0..a.y0 + a.h {
                for x in a.x0..a.x0 + a.w {
                    let i = yy * w + x;
                    if mask[i] {
                        let b = f64::from(a.pixels[(yy - a.y0) * a.w + (x - a.x0)]);
                        for (s, &c) in s.iter_mut().zip(&y[i]) {
                            *s += b * f64::from(c);
                        }
                    }
                }
            }
            s
        })
        .collect();
    std::array::from_fn(|ch| DVector::from_iterator(bands.len(), sums.iter().map(|s| s[ch])))
}

fn reduce(basis: &Basis, target: &Target) -> Result<Reduced, CoatingError> {
    let bands: Vec<&crate::basis::BandImage> =
        basis.ghosts.iter().flat_map(|g| g.bands.iter()).collect();
    let n = bands.len();
    let w = basis.frame.width;
    let mask = &target.mask;
    let rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let a = bands[i];
            (0..n)
                .map(|j| {
                    let b = bands[j];
                    let (x0, x1) = (a.x0.max(b.x0), (a.x0 + a.w).min(b.x0 + b.w));
                    let (y0, y1) = (a.y0.max(b.y0), (a.y0 + a.h).min(b.y0 + b.h));
                    let mut s = 0.0;
                    for y in y0..y1 {
                        for x in x0..x1 {
                            if mask[y * w + x] {
                                s += f64::from(a.at(x, y)) * f64::from(b.at(x, y));
                            }
                        }
                    }
                    s
                })
                .collect()
        })
        .collect();
    let m = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
    let v = project(basis, mask, &target.image.pixels);
    let yy: f64 = target
        .image
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| p.iter().map(|&c| f64::from(c) * f64::from(c)).sum::<f64>())
        .sum();
    let scale = (0..n).map(|i| m[(i, i)]).fold(0.0, f64::max).max(1e-300);
    let mut ridge = 1e-12 * scale;
    let chol = loop {
        let mut mm = m.clone();
        for i in 0..n {
            mm[(i, i)] += ridge;
        }
        if let Some(c) = mm.cholesky() {
            break c;
        }
        ridge *= 10.0;
        // A positive semidefinite Gram matrix factors long before this; one that does not
        // holds non-finite values.
        if ridge > scale {
            return Err(CoatingError::Colours);
        }
    };
    let l = chol.unpack();
    let z: [DVector<f64>; 3] = std::array::from_fn(|ch| {
        l.solve_lower_triangular(&v[ch])
            .unwrap_or_else(|| DVector::zeros(n))
    });
    let floor = yy - z.iter().map(|z| z.norm_squared()).sum::<f64>();
    Ok(Reduced {
        offset: std::array::from_fn(|_| vec![0.0; n]),
        l,
        z,
        floor: floor.max(0.0),
        pixels: mask.iter().filter(|m| **m).count(),
    })
}

/// The fit's residuals for parameters `p` (coatings, then gains when fitted).
struct Evaluator<'a> {
    model: &'a CoatingModel,
    basis: &'a Basis,
    bins: Reweighter,
    reduced: Reduced,
    fit_gains: bool,
}

impl Evaluator<'_> {
    fn gains(&self, p: &[f64]) -> [f64; 3] {
        if self.fit_gains {
            let k = self.model.len();
            [p[k], p[k + 1], p[k + 2]]
        } else {
            [1.0; 3]
        }
    }

    fn colours(&self, p: &[f64]) -> Option<Vec<[f64; 3]>> {
        let sys = self.model.apply(&p[..self.model.len()]);
        Some(self.bins.colours(&sys))
    }

    fn residuals(&self, p: &[f64]) -> Vec<f64> {
        match self.colours(p) {
            Some(c) => self.residuals_of(&c, self.gains(p)),
            None => vec![f64::NAN; 3 * self.reduced.z[0].len()],
        }
    }

    /// The residuals of colours `c` (in the basis's order) under gains `g`.
    fn residuals_of(&self, c: &[[f64; 3]], g: [f64; 3]) -> Vec<f64> {
        self.reduced.residuals(&self.reduced.model(c), g)
    }

    /// Half the squared residual at `p` with the gains that fit best there.
    fn cost_with_best_gains(&self, p: &mut [f64]) -> f64 {
        let Some(c) = self.colours(p) else {
            return f64::INFINITY;
        };
        self.cost_of_colours(&c, p)
    }

    /// The colours of parameters `q` that differ from those of `system` (whose surfaces'
    /// terms are `terms`) in surface `s`'s parameters only.
    fn colours_moved(
        &self,
        system: &LensSystem,
        terms: &[SurfaceTerms],
        s: &ModelSurface,
        q: &[f64],
    ) -> Vec<[f64; 3]> {
        let at = s.coatable.surface;
        let mut surface = system.surfaces[at].clone();
        surface.coating = self.model.coating(s, q);
        let own = self.bins.surface_terms(at, &surface);
        let refs: Vec<&SurfaceTerms> = terms
            .iter()
            .enumerate()
            .map(|(i, t)| if i == at { &own } else { t })
            .collect();
        self.bins.colours_of(&refs, system.sensor_index())
    }

    /// Half the squared residual of colours `c` with the gains that fit best for them
    /// (written into `p`'s gains).
    fn cost_of_colours(&self, c: &[[f64; 3]], p: &mut [f64]) -> f64 {
        let lc = self.reduced.model(c);
        let g = if self.fit_gains {
            let g = self.reduced.best_gains(&lc);
            let k = self.model.len();
            p[k..k + 3].copy_from_slice(&g);
            g
        } else {
            [1.0; 3]
        };
        0.5 * self
            .reduced
            .residuals(&lc, g)
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
    }

    /// A start improved surface by surface: each surface's parameters in turn over a grid
    /// across their bounds ([`SCAN_STEPS`]) (the others held, the gains
    /// the best for each), the best kept; [`SCAN_ROUNDS`] rounds over the surfaces. A single
    /// layer's reflectance is periodic in its thickness, so a local solver from one start
    /// stops in whichever valley it starts in; the scan finds each surface's valley.
    fn scan(&self, mut p: Vec<f64>, bounds: &[Bound]) -> Vec<f64> {
        let mut cost = self.cost_with_best_gains(&mut p);
        for _ in 0..SCAN_ROUNDS {
            for s in &self.model.surfaces {
                let range = s.offset..s.offset + surface_params(self.model, s);
                if range.is_empty() || range.len() > 2 {
                    continue;
                }
                let steps = |k: usize| match (range.len(), k) {
                    (1, _) => SCAN_STEPS * SCAN_STEPS,
                    (_, 0) if s.family == Family::Single => SCAN_STEPS / 2,
                    _ if s.family == Family::Single => SCAN_STEPS * 3 / 2,
                    _ => SCAN_STEPS,
                };
                let axes: Vec<Vec<f64>> = range
                    .clone()
                    .enumerate()
                    .map(|(k, i)| match bounds[i] {
                        Bound::Range(lo, hi) => (0..steps(k))
                            .map(|j| lo + (hi - lo) * (j as f64 + 0.5) / steps(k) as f64)
                            .collect(),
                        Bound::Positive => vec![p[i]],
                    })
                    .collect();
                let mut grid: Vec<Vec<f64>> = vec![Vec::new()];
                for axis in &axes {
                    grid = grid
                        .iter()
                        .flat_map(|g| axis.iter().map(move |&v| [g.as_slice(), &[v]].concat()))
                        .collect();
                }
                // Only this surface's terms change across its grid.
                let system = self.model.apply(&p[..self.model.len()]);
                let terms = self.bins.terms(&system);
                let best = grid
                    .par_iter()
                    .map(|values| {
                        let mut q = p.clone();
                        q[range.clone()].copy_from_slice(values);
                        let c = self.colours_moved(&system, &terms, s, &q);
                        (self.cost_of_colours(&c, &mut q), q)
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some((c, q)) = best.filter(|(c, _)| *c < cost) {
                    cost = c;
                    p = q;
                }
            }
        }
        p
    }

    /// Per channel, the gains that fit best for the coatings of `p` (linear least squares).
    fn best_gains(&self, p: &[f64]) -> [f64; 3] {
        self.colours(p).map_or([1.0; 3], |c| self.best_gains_of(&c))
    }

    /// Per channel, the gains that fit best for colours `c`.
    fn best_gains_of(&self, c: &[[f64; 3]]) -> [f64; 3] {
        self.reduced.best_gains(&self.reduced.model(c))
    }
}

impl Residuals for Evaluator<'_> {
    fn residuals(&self, p: &[f64]) -> Vec<f64> {
        Evaluator::residuals(self, p)
    }

    /// By central differences of steps [`Bound::step`], each coating parameter's column
    /// from its own surface's terms (the other surfaces' held from `p`), the gains' columns
    /// exactly (the residuals are linear in them).
    fn jacobian(&self, p: &[f64], bounds: &[Bound]) -> Option<(DMatrix<f64>, usize)> {
        let k = self.model.len();
        let system = self.model.apply(&p[..k]);
        let terms = self.bins.terms(&system);
        let sensor = system.sensor_index();
        let g = self.gains(p);
        let n = self.reduced.z[0].len();
        let lc = if self.fit_gains {
            let refs: Vec<&SurfaceTerms> = terms.iter().collect();
            Some(self.reduced.model(&self.bins.colours_of(&refs, sensor)))
        } else {
            None
        };
        let columns: Vec<Vec<f64>> = (0..p.len())
            .into_par_iter()
            .map(|j| {
                if j >= k {
                    let ch = j - k;
                    let mut col = vec![0.0; 3 * n];
                    if let Some(lc) = &lc {
                        col[ch * n..(ch + 1) * n].copy_from_slice(&lc[ch]);
                    }
                    return col;
                }
                let s = self
                    .model
                    .surfaces
                    .iter()
                    .rfind(|s| s.offset <= j)
                    .expect("a coating parameter belongs to a surface");
                let h = bounds[j].step(p[j]);
                let moved = |d: f64| {
                    let mut q = p.to_vec();
                    q[j] += d;
                    let c = self.colours_moved(&system, &terms, s, &q);
                    self.reduced.residuals(&self.reduced.model(&c), g)
                };
                let (a, b) = (moved(h), moved(-h));
                a.iter().zip(&b).map(|(a, b)| (a - b) / (2.0 * h)).collect()
            })
            .collect();
        let jac = DMatrix::from_fn(3 * n, p.len(), |i, j| columns[j][i]);
        Some((jac, 2 * k))
    }
}

/// Evaluations and renders a stage made.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    evaluations: usize,
    renders: usize,
}

/// Corrects `found` for the basis's defect (`FitOptions::corrections` times at most): renders
/// the ghosts at its coatings ([`render_ghosts`]), takes the difference `d` from the basis's
/// image there into the model as `S(c + M⁻¹Sᵀd)` (its part the band images span), and solves
/// again from it; stops when no parameter moves by more than [`CORRECTED`] of its range (or
/// value). The fixed point is where the renderer's own image, not the basis's, fits best, as
/// far as the basis's Jacobian leads there.
fn correct<'a>(
    mut ev: Evaluator<'a>,
    aperture: &Aperture,
    light: &ghost_raytrace::scene::LightSpec,
    target: &Target,
    bounds: &[Bound],
    options: &FitOptions,
    mut found: Minimum,
) -> Result<(Evaluator<'a>, Minimum, Counts), CoatingError> {
    let mut counts = Counts::default();
    let k = ev.model.len();
    for _ in 0..options.corrections {
        let system = ev.model.apply(&found.params[..k]);
        let rendered =
            render_ghosts(&system, aperture, ev.basis.frame, light, options.quality)?.image;
        counts.renders += 1;
        let modelled = model_image(ev.basis, &ev.bins.colours(&system), [1.0; 3]);
        let defect: Vec<[f32; 3]> = rendered
            .pixels
            .iter()
            .zip(&modelled.pixels)
            .map(|(r, m)| std::array::from_fn(|ch| r[ch] - m[ch]))
            .collect();
        let sd = project(ev.basis, &target.mask, &defect);
        for (o, sd) in ev.reduced.offset.iter_mut().zip(&sd) {
            *o = ev
                .reduced
                .l
                .solve_lower_triangular(sd)
                .ok_or(CoatingError::Colours)?
                .iter()
                .copied()
                .collect();
        }
        let again = minimise(&ev, &found.params, bounds);
        counts.evaluations += again.evaluations;
        let moved = largest_move(&again.params, &found.params, bounds);
        found = again;
        if moved <= CORRECTED {
            break;
        }
    }
    Ok((ev, found, counts))
}

/// The largest difference between parameters `a` and `b`, each over its bound's range (or
/// the larger of the two values for a positive one).
fn largest_move(a: &[f64], b: &[f64], bounds: &[Bound]) -> f64 {
    a.iter()
        .zip(b)
        .zip(bounds)
        .map(|((a, b), bd)| {
            let scale = match bd {
                Bound::Range(lo, hi) => hi - lo,
                Bound::Positive => a.abs().max(b.abs()).max(1e-12),
            };
            (a - b).abs() / scale
        })
        .fold(0.0, f64::max)
}

/// Up to `k` of `found` (best first) that differ: each more than 2% of some parameter's range
/// (or value) from every one kept before it.
fn distinct(found: &[Minimum], bounds: &[Bound], k: usize) -> Vec<Minimum> {
    let mut kept: Vec<Minimum> = Vec::new();
    for m in found {
        let differs = |o: &Minimum| largest_move(&m.params, &o.params, bounds) > 0.02;
        if kept.iter().all(differs) {
            kept.push(m.clone());
            if kept.len() == k {
                break;
            }
        }
    }
    kept
}

/// Starts spread over the bounds' box of the coatings' parameters (an additive recurrence with
/// the square roots of primes: the same each run), each with its best gains.
fn spread_starts(
    model: &CoatingModel,
    bounds: &[Bound],
    ev: &Evaluator<'_>,
    options: &FitOptions,
) -> Vec<Vec<f64>> {
    let k = model.len();
    (1..=options.spread_starts)
        .map(|j| {
            let mut p: Vec<f64> = bounds[..k]
                .iter()
                .enumerate()
                .map(|(d, b)| {
                    let a = f64::from(PRIMES[d % PRIMES.len()]).sqrt().fract();
                    let t = (j as f64 * a + 0.5 * (d / PRIMES.len()) as f64).fract();
                    match *b {
                        Bound::Range(lo, hi) => lo + (hi - lo) * t,
                        Bound::Positive => 1.0,
                    }
                })
                .collect();
            if options.fit_gains {
                p.extend(ev.best_gains(&p));
            }
            p
        })
        .collect()
}

/// Fits `model`'s coatings (and the gains) to `target`, rendering the basis with `aperture`
/// at `target`'s frame under `light`.
pub fn fit(
    model: &CoatingModel,
    aperture: &Aperture,
    light: &ghost_raytrace::scene::LightSpec,
    target: &Target,
    options: &FitOptions,
) -> Result<Fit, CoatingError> {
    let frame = flarebench_sdk::frame::Frame::across_film(
        target.image.width,
        target.image.height,
        model.system().film_width_mm,
    );
    if target.mask.len() != target.image.pixels.len() {
        return Err(CoatingError::MaskSize);
    }
    let mut bounds = model.bounds();
    if options.fit_gains {
        bounds.extend([Bound::Positive; 3]);
    }
    let scan = options.initial.is_none();
    let (mut evaluations, mut fit_ms, mut basis_ms, mut renders) = (0, 0.0, 0.0, 0);
    let mut corrections = 0;
    // One pass: the basis rendered with `at`'s coatings (the lens's own without), then the
    // solver from `starts` (each scanned first when `scan_starts`), then rescans from the best.
    // Returns every solution found, best first, with the pass's basis.
    let mut pass = |at: Option<&Vec<f64>>,
                    starts_of: &dyn Fn(&Evaluator<'_>) -> Vec<Vec<f64>>,
                    scan_starts: bool|
     -> Result<(Basis, Reweighter, Reduced, Vec<Minimum>), CoatingError> {
        let t0 = std::time::Instant::now();
        let system = match at {
            Some(p) => model.apply(&p[..model.len()]),
            None => model.system().clone(),
        };
        let basis = Basis::render_with_nodes(
            &system,
            aperture,
            frame,
            light,
            options.quality,
            &options.node_deg,
        )?;
        basis_ms += t0.elapsed().as_secs_f64() * 1e3;
        renders += 1;
        let t1 = std::time::Instant::now();
        let ev = Evaluator {
            model,
            bins: Reweighter::new(&basis, &system, Colouring::Renderer)?,
            reduced: reduce(&basis, target)?,
            basis: &basis,
            fit_gains: options.fit_gains,
        };
        let mut tried: Vec<Minimum> = starts_of(&ev)
            .into_par_iter()
            .map(|s| {
                let s = if scan_starts { ev.scan(s, &bounds) } else { s };
                minimise(&ev, &s, &bounds)
            })
            .collect();
        evaluations += tried.iter().map(|m| m.evaluations).sum::<usize>();
        tried.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        if tried.is_empty() {
            return Err(CoatingError::NoStart);
        }
        // Scan from the best and solve again while that lowers the cost: the solver stops in
        // a valley of the joint problem that a surface's scan can leave.
        if scan {
            for _ in 0..MAX_RESCANS {
                let again = minimise(&ev, &ev.scan(tried[0].params.clone(), &bounds), &bounds);
                evaluations += again.evaluations;
                if again.cost >= tried[0].cost * (1.0 - 1e-6) {
                    break;
                }
                tried.insert(0, again);
            }
        }
        fit_ms += t1.elapsed().as_secs_f64() * 1e3;
        let Evaluator { bins, reduced, .. } = ev;
        Ok((basis, bins, reduced, tried))
    };
    // The first pass from every start; its distinct best solutions are each refined by the
    // remaining passes (the basis rendered anew at each), and the best refined one is kept:
    // each is judged under a basis rendered with its own coatings, so a minimum that only
    // the first basis's error made look best loses to one that is.
    let first_starts = |ev: &Evaluator<'_>| -> Vec<Vec<f64>> {
        if let Some(p) = &options.initial {
            return vec![p.clone()];
        }
        let mut starts: Vec<Vec<f64>> = Vec::new();
        for &(n, q) in &options.starts {
            let mut p = model.start(n, q);
            if options.fit_gains {
                p.extend(ev.best_gains(&p));
            }
            // Without single layers every start is the designs' nominal one.
            if !starts.contains(&p) {
                starts.push(p);
            }
        }
        starts.extend(spread_starts(model, &bounds, ev, options));
        starts
    };
    let (basis0, bins0, reduced0, found0) = pass(options.initial.as_ref(), &first_starts, scan)?;
    let candidates = distinct(&found0, &bounds, options.candidates.max(1));
    // The refined solutions (with one pass, the first pass's distinct best on its basis),
    // each then corrected for its basis's defect; the best corrected one kept.
    let mut bases: Vec<Basis> = Vec::new();
    let mut refined: Vec<(usize, Reweighter, Reduced, Minimum)> = Vec::new();
    if options.passes <= 1 {
        bases.push(basis0);
        for c in candidates {
            refined.push((0, bins0.clone(), reduced0.clone(), c));
        }
    } else {
        drop((basis0, bins0, reduced0));
        for c in candidates {
            let mut current = c;
            let mut last = None;
            for _ in 1..options.passes {
                let start = current.params.clone();
                let (basis, bins, reduced, found) =
                    pass(Some(&start), &|_| vec![start.clone()], false)?;
                current = found[0].clone();
                last = Some((basis, bins, reduced, current.clone()));
            }
            if let Some((basis, bins, reduced, found)) = last {
                bases.push(basis);
                refined.push((bases.len() - 1, bins, reduced, found));
            }
        }
    }
    // Corrected best first. A correction moves a solution's residual norm by about its
    // basis's defect's part in the band images' span (the offset's norm); a solution whose
    // norm exceeds the best corrected one's by more than twice that defect is left as it is.
    refined.sort_by(|a, b| a.3.cost.total_cmp(&b.3.cost));
    let mut last: Option<(usize, Reweighter, Reduced, Minimum)> = None;
    let mut defect = 0.0_f64;
    for (b, bins, reduced, found) in refined {
        if let Some(l) = &last
            && options.corrections > 0
            && (2.0 * found.cost).sqrt() > (2.0 * l.3.cost).sqrt() + 2.0 * defect
        {
            continue;
        }
        let t0 = std::time::Instant::now();
        let ev = Evaluator {
            model,
            basis: &bases[b],
            bins,
            reduced,
            fit_gains: options.fit_gains,
        };
        let (ev, found, counts) = correct(ev, aperture, light, target, &bounds, options, found)?;
        defect = defect.max(ev.reduced.offset_norm());
        evaluations += counts.evaluations;
        corrections += counts.renders;
        fit_ms += t0.elapsed().as_secs_f64() * 1e3;
        let Evaluator { bins, reduced, .. } = ev;
        if last.as_ref().is_none_or(|l| found.cost < l.3.cost) {
            last = Some((b, bins, reduced, found));
        }
    }
    let converged = last.as_ref().is_some_and(|l| l.3.converged);
    let (b, bins, reduced, found) = last.expect("at least one pass");
    let basis = bases.swap_remove(b);
    let p = found.params;
    let ev = Evaluator {
        model,
        basis: &basis,
        bins,
        reduced,
        fit_gains: options.fit_gains,
    };
    // Evaluations per second, measured on the residuals alone.
    let t = std::time::Instant::now();
    let mut k = 0;
    while t.elapsed().as_secs_f64() < 0.2 || k < 3 {
        std::hint::black_box(ev.residuals(&p));
        k += 1;
    }
    let evaluations_per_s = k as f64 / t.elapsed().as_secs_f64();
    // The renderer's image and ghost energies at the solution, when it was corrected by them.
    let rendered = if options.corrections > 0 {
        let system = model.apply(&p[..model.len()]);
        Some(render_ghosts(
            &system,
            aperture,
            basis.frame,
            light,
            options.quality,
        )?)
    } else {
        None
    };
    summarise(
        &ev,
        &p,
        &bounds,
        target,
        rendered,
        (evaluations, renders, corrections, converged),
        (fit_ms, basis_ms, evaluations_per_s),
    )
}

/// The fit's report at `p`. With `rendered` (the renderer's image and ghost energies at `p`'s
/// coatings, gains 1) the fitted image and the ghosts' energies are the renderer's, else the
/// basis's.
fn summarise(
    ev: &Evaluator<'_>,
    p: &[f64],
    bounds: &[Bound],
    target: &Target,
    rendered: Option<Rendered>,
    (evaluations, renders, corrections, converged): (usize, usize, usize, bool),
    (fit_ms, basis_ms, evaluations_per_s): (f64, f64, f64),
) -> Result<Fit, CoatingError> {
    let model = ev.model;
    let names: Vec<String> = model
        .names()
        .into_iter()
        .chain(
            ev.fit_gains
                .then(|| ["gain R", "gain G", "gain B"].map(String::from))
                .into_iter()
                .flatten(),
        )
        .collect();
    let r = ev.residuals(p);
    let sq: f64 = r.iter().map(|v| v * v).sum::<f64>() + ev.reduced.floor;
    let dof = (3 * ev.reduced.pixels).saturating_sub(p.len()).max(1) as f64;
    let s2 = sq / dof;
    // Jacobian in parameters scaled by their ranges (or values), its SVD.
    let (jac, _) = Residuals::jacobian(ev, p, bounds).expect("the fit's Jacobian");
    let scale: Vec<f64> = bounds
        .iter()
        .zip(p)
        .map(|(b, &v)| match b {
            Bound::Range(lo, hi) => hi - lo,
            Bound::Positive => v.abs().max(1e-12),
        })
        .collect();
    let js = DMatrix::from_fn(jac.nrows(), jac.ncols(), |i, j| jac[(i, j)] * scale[j]);
    let jtj = js.transpose() * &js;
    let eig = jtj.clone().symmetric_eigen();
    let top = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let mut unconstrained = Vec::new();
    let mut free = vec![false; p.len()];
    let mut inv = DMatrix::zeros(p.len(), p.len());
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        let vec = eig.eigenvectors.column(k);
        if lambda <= NULL_RCOND * top || lambda <= 0.0 {
            let params: Vec<(String, f64)> = vec
                .iter()
                .enumerate()
                .filter(|(_, w)| w.abs() >= 0.2)
                .map(|(i, w)| {
                    free[i] = true;
                    (names[i].clone(), *w)
                })
                .collect();
            unconstrained.push(Unconstrained {
                params,
                relative: (lambda.max(0.0) / top.max(1e-300)).sqrt(),
            });
        } else {
            inv += (vec * vec.transpose()) / lambda;
        }
    }
    // Back to the parameters' own units.
    let cov = DMatrix::from_fn(p.len(), p.len(), |i, j| {
        s2 * inv[(i, j)] * scale[i] * scale[j]
    });
    let params: Vec<FittedParam> = names
        .iter()
        .enumerate()
        .map(|(i, name)| FittedParam {
            name: name.clone(),
            value: p[i],
            sigma: (!free[i]).then(|| cov[(i, i)].max(0.0).sqrt()),
            constrained: !free[i],
        })
        .collect();
    // Ghost energies and their errors (the gradient by central differences).
    let gains = ev.gains(p);
    let colours = ev.colours(p).ok_or(CoatingError::Colours)?;
    let mut energies = ghost_energies(ev.basis, &colours, gains);
    let image = match rendered {
        Some(Rendered {
            mut image,
            energies: rendered_energies,
        }) => {
            for (e, g) in energies.iter_mut().zip(&ev.basis.ghosts) {
                if let Some((_, r)) = rendered_energies.iter().find(|(path, _)| *path == g.path) {
                    *e = std::array::from_fn(|ch| r[ch] * gains[ch]);
                }
            }
            for px in image.pixels.iter_mut() {
                for (c, g) in px.iter_mut().zip(gains) {
                    *c *= g as f32;
                }
            }
            image
        }
        None => model_image(ev.basis, &colours, gains),
    };
    let total = |q: &[f64]| -> Vec<f64> {
        match ev.colours(q) {
            Some(c) => ghost_energies(ev.basis, &c, ev.gains(q))
                .iter()
                .map(|e| e.iter().sum())
                .collect(),
            None => vec![f64::NAN; energies.len()],
        }
    };
    let grad = jacobian_at(&total, p, bounds);
    let residual_of = residual_per_ghost(ev.basis, &colours, gains, &image, target);
    let ghosts = ev
        .basis
        .ghosts
        .iter()
        .enumerate()
        .map(|(g, gb)| {
            let e: f64 = energies[g].iter().sum();
            let row = grad.row(g).transpose();
            // A direction the image does not see moves the energy without bound.
            let free_moves = free
                .iter()
                .enumerate()
                .any(|(i, &f)| f && row[i].abs() * scale[i] > 1e-9 * e.abs());
            let var = (row.transpose() * &cov * &row)[(0, 0)];
            let rel = if free_moves || e <= 0.0 {
                f64::INFINITY
            } else {
                var.max(0.0).sqrt() / e
            };
            FittedGhost {
                path: gb.path.to_string(),
                energy: energies[g],
                relative_sigma: rel,
                constrained: rel <= CONSTRAINED_ENERGY,
                residual: residual_of[g],
            }
        })
        .collect();
    let counted: Vec<usize> = (0..target.mask.len()).filter(|&i| target.mask[i]).collect();
    let (mut num, mut den) = (0.0, 0.0);
    for &i in &counted {
        for ch in 0..3 {
            let (m, y) = (
                f64::from(image.pixels[i][ch]),
                f64::from(target.image.pixels[i][ch]),
            );
            num += (m - y) * (m - y);
            den += y * y;
        }
    }
    Ok(Fit {
        params,
        gains,
        ghosts,
        unconstrained,
        relative_rmse: if den > 0.0 { (num / den).sqrt() } else { 0.0 },
        residual_sq: num,
        pixels_counted: counted.len(),
        band_images: ev.basis.band_count(),
        evaluations,
        renders,
        corrections,
        converged,
        fit_ms,
        basis_ms,
        evaluations_per_s,
        system: model.apply(&p[..model.len()]),
        image,
        basis: ev.basis.clone(),
        raw: p.to_vec(),
    })
}

/// The model image: every band image times its colour and the gains.
pub fn model_image(basis: &Basis, colours: &[[f64; 3]], gains: [f64; 3]) -> HdrImage {
    let (w, h) = (basis.frame.width, basis.frame.height);
    let mut img = HdrImage::new(w, h);
    let mut c = colours.iter();
    for g in &basis.ghosts {
        for b in &g.bands {
            let col = c.next().expect("one colour per band image");
            let k: [f32; 3] = std::array::from_fn(|ch| (col[ch] * gains[ch]) as f32);
            for y in 0..b.h {
                let row = &mut img.pixels[(b.y0 + y) * w + b.x0..(b.y0 + y) * w + b.x0 + b.w];
                for (o, &s) in row.iter_mut().zip(&b.pixels[y * b.w..(y + 1) * b.w]) {
                    for ch in 0..3 {
                        o[ch] += s * k[ch];
                    }
                }
            }
        }
    }
    img
}

/// Per ghost: the image's residual (model − target, summed over channels) over the counted
/// pixels where the ghost is at least half its own peak, over the ghost's light there.
fn residual_per_ghost(
    basis: &Basis,
    colours: &[[f64; 3]],
    gains: [f64; 3],
    image: &HdrImage,
    target: &Target,
) -> Vec<Option<f64>> {
    let w = basis.frame.width;
    let mut c = colours.iter();
    basis
        .ghosts
        .iter()
        .map(|g| {
            // The ghost's own image (sum of channels) over the union of its bands' boxes.
            let cols: Vec<f64> = g
                .bands
                .iter()
                .map(|_| {
                    let col = c.next().expect("one colour per band image");
                    (0..3).map(|ch| col[ch] * gains[ch]).sum()
                })
                .collect();
            let x0 = g.bands.iter().map(|b| b.x0).min()?;
            let y0 = g.bands.iter().map(|b| b.y0).min()?;
            let x1 = g.bands.iter().map(|b| b.x0 + b.w).max()?;
            let y1 = g.bands.iter().map(|b| b.y0 + b.h).max()?;
            let own = |x: usize, y: usize| -> f64 {
                g.bands
                    .iter()
                    .zip(&cols)
                    .map(|(b, k)| f64::from(b.at(x, y)) * k)
                    .sum()
            };
            let mut peak: f64 = 0.0;
            for y in y0..y1 {
                for x in x0..x1 {
                    peak = peak.max(own(x, y));
                }
            }
            let (mut res, mut light) = (0.0, 0.0);
            for y in y0..y1 {
                for x in x0..x1 {
                    let o = own(x, y);
                    if o >= 0.5 * peak && target.mask[y * w + x] {
                        let i = y * w + x;
                        res += (0..3)
                            .map(|ch| {
                                f64::from(image.pixels[i][ch])
                                    - f64::from(target.image.pixels[i][ch])
                            })
                            .sum::<f64>();
                        light += o;
                    }
                }
            }
            (light > 0.0).then(|| res / light)
        })
        .collect()
}

//! Choosing each surface's coating from the catalogue to cut a lens's flare.
//!
//! For a set of light angles, each angle's basis (`crate::basis`) is rendered once; an
//! assignment of designs to the air–glass surfaces then costs its ghosts' colours
//! (`crate::reweight`) per angle. The objective is one of [`Objective`]'s, over the angles. The
//! search is coordinate descent from MgF₂ everywhere: each surface in turn takes the design
//! that lowers the objective most within the budget of premium surfaces, rounds repeated until
//! none changes (a local optimum of single-surface moves, not a proven global one).

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use ghost_raytrace::scene::{LightSpec, Quality};
use rayon::prelude::*;
use serde::Serialize;

use crate::CoatingError;
use crate::basis::Basis;
use crate::catalogue::{Coatable, Design, coatable_surfaces};
use crate::reweight::{Colouring, Reweighter};

/// What the choice minimises, over the light angles.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind", content = "threshold")]
pub enum Objective {
    /// The ghosts' energy on the frame (luminance), summed over the angles.
    Total,
    /// The brightest ghost's energy, the largest over the angles.
    Brightest,
    /// The energy of the ghosts whose peak (luminance of their brightest pixel) is above this
    /// fraction of the brightest ghost's peak at the same angle with MgF₂ everywhere: the
    /// ghosts that stand out, summed over the angles.
    Visible(f64),
}

/// Rec. 709 luminance of linear sRGB.
fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// One light angle's basis and reweighter.
#[derive(Debug)]
struct Angle {
    basis: Basis,
    reweighter: Reweighter,
}

/// A lens's flare under its air–glass surfaces' designs, angle by angle.
#[derive(Debug)]
pub struct Chooser {
    system: LensSystem,
    surfaces: Vec<Coatable>,
    angles: Vec<Angle>,
    objective: Objective,
    /// Per angle, the brightest ghost's peak with MgF₂ everywhere.
    reference_peaks: Vec<f64>,
}

/// Per ghost path, its energy (luminance on the frame) at each angle.
#[derive(Clone, Debug, Serialize)]
pub struct GhostEnergy {
    pub path: String,
    pub energy: Vec<f64>,
    /// Its peak per angle (luminance of its brightest pixel).
    pub peak: Vec<f64>,
}

/// The flare under one assignment.
#[derive(Clone, Debug, Serialize)]
pub struct Evaluation {
    pub designs: Vec<(usize, Design)>,
    pub objective: f64,
    /// The ghosts' total energy on the frame at each angle.
    pub total: Vec<f64>,
    pub ghosts: Vec<GhostEnergy>,
}

/// What the choice found.
#[derive(Clone, Debug, Serialize)]
pub struct Choice {
    pub before: Evaluation,
    pub after: Evaluation,
    /// Objective before over after.
    pub factor: f64,
    pub evaluations: usize,
    pub rounds: usize,
    pub basis_ms: f64,
    pub choice_ms: f64,
}

impl Chooser {
    /// The bases of `system` for `lights` at `frame`, rendered with MgF₂ on every air–glass
    /// surface (the start, and where the basis is closest to the designs between).
    pub fn new(
        system: &LensSystem,
        aperture: &Aperture,
        frame: Frame,
        lights: &[LightSpec],
        quality: Quality,
        objective: Objective,
    ) -> Result<Chooser, CoatingError> {
        let surfaces = coatable_surfaces(system);
        if surfaces.is_empty() {
            return Err(CoatingError::NothingToCoat(system.name.clone()));
        }
        let start = assign(system, &surfaces, &vec![Design::Mgf2; surfaces.len()]);
        let angles = lights
            .iter()
            .map(|light| {
                let basis = Basis::render(&start, aperture, frame, light, quality)?;
                let reweighter = Reweighter::new(&basis, &start, Colouring::Cells)?;
                Ok(Angle { basis, reweighter })
            })
            .collect::<Result<Vec<_>, CoatingError>>()?;
        let reference_peaks = angles
            .iter()
            .map(|a| {
                ghost_figures(&a.basis, &a.reweighter.colours(&start), true)
                    .iter()
                    .map(|g| g.2)
                    .fold(0.0, f64::max)
            })
            .collect();
        Ok(Chooser {
            system: system.clone(),
            surfaces,
            angles,
            objective,
            reference_peaks,
        })
    }

    /// The air–glass surfaces, in order.
    pub fn surfaces(&self) -> &[Coatable] {
        &self.surfaces
    }

    /// The lens with `designs` (one per [`Chooser::surfaces`]).
    pub fn lens(&self, designs: &[Design]) -> LensSystem {
        assign(&self.system, &self.surfaces, designs)
    }

    /// The flare under `designs`.
    pub fn evaluate(&self, designs: &[Design]) -> Evaluation {
        self.evaluate_with(designs, true)
    }

    /// The flare under `designs`, its ghosts' peaks measured only when `peaks` is set or the
    /// objective needs them (each costs a pass over the ghost's band images; the search's
    /// trials of the total and brightest objectives do without).
    fn evaluate_with(&self, designs: &[Design], peaks: bool) -> Evaluation {
        let peaks = peaks || matches!(self.objective, Objective::Visible(_));
        let sys = self.lens(designs);
        let per_angle: Vec<Vec<(String, f64, f64)>> = self
            .angles
            .iter()
            .map(|a| ghost_figures(&a.basis, &a.reweighter.colours(&sys), peaks))
            .collect();
        let paths: Vec<String> = per_angle
            .iter()
            .flat_map(|g| g.iter().map(|(p, _, _)| p.clone()))
            .fold(Vec::new(), |mut v, p| {
                if !v.contains(&p) {
                    v.push(p);
                }
                v
            });
        let ghosts: Vec<GhostEnergy> = paths
            .iter()
            .map(|p| {
                let (energy, peak) = per_angle
                    .iter()
                    .map(|g| {
                        g.iter()
                            .find(|(q, _, _)| q == p)
                            .map_or((0.0, 0.0), |(_, e, k)| (*e, *k))
                    })
                    .unzip();
                GhostEnergy {
                    path: p.clone(),
                    energy,
                    peak,
                }
            })
            .collect();
        let total: Vec<f64> = (0..self.angles.len())
            .map(|k| ghosts.iter().map(|g| g.energy[k]).sum())
            .collect();
        let objective = match self.objective {
            Objective::Total => total.iter().sum(),
            Objective::Brightest => ghosts
                .iter()
                .flat_map(|g| g.energy.iter().copied())
                .fold(0.0, f64::max),
            Objective::Visible(threshold) => {
                let direct = &self.reference_peaks;
                ghosts
                    .iter()
                    .flat_map(|g| {
                        g.energy
                            .iter()
                            .zip(&g.peak)
                            .zip(direct)
                            .filter(|((_, p), d)| **p > threshold * **d)
                            .map(|((e, _), _)| *e)
                    })
                    .sum()
            }
        };
        Evaluation {
            designs: self
                .surfaces
                .iter()
                .zip(designs)
                .map(|(s, d)| (s.surface, *d))
                .collect(),
            objective,
            total,
            ghosts,
        }
    }

    /// Coordinate descent from MgF₂ everywhere, with at most `max_premium` surfaces of a
    /// premium design (module docs).
    pub fn choose(&self, max_premium: usize) -> Choice {
        let t = std::time::Instant::now();
        let n = self.surfaces.len();
        let start = vec![Design::Mgf2; n];
        let before = self.evaluate(&start);
        let mut designs = start;
        let mut best = before.objective;
        let (mut evaluations, mut rounds) = (1, 0);
        loop {
            rounds += 1;
            let mut changed = false;
            for s in 0..n {
                let premium_elsewhere = designs
                    .iter()
                    .enumerate()
                    .filter(|(i, d)| *i != s && d.is_premium())
                    .count();
                let tried: Vec<(Design, f64)> = Design::ALL
                    .par_iter()
                    .filter(|d| **d != designs[s])
                    .filter(|d| !d.is_premium() || premium_elsewhere < max_premium)
                    .map(|&d| {
                        let mut trial = designs.clone();
                        trial[s] = d;
                        (d, self.evaluate_with(&trial, false).objective)
                    })
                    .collect();
                evaluations += tried.len();
                if let Some(&(d, v)) = tried.iter().min_by(|a, b| a.1.total_cmp(&b.1))
                    && v < best * (1.0 - 1e-9)
                {
                    designs[s] = d;
                    best = v;
                    changed = true;
                }
            }
            if !changed || rounds >= 8 {
                break;
            }
        }
        let after = self.evaluate(&designs);
        Choice {
            factor: if after.objective > 0.0 {
                before.objective / after.objective
            } else {
                f64::INFINITY
            },
            before,
            after,
            evaluations: evaluations + 1,
            rounds,
            basis_ms: 0.0,
            choice_ms: t.elapsed().as_secs_f64() * 1e3,
        }
    }
}

/// `system` with `designs` on `surfaces`.
pub fn assign(system: &LensSystem, surfaces: &[Coatable], designs: &[Design]) -> LensSystem {
    let mut sys = system.clone();
    for (c, d) in surfaces.iter().zip(designs) {
        sys.surfaces[c.surface].coating = d.coating(c.substrate, c.air_first);
    }
    sys
}

/// Per ghost of `basis` under `colours`: its path, energy (luminance on the frame) and, when
/// `peaks` is set, peak (luminance of its brightest pixel; 0 otherwise).
fn ghost_figures(basis: &Basis, colours: &[[f64; 3]], peaks: bool) -> Vec<(String, f64, f64)> {
    let mut c = colours.iter();
    basis
        .ghosts
        .iter()
        .map(|g| {
            let lum: Vec<f64> = g
                .bands
                .iter()
                .map(|_| luminance(*c.next().expect("one colour per band image")))
                .collect();
            let energy = g.bands.iter().zip(&lum).map(|(b, l)| b.sum * l).sum();
            if !peaks {
                return (g.path.to_string(), energy, 0.0);
            }
            // The peak of the ghost's own image: its bands summed over their boxes.
            let x0 = g.bands.iter().map(|b| b.x0).min().unwrap_or(0);
            let y0 = g.bands.iter().map(|b| b.y0).min().unwrap_or(0);
            let x1 = g.bands.iter().map(|b| b.x0 + b.w).max().unwrap_or(0);
            let y1 = g.bands.iter().map(|b| b.y0 + b.h).max().unwrap_or(0);
            let mut img = vec![0.0; (x1 - x0) * (y1 - y0)];
            for (b, l) in g.bands.iter().zip(&lum) {
                for y in 0..b.h {
                    for x in 0..b.w {
                        img[(b.y0 + y - y0) * (x1 - x0) + b.x0 + x - x0] +=
                            f64::from(b.pixels[y * b.w + x]) * l;
                    }
                }
            }
            let peak = img.iter().copied().fold(0.0, f64::max);
            (g.path.to_string(), energy, peak)
        })
        .collect()
}

//! The colour each band image of a basis takes under a lens's coatings (`crate::basis`), times
//! the light's intensity, in one of two [`Colouring`]s: by cells (over the image's bin in 5 nm
//! cells, the light's linear-sRGB weights times the path's transmission at normal incidence
//! times its two reflectances at the image's pair of hat nodes), or as the renderer colours a
//! band (`ghost_raytrace::colour`: the two reflectances at the hat nodes relative to normal
//! incidence at the bin's centre, where the band was traced, times, over the bin in 5 nm
//! cells, the light's weights and the path's throughput at normal incidence).

use flarebench_sdk::color::{SAMPLING_MAX_NM, SAMPLING_MIN_NM, SpectralSampling};
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::system::SurfaceKind;
use flarebench_sdk::{LensSystem, Surface};
use ghost_raytrace::colour::Bin;

use crate::CoatingError;
use crate::basis::Basis;

/// Cells the colours are integrated over: 5 nm over 380–780 nm, as the renderer's.
const CELLS: usize = 80;

/// A ghost path's transmission at normal incidence from per-surface factors
/// (`[T forward, R forward, T backward, R backward]`, `colour::surface_factors`): the
/// transmittances of every surface crossed from the front to the first reflection, back to
/// the second, and on to the sensor; the reflections themselves left out.
pub fn transmission(path: GhostPath, f: &[[f64; 4]], sensor: usize) -> f64 {
    let r = path.reflections();
    let mut t = 1.0;
    let mut at: Option<usize> = None;
    for (k, &s) in r.iter().enumerate() {
        t *= match at {
            None => f[..s].iter().map(|x| x[0]).product::<f64>(),
            Some(p) if k % 2 == 0 => f[p + 1..s].iter().map(|x| x[0]).product(),
            Some(p) => f[s + 1..p].iter().map(|x| x[2]).product(),
        };
        at = Some(s);
    }
    let last = at.unwrap_or(0);
    t * f[last + 1..sensor].iter().map(|x| x[0]).product::<f64>()
}

/// How a basis's band images take their colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colouring {
    /// Each reflectance at the image's hat nodes in every 5 nm cell of its bin: the physics of
    /// a band, whatever bins the renderer would trace the coatings at (the choice, which
    /// weighs coatings far from those the basis was rendered with).
    Cells,
    /// As the renderer colours a band: the reflectances at the hat nodes relative to normal
    /// incidence at the bin's centre, times the spectrum at normal incidence over the bin (the
    /// fit, which is corrected against the renderer at bases of its own coatings).
    Renderer,
}

/// One band image's recipe: its ghost, its cells with their shares of its bin, its hats.
#[derive(Clone, Debug)]
struct Recipe {
    ghost: usize,
    cells: Vec<(usize, f64)>,
    hats: (usize, usize),
    /// Its bin's centre, where its image was traced: an index into `Reweighter::centres`.
    centre: usize,
}

/// What turns coatings into the colours of a basis's band images, made once per basis.
#[derive(Clone, Debug)]
pub struct Reweighter {
    /// Each cell's light weights (linear sRGB, times the light's intensity).
    weights: Vec<[f64; 3]>,
    /// How the band images are coloured.
    colouring: Colouring,
    /// Each cell's centre and the media indices there.
    cell_points: Vec<(f64, Vec<f64>)>,
    /// The bins' centres (where the band images were traced) and the media indices there.
    centres: Vec<(f64, Vec<f64>)>,
    /// The basis's nodes' cosines.
    nodes: Vec<f64>,
    /// Per surface and direction (forward, backward): the hat nodes some image uses.
    used: Vec<[Vec<bool>; 2]>,
    paths: Vec<GhostPath>,
    recipes: Vec<Recipe>,
}

impl Reweighter {
    pub fn new(
        basis: &Basis,
        system: &LensSystem,
        colouring: Colouring,
    ) -> Result<Reweighter, CoatingError> {
        let light = &basis.light;
        let sampling = SpectralSampling::new(CELLS, light.spectrum)
            .map_err(ghost_raytrace::GhostRenderError::from)?;
        let weights = sampling
            .weights()
            .iter()
            .map(|w| w.map(|v| f64::from(v) * light.intensity))
            .collect();
        let width = (SAMPLING_MAX_NM - SAMPLING_MIN_NM) / CELLS as f64;
        let mut recipes = Vec::new();
        let mut centres: Vec<(f64, Vec<f64>)> = Vec::new();
        for (g, gb) in basis.ghosts.iter().enumerate() {
            for b in &gb.bands {
                let bin = Bin::new(system, gb.bins, b.bin);
                let centre = match centres.iter().position(|c| c.0 == bin.centre_nm) {
                    Some(i) => i,
                    None => {
                        centres.push((bin.centre_nm, system.indices(bin.centre_nm)));
                        centres.len() - 1
                    }
                };
                let cells = (0..CELLS)
                    .filter_map(|k| {
                        let lo = (SAMPLING_MIN_NM + width * k as f64).max(bin.lo_nm);
                        let hi = (SAMPLING_MIN_NM + width * (k + 1) as f64).min(bin.hi_nm);
                        let share = ((hi - lo) / width).clamp(0.0, 1.0);
                        (share > 0.0).then_some((k, share))
                    })
                    .collect();
                recipes.push(Recipe {
                    ghost: g,
                    cells,
                    hats: b.hats,
                    centre,
                });
            }
        }
        let mut used = vec![
            [
                vec![false; basis.nodes.len()],
                vec![false; basis.nodes.len()]
            ];
            system.surfaces.len()
        ];
        for r in &recipes {
            let path = basis.ghosts[r.ghost].path;
            used[path.first()][0][r.hats.0] = true;
            used[path.second()][1][r.hats.1] = true;
        }
        let cell_points = sampling
            .wavelengths_nm()
            .iter()
            .map(|&l| (l, system.indices(l)))
            .collect();
        Ok(Reweighter {
            colouring,
            cell_points,
            centres,
            nodes: basis.nodes.clone(),
            weights,
            used,
            paths: basis.ghosts.iter().map(|g| g.path).collect(),
            recipes,
        })
    }

    /// Every band image's colour under `system`'s coatings, in the basis's order.
    pub fn colours(&self, system: &LensSystem) -> Vec<[f64; 3]> {
        let terms = self.terms(system);
        let refs: Vec<&SurfaceTerms> = terms.iter().collect();
        self.colours_of(&refs, system.sensor_index())
    }

    /// Every surface's terms under `system`'s coatings.
    pub fn terms(&self, system: &LensSystem) -> Vec<SurfaceTerms> {
        system
            .surfaces
            .iter()
            .enumerate()
            .map(|(s, surface)| self.surface_terms(s, surface))
            .collect()
    }

    /// The terms of `surface`, the lens's surface `s`, under its coating: its
    /// normal-incidence factors per cell (`colour::surface_factors`, from the held indices)
    /// and, where a ghost reflects there, its reflectances per direction and hat node at each
    /// cell ([`Colouring::Cells`]) or at each bin's centre, with those at normal incidence
    /// there ([`Colouring::Renderer`]).
    pub fn surface_terms(&self, s: usize, surface: &Surface) -> SurfaceTerms {
        // The reflectance going forward or backward at incidence cosine `c`, at a wavelength
        // and its media indices (none where the surface does not reflect).
        let at = |forward: bool, c: f64, (l, n): &(f64, Vec<f64>)| {
            if surface.kind != SurfaceKind::Refracting || n[s] == n[s + 1] {
                return 0.0;
            }
            let (n1, n2) = if forward {
                (n[s], n[s + 1])
            } else {
                (n[s + 1], n[s])
            };
            surface.coating.reflectance(n1, n2, c, *l, forward)
        };
        let factors = self
            .cell_points
            .iter()
            .map(|x| {
                let (rf, rb) = (at(true, 1.0, x), at(false, 1.0, x));
                [1.0 - rf, rf, 1.0 - rb, rb]
            })
            .collect();
        // The wavelengths the reflectances at the nodes are taken at: every cell, or the bins'
        // centres.
        let points: &[(f64, Vec<f64>)] = match self.colouring {
            Colouring::Cells => &self.cell_points,
            Colouring::Renderer => &self.centres,
        };
        let refl = std::array::from_fn(|dir| {
            self.nodes
                .iter()
                .zip(&self.used[s][dir])
                .map(|(&c, &used)| {
                    if !used {
                        return Vec::new();
                    }
                    points.iter().map(|x| at(dir == 0, c, x)).collect()
                })
                .collect()
        });
        let normal = std::array::from_fn(|dir| match self.colouring {
            Colouring::Cells => Vec::new(),
            Colouring::Renderer => self.centres.iter().map(|x| at(dir == 0, 1.0, x)).collect(),
        });
        SurfaceTerms {
            factors,
            refl,
            normal,
        }
    }

    /// Every band image's colour from the surfaces' terms (one per surface, in order).
    pub fn colours_of(&self, terms: &[&SurfaceTerms], sensor: usize) -> Vec<[f64; 3]> {
        let mut f = vec![[1.0, 0.0, 1.0, 0.0]; terms.len()];
        let mut transmissions = vec![[0.0; CELLS]; self.paths.len()];
        for k in 0..CELLS {
            for (fs, t) in f.iter_mut().zip(terms) {
                *fs = t.factors[k];
            }
            for (t, &path) in transmissions.iter_mut().zip(&self.paths) {
                t[k] = transmission(path, &f, sensor);
            }
        }
        self.recipes
            .iter()
            .map(|rec| {
                let path = self.paths[rec.ghost];
                let t = &transmissions[rec.ghost];
                let (a, b) = (&terms[path.first()], &terms[path.second()]);
                let (r1, r2) = (&a.refl[0][rec.hats.0], &b.refl[1][rec.hats.1]);
                // The two reflectances in cell `k`: at the nodes there, or at normal incidence
                // there times the nodes' angle factor at the bin's centre.
                let ratio = match self.colouring {
                    Colouring::Cells => 1.0,
                    Colouring::Renderer => {
                        let at_centre = a.normal[0][rec.centre] * b.normal[1][rec.centre];
                        if at_centre.is_nan() || at_centre <= 0.0 {
                            return [0.0; 3];
                        }
                        r1[rec.centre] * r2[rec.centre] / at_centre
                    }
                };
                let reflected = |k: usize| match self.colouring {
                    Colouring::Cells => r1[k] * r2[k],
                    Colouring::Renderer => a.factors[k][1] * b.factors[k][3] * ratio,
                };
                let mut c = [0.0; 3];
                for &(k, share) in &rec.cells {
                    let v = share * t[k] * reflected(k);
                    for (ch, w) in c.iter_mut().zip(self.weights[k]) {
                        *ch += w * v;
                    }
                }
                c
            })
            .collect()
    }
}

/// One surface's part in the colours under its coating ([`Reweighter::surface_terms`]): the
/// colours of coatings that differ on one surface differ only in its terms.
#[derive(Clone, Debug)]
pub struct SurfaceTerms {
    /// `[T forward, R forward, T backward, R backward]` at normal incidence, per cell.
    factors: Vec<[f64; 4]>,
    /// Reflectance per direction (forward, backward), hat node and cell or bin centre (by the
    /// colouring); empty where no ghost of the basis reflects so.
    refl: [Vec<Vec<f64>>; 2],
    /// Reflectance at normal incidence per direction and bin centre ([`Colouring::Renderer`];
    /// empty by cells).
    normal: [Vec<f64>; 2],
}

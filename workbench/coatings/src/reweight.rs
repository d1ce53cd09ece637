//! The colour each band image of a basis takes under a lens's coatings (`crate::basis`):
//! over the image's bin, in 5 nm cells, the light's linear-sRGB weights times the path's
//! transmission at normal incidence times its two reflectances at the image's pair of hat
//! nodes, times the light's intensity.

use flarebench_sdk::LensSystem;
use flarebench_sdk::color::{SAMPLING_MAX_NM, SAMPLING_MIN_NM, SpectralSampling};
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::system::SurfaceKind;
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

/// One band image's recipe: its ghost, its cells with their shares of its bin, its hats.
#[derive(Clone, Debug)]
struct Recipe {
    ghost: usize,
    cells: Vec<(usize, f64)>,
    hats: (usize, usize),
}

/// What turns coatings into the colours of a basis's band images, made once per basis.
#[derive(Clone, Debug)]
pub struct Reweighter {
    /// Each cell's centre and the light's weights there (times its intensity).
    cells: Vec<(f64, [f64; 3])>,
    /// Each cell's media indices (coatings do not change them).
    indices: Vec<Vec<f64>>,
    /// The basis's nodes' cosines.
    nodes: Vec<f64>,
    /// Per surface and direction (forward, backward): the hat nodes some image uses.
    used: Vec<[Vec<bool>; 2]>,
    paths: Vec<GhostPath>,
    recipes: Vec<Recipe>,
}

impl Reweighter {
    pub fn new(basis: &Basis, system: &LensSystem) -> Result<Reweighter, CoatingError> {
        let light = &basis.light;
        let sampling = SpectralSampling::new(CELLS, light.spectrum)
            .map_err(ghost_raytrace::GhostRenderError::from)?;
        let cells = sampling
            .wavelengths_nm()
            .iter()
            .zip(sampling.weights())
            .map(|(&l, w)| (l, w.map(|v| f64::from(v) * light.intensity)))
            .collect();
        let width = (SAMPLING_MAX_NM - SAMPLING_MIN_NM) / CELLS as f64;
        let mut recipes = Vec::new();
        for (g, gb) in basis.ghosts.iter().enumerate() {
            for b in &gb.bands {
                let bin = Bin::new(system, gb.bins, b.bin);
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
                });
            }
        }
        let indices = sampling
            .wavelengths_nm()
            .iter()
            .map(|&l| system.indices(l))
            .collect();
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
        Ok(Reweighter {
            nodes: basis.nodes.clone(),
            cells,
            indices,
            used,
            paths: basis.ghosts.iter().map(|g| g.path).collect(),
            recipes,
        })
    }

    /// Every band image's colour under `system`'s coatings, in the basis's order.
    pub fn colours(&self, system: &LensSystem) -> Vec<[f64; 3]> {
        let sensor = system.sensor_index();
        let nodes = &self.nodes;
        let indices = &self.indices;
        // Normal-incidence factors per cell and surface (`colour::surface_factors`, from the
        // held indices).
        let factors: Vec<Vec<[f64; 4]>> = self
            .cells
            .iter()
            .zip(indices)
            .map(|(&(l, _), n)| {
                system
                    .surfaces
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        if s.kind != SurfaceKind::Refracting || n[i] == n[i + 1] {
                            return [1.0, 0.0, 1.0, 0.0];
                        }
                        let rf = s.coating.reflectance(n[i], n[i + 1], 1.0, l, true);
                        let rb = s.coating.reflectance(n[i + 1], n[i], 1.0, l, false);
                        [1.0 - rf, rf, 1.0 - rb, rb]
                    })
                    .collect()
            })
            .collect();
        // Each reflecting surface's reflectances, per direction, node and cell, once.
        let mut refl: Vec<[Option<Vec<Vec<f64>>>; 2]> = vec![[None, None]; system.surfaces.len()];
        for path in &self.paths {
            for (s, dir) in [(path.first(), 0), (path.second(), 1)] {
                if refl[s][dir].is_some() {
                    continue;
                }
                let forward = dir == 0;
                refl[s][dir] = Some(
                    nodes
                        .iter()
                        .zip(&self.used[s][dir])
                        .map(|(&c, &used)| {
                            if !used {
                                return Vec::new();
                            }
                            (0..CELLS)
                                .map(|k| {
                                    let n = &indices[k];
                                    let (n1, n2) = if forward {
                                        (n[s], n[s + 1])
                                    } else {
                                        (n[s + 1], n[s])
                                    };
                                    system.surfaces[s].coating.reflectance(
                                        n1,
                                        n2,
                                        c,
                                        self.cells[k].0,
                                        forward,
                                    )
                                })
                                .collect()
                        })
                        .collect(),
                );
            }
        }
        let transmissions: Vec<Vec<f64>> = self
            .paths
            .iter()
            .map(|&path| {
                factors
                    .iter()
                    .map(|f| transmission(path, f, sensor))
                    .collect()
            })
            .collect();
        self.recipes
            .iter()
            .map(|rec| {
                let path = self.paths[rec.ghost];
                let t = &transmissions[rec.ghost];
                let (Some(ra), Some(rb)) = (&refl[path.first()][0], &refl[path.second()][1]) else {
                    return [0.0; 3];
                };
                let (r1, r2) = (&ra[rec.hats.0], &rb[rec.hats.1]);
                let mut c = [0.0; 3];
                for &(k, share) in &rec.cells {
                    let v = share * t[k] * r1[k] * r2[k];
                    for (ch, w) in c.iter_mut().zip(self.cells[k].1) {
                        *ch += w * v;
                    }
                }
                c
            })
            .collect()
    }
}

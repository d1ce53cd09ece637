//! Precomputed ghost bounds for a lens over a range of incidence angles (`flarebench
//! precompute`), stored as JSON (format in docs/formats.md) and interpolated between angles.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::system::LensSystem;
use crate::trace::InterfaceTableSet;

use super::bounds::{self, BoundsMode, GhostBounds};
use super::enumerate::{GhostPath, enumerate_ghosts};
use super::grid::GridTrace;

/// Identifies the file format.
pub const FORMAT: &str = "flarebench-ghost-bounds";
pub const VERSION: u32 = 1;

/// Ghost bounds per ghost and angle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoundsTable {
    pub format: String,
    pub version: u32,
    /// The lens's name and a fingerprint of its prescription (FNV-1a of its canonical XML), so
    /// a table is not used with another lens.
    pub lens: String,
    pub lens_fingerprint: String,
    pub mode: BoundsMode,
    pub wavelength_nm: f64,
    /// Incidence angles (degrees), increasing from 0.
    pub angles_deg: Vec<f64>,
    pub ghosts: Vec<GhostPath>,
    /// `bounds[g][a]`: ghost `g` at angle `a`; `None` where no ray of it reaches the sensor.
    pub bounds: Vec<Vec<Option<GhostBounds>>>,
}

/// FNV-1a (64 bit) of the lens's canonical XML, as hex.
pub fn fingerprint(system: &LensSystem) -> String {
    let text = crate::io::write_xml(system);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Angles from 0 to `max_deg` in steps of at most `step_deg`.
pub fn angle_steps(max_deg: f64, step_deg: f64) -> Vec<f64> {
    let n = (max_deg / step_deg).ceil().max(1.0) as usize;
    (0..=n).map(|i| max_deg * i as f64 / n as f64).collect()
}

impl BoundsTable {
    /// Computes the bounds of every ghost at every angle; `progress` is called once per ghost
    /// finished (from worker threads).
    pub fn compute(
        system: &LensSystem,
        angles_deg: &[f64],
        mode: BoundsMode,
        wavelength_nm: f64,
        progress: &(dyn Fn() + Sync),
    ) -> BoundsTable {
        let ghosts = enumerate_ghosts(system);
        let tables = InterfaceTableSet::for_system(system, wavelength_nm);
        let direct: Vec<f64> = match mode {
            BoundsMode::Precise => angles_deg
                .par_iter()
                .map_init(GridTrace::default, |scratch, &deg| {
                    bounds::direct_flux(system, &tables, deg.to_radians(), scratch)
                })
                .collect(),
            BoundsMode::Approximate => vec![0.0; angles_deg.len()],
        };
        // Ghosts in parallel; within a ghost, angles in order, each search starting from the
        // previous angle's rectangle.
        let bounds: Vec<Vec<Option<GhostBounds>>> = ghosts
            .par_iter()
            .map_init(GridTrace::default, |scratch, &g| {
                let mut prev: Option<GhostBounds> = None;
                let seq = bounds::ghost_sequence(system, g, &tables);
                let row: Vec<Option<GhostBounds>> = angles_deg
                    .iter()
                    .zip(&direct)
                    .map(|(&deg, &direct)| {
                        let theta = deg.to_radians();
                        let b = match mode {
                            BoundsMode::Precise => seq.as_ref().and_then(|seq| {
                                let start = prev.map(|p| p.entrance);
                                bounds::precise_from(system, seq, theta, direct, start, scratch)
                            }),
                            BoundsMode::Approximate => {
                                bounds::approximate(system, g, wavelength_nm, theta)
                            }
                        };
                        prev = b;
                        b
                    })
                    .collect();
                progress();
                row
            })
            .collect();
        BoundsTable {
            format: FORMAT.to_string(),
            version: VERSION,
            lens: system.name.clone(),
            lens_fingerprint: fingerprint(system),
            mode,
            wavelength_nm,
            angles_deg: angles_deg.to_vec(),
            ghosts,
            bounds,
        }
    }

    /// Checks that the table is of this format and for this lens.
    pub fn check_for(&self, system: &LensSystem) -> Result<(), String> {
        if self.format != FORMAT || self.version != VERSION {
            return Err(format!(
                "not a {FORMAT} v{VERSION} file (format `{}`, version {})",
                self.format, self.version
            ));
        }
        if self.lens_fingerprint != fingerprint(system) {
            return Err(format!(
                "the table was computed for lens `{}` (fingerprint {}), not this prescription",
                self.lens, self.lens_fingerprint
            ));
        }
        if self.bounds.len() != self.ghosts.len()
            || self.bounds.iter().any(|b| b.len() != self.angles_deg.len())
            || !self.angles_deg.windows(2).all(|w| w[1] > w[0])
        {
            return Err("the table's ghost and angle lists do not match".into());
        }
        Ok(())
    }

    /// Bounds of ghost `g` at `theta_deg`, between tabulated angles: the union of the two
    /// neighbours' rectangles (so no part of the ghost is cut), the larger grid, and the
    /// interpolated energy. `None` beyond the table or where neither neighbour has light.
    pub fn lookup(&self, g: usize, theta_deg: f64) -> Option<GhostBounds> {
        let a = &self.angles_deg;
        if !(theta_deg >= a[0] && theta_deg <= *a.last()?) {
            return None;
        }
        let hi = a.partition_point(|&x| x < theta_deg).min(a.len() - 1);
        let lo = hi.saturating_sub(usize::from(a[hi] > theta_deg));
        let (bl, bh) = (self.bounds[g][lo], self.bounds[g][hi]);
        match (bl, bh) {
            (Some(l), Some(h)) => {
                let t = if hi > lo {
                    (theta_deg - a[lo]) / (a[hi] - a[lo])
                } else {
                    0.0
                };
                Some(GhostBounds {
                    entrance: l.entrance.union(&h.entrance),
                    sensor: l.sensor.union(&h.sensor),
                    grid: l.grid.max(h.grid),
                    mean_intensity: l.mean_intensity + t * (h.mean_intensity - l.mean_intensity),
                    energy_share: l.energy_share + t * (h.energy_share - l.energy_share),
                })
            }
            (Some(b), None) | (None, Some(b)) => Some(b),
            (None, None) => None,
        }
    }

    /// Index of `path` in the table.
    pub fn ghost_index(&self, path: GhostPath) -> Option<usize> {
        self.ghosts.iter().position(|&g| g == path)
    }
}

//! Precomputed ghost bounds for a lens over a range of incidence angles (`flarebench
//! precompute`), stored as JSON (format in docs/formats.md) and interpolated between angles.
//!
//! A table holds every two-reflection ghost and, when computed with
//! [`ReflectionOrder::Four`], the four-reflection ghosts whose traced energy bound
//! ([`FourReflectionBounds`]) reaches the table's `four_reflection_bound_threshold` at some
//! tabulated angle; the others are never traced.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::system::LensSystem;
use crate::trace::InterfaceTableSet;

use super::bounds::{self, BoundsMode, GhostBounds};
use super::enumerate::{
    GhostPath, ReflectionOrder, enumerate_four_reflection_ghosts, enumerate_ghosts,
};
use super::four_bound::FourReflectionBounds;
use super::grid::GridTrace;

/// Identifies the file format.
pub const FORMAT: &str = "flarebench-ghost-bounds";
/// The version of a table of two-reflection ghosts.
pub const VERSION: u32 = 3;
/// The version of a table computed with four-reflection ghosts: a reader of [`VERSION`]
/// tables would misread their paths, so it must refuse them.
pub const VERSION_FOUR: u32 = 4;
/// Versions 1 (two reflections) and 2 (four) measured energy shares against the direct
/// image at each angle, which vanishes where that image is vignetted away: they are refused
/// with a note to compute the table again.
const OLD_VERSIONS: [u32; 2] = [1, 2];

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
    /// Set when four-reflection ghosts were considered: those whose energy bound is below
    /// this at every tabulated angle are not in the table (version 4 files only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub four_reflection_bound_threshold: Option<f64>,
    /// How many four-reflection paths the lens has (in the table or not; version 4 only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub four_reflection_paths: Option<usize>,
}

/// Which ghosts a table covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableOptions {
    pub reflections: ReflectionOrder,
    /// Four-reflection ghosts whose energy bound stays below this at every angle are left out
    /// (the default quality's culling threshold, 1e-6, is what `precompute` uses).
    pub four_reflection_bound_threshold: f64,
}

impl Default for TableOptions {
    fn default() -> Self {
        TableOptions {
            reflections: ReflectionOrder::Two,
            four_reflection_bound_threshold: 1e-6,
        }
    }
}

pub use crate::fingerprint::fingerprint;

/// The largest angle a table covers by default (degrees): half the film diagonal's field (at
/// the d line's focal length) plus 10°, at most 89°.
pub fn default_max_angle_deg(system: &LensSystem) -> Result<f64, crate::paraxial::ParaxialError> {
    let efl = crate::paraxial::analyse(system, crate::spectrum::LAMBDA_D_NM)?
        .efl_mm
        .abs();
    let half_diag = 0.5 * system.film_width_mm.hypot(system.film_height_mm);
    Ok(((half_diag / efl).atan().to_degrees() + 10.0).min(89.0))
}

/// Angles from 0 to `max_deg` in steps of at most `step_deg`.
pub fn angle_steps(max_deg: f64, step_deg: f64) -> Vec<f64> {
    let n = (max_deg / step_deg).ceil().max(1.0) as usize;
    (0..=n).map(|i| max_deg * i as f64 / n as f64).collect()
}

impl BoundsTable {
    /// Computes the bounds of every two-reflection ghost at every angle; `progress` is called
    /// once per ghost finished (from worker threads).
    pub fn compute(
        system: &LensSystem,
        angles_deg: &[f64],
        mode: BoundsMode,
        wavelength_nm: f64,
        progress: &(dyn Fn() + Sync),
    ) -> BoundsTable {
        Self::compute_with(
            system,
            angles_deg,
            mode,
            wavelength_nm,
            &TableOptions::default(),
            &|_| {},
            progress,
        )
    }

    /// [`Self::compute`] for the ghosts `options` asks for. `start` is called once with the
    /// number of ghosts that will be computed (after the four-reflection cull), then
    /// `progress` once per ghost finished.
    pub fn compute_with(
        system: &LensSystem,
        angles_deg: &[f64],
        mode: BoundsMode,
        wavelength_nm: f64,
        options: &TableOptions,
        start: &dyn Fn(usize),
        progress: &(dyn Fn() + Sync),
    ) -> BoundsTable {
        let four = options.reflections == ReflectionOrder::Four;
        let mut ghosts = enumerate_ghosts(system);
        let tables = InterfaceTableSet::for_system(system, wavelength_nm);
        // The reference flux: for the precise energies, and for the four-reflection bound.
        let reference = if mode == BoundsMode::Precise || four {
            bounds::reference_flux(system, &tables, &mut GridTrace::default())
        } else {
            0.0
        };
        let mut four_paths = None;
        if four {
            // The cull before tracing: a path stays when its traced prefix bound reaches the
            // threshold at some tabulated angle.
            let all = enumerate_four_reflection_ghosts(system);
            let mut largest = vec![0.0f64; all.len()];
            for &deg in angles_deg {
                let at =
                    FourReflectionBounds::compute(system, &tables, deg.to_radians(), reference);
                for (l, p) in largest.iter_mut().zip(&all) {
                    // Every path of the lens has a bound; keep one that had none.
                    *l = l.max(at.get(p).unwrap_or(f64::INFINITY));
                }
            }
            four_paths = Some(all.len());
            ghosts.extend(
                all.iter()
                    .zip(&largest)
                    .filter(|&(_, &l)| l >= options.four_reflection_bound_threshold)
                    .map(|(&p, _)| p),
            );
        }
        start(ghosts.len());
        let bounds = compute_rows(
            system,
            &ghosts,
            &tables,
            reference,
            angles_deg,
            mode,
            wavelength_nm,
            None,
            progress,
        );
        BoundsTable {
            format: FORMAT.to_string(),
            version: if four { VERSION_FOUR } else { VERSION },
            lens: system.name.clone(),
            lens_fingerprint: fingerprint(system),
            mode,
            wavelength_nm,
            angles_deg: angles_deg.to_vec(),
            ghosts,
            bounds,
            four_reflection_bound_threshold: four
                .then_some(options.four_reflection_bound_threshold),
            four_reflection_paths: four_paths,
        }
    }

    /// Adds `angles_deg` (above the table's last angle, ascending) for the same ghosts, each
    /// ghost's search continuing from its rectangle at the last angle: the table is then what
    /// one [`Self::compute_with`] over all its angles would have made, bit for bit.
    pub fn extend(&mut self, system: &LensSystem, angles_deg: &[f64]) -> Result<(), String> {
        self.check_for(system)?;
        if angles_deg
            .first()
            .zip(self.angles_deg.last())
            .is_some_and(|(a, b)| a <= b)
            || !angles_deg.windows(2).all(|w| w[1] > w[0])
        {
            return Err("the angles added must ascend beyond the table's last".into());
        }
        let tables = InterfaceTableSet::for_system(system, self.wavelength_nm);
        let reference = if self.mode == BoundsMode::Precise || self.has_four_reflections() {
            bounds::reference_flux(system, &tables, &mut GridTrace::default())
        } else {
            0.0
        };
        let last: Vec<Option<GhostBounds>> = self
            .bounds
            .iter()
            .map(|row| row.last().copied().flatten())
            .collect();
        let rows = compute_rows(
            system,
            &self.ghosts,
            &tables,
            reference,
            angles_deg,
            self.mode,
            self.wavelength_nm,
            Some(&last),
            &|| {},
        );
        self.angles_deg.extend_from_slice(angles_deg);
        for (row, more) in self.bounds.iter_mut().zip(rows) {
            row.extend(more);
        }
        Ok(())
    }

    /// True when the table was computed with four-reflection ghosts (some may have been left
    /// out by the bound: see `four_reflection_bound_threshold`).
    pub fn has_four_reflections(&self) -> bool {
        self.four_reflection_bound_threshold.is_some()
    }

    /// Checks that the table is of this format and for this lens.
    pub fn check_for(&self, system: &LensSystem) -> Result<(), String> {
        let known = match self.version {
            VERSION => !self.has_four_reflections() && self.ghosts.iter().all(|g| !g.is_four()),
            VERSION_FOUR => self.has_four_reflections(),
            _ => false,
        };
        if self.format == FORMAT && OLD_VERSIONS.contains(&self.version) {
            return Err(format!(
                "a {FORMAT} v{} file, whose energy shares are relative to the direct image at \
                 each angle (this version measures them against the on-axis direct image): \
                 run `flarebench precompute` again",
                self.version
            ));
        }
        if self.format != FORMAT || !known {
            return Err(format!(
                "not a {FORMAT} v{VERSION} or v{VERSION_FOUR} file (format `{}`, version {})",
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

/// Each ghost's bounds at each angle: ghosts in parallel; within a ghost, angles in order, each
/// precise search starting from the previous angle's rectangle (from `prev[g]` at the first
/// angle, when given).
#[allow(clippy::too_many_arguments)]
fn compute_rows(
    system: &LensSystem,
    ghosts: &[GhostPath],
    tables: &InterfaceTableSet,
    reference: f64,
    angles_deg: &[f64],
    mode: BoundsMode,
    wavelength_nm: f64,
    prev: Option<&[Option<GhostBounds>]>,
    progress: &(dyn Fn() + Sync),
) -> Vec<Vec<Option<GhostBounds>>> {
    ghosts
        .par_iter()
        .enumerate()
        .map_init(GridTrace::default, |scratch, (k, &g)| {
            let mut prev: Option<GhostBounds> = prev.and_then(|p| p[k]);
            let seq = bounds::ghost_sequence(system, g, tables);
            let row: Vec<Option<GhostBounds>> = angles_deg
                .iter()
                .map(|&deg| {
                    let theta = deg.to_radians();
                    let b = match mode {
                        BoundsMode::Precise => seq.as_ref().and_then(|seq| {
                            let start = prev.map(|p| p.entrance);
                            bounds::precise_from(system, seq, theta, reference, start, scratch)
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
        .collect()
}

//! A lens as the plugin holds it: its bounds table (every two-reflection ghost's entrance
//! rectangle from 0° to the table's largest angle, traced) and its fits per set of settings,
//! each found in memory, else on disk ([`crate::cache`]), else made and stored; with the time
//! each took.

use std::path::{Path, PathBuf};
use std::sync::{Arc, PoisonError};
use std::time::Instant;

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::bounds::BoundsMode;
use flarebench_sdk::ghost::table::{BoundsTable, angle_steps, default_max_angle_deg, fingerprint};
use rayon::prelude::*;

use crate::cache::{self, FitMap, memory};
use crate::error::PolyError;
use crate::fit::{FitSettings, GhostFit};

/// Wavelength the bounds are traced at (nm), as the ray-traced renderer's.
pub const BOUNDS_LAMBDA_NM: f64 = 550.0;

/// Angle step of the bounds table (degrees): `flarebench precompute`'s largest.
pub const TABLE_STEP_DEG: f64 = 0.5;

/// Where something came from and how long it took (ms).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Memory,
    Disk,
    Made,
}

/// How a table or a set of fits was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    pub source: Source,
    pub ms: f64,
}

/// A prepared lens.
#[derive(Debug)]
pub struct LensModel {
    pub system: LensSystem,
    pub fingerprint: String,
    pub table: Arc<BoundsTable>,
    pub table_timing: Timing,
    /// The disk cache's directory (`None`: memory only).
    pub dir: Option<PathBuf>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn warn(what: &str) {
    eprintln!("warning: ghost-polynomial: {what}");
}

impl LensModel {
    /// `system` with its bounds table, from memory, `dir` or traced.
    pub fn new(system: &LensSystem, dir: Option<&Path>) -> Result<LensModel, PolyError> {
        let t = Instant::now();
        let fp = fingerprint(system);
        let max = default_max_angle_deg(system)?;
        let angles = angle_steps(max, TABLE_STEP_DEG);
        let remembered = memory()
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .tables
            .get(&fp)
            .cloned();
        let (table, source) = if let Some(table) = remembered {
            (table, Source::Memory)
        } else {
            let check = |tb: &BoundsTable| {
                tb.check_for(system)?;
                if tb.angles_deg != angles || tb.mode != BoundsMode::Precise {
                    return Err("made with other angles or bounds".to_string());
                }
                Ok(())
            };
            let read = dir.and_then(|d| match cache::read_table(d, &fp, check) {
                Ok(t) => t,
                Err(e) => {
                    warn(&format!("ignoring the cached bounds table {e}"));
                    None
                }
            });
            let (table, source) = match read {
                Some(tb) => (tb, Source::Disk),
                None => {
                    let tb = BoundsTable::compute(
                        system,
                        &angles,
                        BoundsMode::Precise,
                        BOUNDS_LAMBDA_NM,
                        &|| {},
                    );
                    if let Some(d) = dir
                        && let Err(e) = cache::write_table(d, &fp, &tb)
                    {
                        warn(&format!("could not cache the bounds table: {e}"));
                    }
                    (tb, Source::Made)
                }
            };
            let table = Arc::new(table);
            memory()
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .tables
                .insert(fp.clone(), table.clone());
            (table, source)
        };
        Ok(LensModel {
            system: system.clone(),
            fingerprint: fp,
            table,
            table_timing: Timing { source, ms: ms(t) },
            dir: dir.map(Path::to_path_buf),
        })
    }

    /// Every ghost's fit with `settings`, from memory, disk or made (in parallel over the
    /// ghosts) and stored.
    pub fn fits(&self, settings: &FitSettings) -> (Arc<FitMap>, Timing) {
        let t = Instant::now();
        let key = (self.fingerprint.clone(), *settings);
        if let Some(f) = memory()
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .fits
            .get(&key)
        {
            return (
                f.clone(),
                Timing {
                    source: Source::Memory,
                    ms: ms(t),
                },
            );
        }
        let read = self.dir.as_deref().and_then(|d| {
            match cache::read_fits(d, &self.fingerprint, settings) {
                Ok(f) => f,
                Err(e) => {
                    warn(&format!("ignoring the cached fits {e}; fitting again"));
                    None
                }
            }
        });
        let (fits, source) = match read {
            Some(f) => (f, Source::Disk),
            None => {
                let fits = self.fit_all(settings);
                if let Some(d) = &self.dir
                    && let Err(e) = cache::write_fits(d, &self.fingerprint, settings, &fits)
                {
                    warn(&format!("could not cache the fits: {e}"));
                }
                (fits, Source::Made)
            }
        };
        let map: Arc<FitMap> = Arc::new(fits.into_iter().map(|f| (f.path, f)).collect());
        memory()
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .fits
            .insert(key, map.clone());
        (map, Timing { source, ms: ms(t) })
    }

    /// Fits every ghost of the table that has light at some angle.
    pub fn fit_all(&self, settings: &FitSettings) -> Vec<GhostFit> {
        (0..self.table.ghosts.len())
            .into_par_iter()
            .filter_map(|g| GhostFit::fit(&self.system, &self.table, g, settings))
            .collect()
    }
}

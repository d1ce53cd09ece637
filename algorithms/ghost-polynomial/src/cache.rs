//! The fits and bounds tables kept between renders: in memory for the process (keyed by the
//! lens's fingerprint and the fit's settings), and on disk in one directory — by default
//! `$XDG_CACHE_HOME/flarebench/ghost-polynomial` (or `~/.cache/…`); the environment variable
//! [`CACHE_ENV`] names another, or, set empty, turns the disk cache off. Files are named by the
//! lens's fingerprint (FNV-1a of its canonical XML) and the settings, written atomically, and
//! checked when read: a file that cannot be read, is malformed or belongs to another lens or
//! version is ignored with a warning and the fit made again.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::io::write_atomically;
use serde::{Deserialize, Serialize};

use crate::fit::{FitSettings, GhostFit};

/// The environment variable naming the cache directory (empty: no disk cache).
pub const CACHE_ENV: &str = "FLAREBENCH_GHOST_POLYNOMIAL_CACHE";
/// Identifies a fits file.
pub const FORMAT: &str = "flarebench-ghost-polynomial-fits";
/// Its version: a change to the sampling, the basis or the outputs makes old files stale.
pub const VERSION: u32 = 1;

/// The disk cache's directory: [`CACHE_ENV`] if set (`None` when empty), else
/// `$XDG_CACHE_HOME/flarebench/ghost-polynomial`, else `$HOME/.cache/flarebench/ghost-polynomial`.
pub fn default_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os(CACHE_ENV) {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
    Some(base.join("flarebench").join("ghost-polynomial"))
}

/// A lens's fits made with one set of settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FitsFile {
    pub format: String,
    pub version: u32,
    pub lens_fingerprint: String,
    pub settings: FitSettings,
    pub fits: Vec<GhostFit>,
}

/// The file of `fingerprint`'s fits with `s` in `dir`.
pub fn fits_path(dir: &Path, fingerprint: &str, s: &FitSettings) -> PathBuf {
    dir.join(format!(
        "{fingerprint}.d{}-t{}-s{}-r{}.fits.json",
        s.degree, s.terms, s.samples, s.seed
    ))
}

/// The file of `fingerprint`'s bounds table in `dir`.
pub fn table_path(dir: &Path, fingerprint: &str) -> PathBuf {
    dir.join(format!("{fingerprint}.bounds.json"))
}

/// Reads the fits of `fingerprint` with `settings` from `dir`: `Ok(None)` when there is no
/// file, `Err(why)` when there is one that cannot be used.
pub fn read_fits(
    dir: &Path,
    fingerprint: &str,
    settings: &FitSettings,
) -> Result<Option<Vec<GhostFit>>, String> {
    let path = fits_path(dir, fingerprint, settings);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let file: FitsFile =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    if file.format != FORMAT || file.version != VERSION {
        return Err(format!(
            "{}: format {} version {}, expected {FORMAT} version {VERSION}",
            path.display(),
            file.format,
            file.version
        ));
    }
    if file.lens_fingerprint != fingerprint || file.settings != *settings {
        return Err(format!(
            "{}: made for another lens or settings",
            path.display()
        ));
    }
    if let Some(bad) = file.fits.iter().find(|f| !f.is_well_formed(settings)) {
        return Err(format!(
            "{}: the fit of ghost {} is malformed",
            path.display(),
            bad.path
        ));
    }
    Ok(Some(file.fits))
}

/// Writes the fits (atomically); `Err(why)` when it could not.
pub fn write_fits(
    dir: &Path,
    fingerprint: &str,
    settings: &FitSettings,
    fits: &[GhostFit],
) -> Result<(), String> {
    let file = FitsFile {
        format: FORMAT.to_string(),
        version: VERSION,
        lens_fingerprint: fingerprint.to_string(),
        settings: *settings,
        fits: fits.to_vec(),
    };
    let path = fits_path(dir, fingerprint, settings);
    let json = serde_json::to_string(&file).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(dir)
        .and_then(|()| write_atomically(&path, json.as_bytes()))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads a bounds table from `dir`: `Ok(None)` without a file, `Err(why)` for one that cannot
/// be used (unreadable, or not `check`'s).
pub fn read_table(
    dir: &Path,
    fingerprint: &str,
    check: impl Fn(&BoundsTable) -> Result<(), String>,
) -> Result<Option<BoundsTable>, String> {
    let path = table_path(dir, fingerprint);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let table: BoundsTable =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    check(&table).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Some(table))
}

/// Writes a bounds table (atomically).
pub fn write_table(dir: &Path, fingerprint: &str, table: &BoundsTable) -> Result<(), String> {
    let path = table_path(dir, fingerprint);
    let json = serde_json::to_string(table).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(dir)
        .and_then(|()| write_atomically(&path, json.as_bytes()))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// A lens's fits, by path.
pub type FitMap = HashMap<GhostPath, GhostFit>;

/// The process's fits and tables, by fingerprint (and settings).
#[derive(Debug, Default)]
pub struct Memory {
    pub tables: HashMap<String, Arc<BoundsTable>>,
    pub fits: HashMap<(String, FitSettings), Arc<FitMap>>,
}

/// The process-wide memory cache.
pub fn memory() -> &'static Mutex<Memory> {
    static MEMORY: OnceLock<Mutex<Memory>> = OnceLock::new();
    MEMORY.get_or_init(Mutex::default)
}

/// Drops `fingerprint`'s table and fits from the process's memory, so that the next look-up
/// reads the disk cache (or makes them).
pub fn forget(fingerprint: &str) {
    let mut m = memory()
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    m.tables.remove(fingerprint);
    m.fits.retain(|(fp, _), _| fp != fingerprint);
}

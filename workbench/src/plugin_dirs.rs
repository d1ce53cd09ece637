//! Finding plugin libraries: beside the `flarebench` executable, in the directories of
//! `FLAREBENCH_PLUGIN_PATH` (separated like `PATH`), and by explicit path. Every library found
//! is loaded and checked (`flarebench_sdk::abi::host::load`); one that fails is kept with its
//! reason, so `plugins list` can show it as broken.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flarebench_sdk::abi::host::{self, LoadedPlugin, PluginLoadError};

/// The environment variable with extra plugin directories.
pub const PLUGIN_PATH_VAR: &str = "FLAREBENCH_PLUGIN_PATH";

/// A library found, loaded or not.
#[derive(Debug)]
pub struct Found {
    pub path: PathBuf,
    pub plugin: Result<LoadedPlugin, PluginLoadError>,
    /// Set when another library already provides this plugin's name (the first one wins).
    pub shadowed_by: Option<PathBuf>,
}

/// The directories searched, in order: the executable's own directory, then
/// `FLAREBENCH_PLUGIN_PATH`'s.
pub fn search_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        dirs.push(dir.to_path_buf());
    }
    if let Some(p) = std::env::var_os(PLUGIN_PATH_VAR) {
        dirs.extend(std::env::split_paths(&p).filter(|d| !d.as_os_str().is_empty()));
    }
    dirs
}

/// Whether `path` is named like a shared library on this platform.
fn is_library(path: &Path) -> bool {
    path.is_file()
        && path.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
            n.starts_with(std::env::consts::DLL_PREFIX) && n.ends_with(std::env::consts::DLL_SUFFIX)
        })
}

/// Every library in the search directories plus `explicit` paths, each loaded (explicit paths
/// first, so they win over a discovered plugin of the same name).
pub fn discover(explicit: &[PathBuf]) -> Vec<Found> {
    let mut paths: Vec<PathBuf> = explicit.to_vec();
    for dir in search_dirs() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut libs: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| is_library(p))
            .collect();
        libs.sort();
        paths.extend(libs);
    }
    let mut seen = HashSet::new();
    let mut found: Vec<Found> = Vec::new();
    for path in paths {
        let key = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if !seen.insert(key) {
            continue;
        }
        let plugin = host::load(&path);
        let shadowed_by = plugin.as_ref().ok().and_then(|p| {
            found
                .iter()
                .find(|f| {
                    f.shadowed_by.is_none() && f.plugin.as_ref().is_ok_and(|q| q.name == p.name)
                })
                .map(|f| f.path.clone())
        });
        found.push(Found {
            path,
            plugin,
            shadowed_by,
        });
    }
    found
}

/// The plugin `spec` names: a path to a library (anything with a `/` or the library suffix),
/// else a plugin name among those discovered.
pub fn find(spec: &str, explicit: &[PathBuf]) -> anyhow::Result<LoadedPlugin> {
    if spec.contains(std::path::MAIN_SEPARATOR) || spec.ends_with(std::env::consts::DLL_SUFFIX) {
        return host::load(Path::new(spec)).with_context(|| format!("plugin `{spec}`"));
    }
    let found = discover(explicit);
    let mut broken = Vec::new();
    for f in found {
        match f.plugin {
            Ok(p) if p.name == spec && f.shadowed_by.is_none() => return Ok(p),
            Ok(_) => {}
            Err(e) => broken.push(e.to_string()),
        }
    }
    let dirs: Vec<String> = search_dirs()
        .iter()
        .map(|d| d.display().to_string())
        .collect();
    let mut msg = format!(
        "no plugin named `{spec}` (searched {}; set {PLUGIN_PATH_VAR} or give a path; `flarebench plugins list` shows what is there)",
        dirs.join(", ")
    );
    if !broken.is_empty() {
        msg.push_str(&format!(
            "; {} librar{} could not be loaded",
            broken.len(),
            if broken.len() == 1 { "y" } else { "ies" }
        ));
    }
    bail!(msg)
}

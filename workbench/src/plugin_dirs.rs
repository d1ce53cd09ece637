//! Finding plugin libraries: beside the `flarebench` executable, in the directories of
//! `FLAREBENCH_PLUGIN_PATH` (separated like `PATH`), and by explicit path. Every library found
//! is loaded and checked (`flarebench_sdk::abi::host::load`); one that fails is kept with its
//! reason, so `plugins list` can show it as broken.
//!
//! Test plugins — libraries named `flarebench_test_*` (`libflarebench_test_….so`), which
//! `cargo build --workspace` puts beside the binary for the host's tests — are not discovered
//! unless [`TEST_PLUGINS_VAR`] is `1`; a path given explicitly always loads. The Python
//! module's library ([`NOT_PLUGINS`]), which the same build puts there, is no plugin and is
//! never discovered.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flarebench_sdk::abi::host::{self, LoadedPlugin, PluginLoadError};

/// The environment variable with extra plugin directories.
pub const PLUGIN_PATH_VAR: &str = "FLAREBENCH_PLUGIN_PATH";
/// Set to `1` to discover test plugins ([`TEST_PLUGIN_PREFIX`]) in the search directories.
pub const TEST_PLUGINS_VAR: &str = "FLAREBENCH_TEST_PLUGINS";
/// The library name (after the platform's `lib` prefix) that marks a plugin built for the
/// host's tests.
pub const TEST_PLUGIN_PREFIX: &str = "flarebench_test_";

/// Library names (after the platform's `lib` prefix) of the workspace's shared libraries that
/// are not plugins: the Python module (`workbench/python`, `lib_flarebench.so`), which cannot
/// even be loaded outside a Python interpreter.
pub const NOT_PLUGINS: &[&str] = &["_flarebench"];

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

/// The library name of `path` without the platform's prefix and suffix, when it is named like
/// a shared library on this platform and is a file.
fn library_name(path: &Path) -> Option<&str> {
    let name = path.file_name()?.to_str()?;
    let stem = name
        .strip_prefix(std::env::consts::DLL_PREFIX)?
        .strip_suffix(std::env::consts::DLL_SUFFIX)?;
    path.is_file().then_some(stem)
}

/// Whether test plugins are discovered ([`TEST_PLUGINS_VAR`] is `1`).
fn test_plugins_wanted() -> bool {
    std::env::var_os(TEST_PLUGINS_VAR).is_some_and(|v| v == "1")
}

/// Every library in the search directories plus `explicit` paths, each loaded (explicit paths
/// first, so they win over a discovered plugin of the same name).
pub fn discover(explicit: &[PathBuf]) -> Vec<Found> {
    let mut paths: Vec<PathBuf> = explicit.to_vec();
    let tests = test_plugins_wanted();
    for dir in search_dirs() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut libs: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                library_name(p).is_some_and(|n| {
                    !NOT_PLUGINS.contains(&n) && (tests || !n.starts_with(TEST_PLUGIN_PREFIX))
                })
            })
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

/// Whether `spec` names a library by its path (it has a `/` or ends in the library suffix)
/// rather than a plugin by its name.
pub fn is_library_path(spec: &str) -> bool {
    spec.contains(std::path::MAIN_SEPARATOR) || spec.ends_with(std::env::consts::DLL_SUFFIX)
}

/// The plugin `spec` names: a path to a library (see [`is_library_path`]), else a plugin name
/// among those discovered.
pub fn find(spec: &str, explicit: &[PathBuf]) -> anyhow::Result<LoadedPlugin> {
    if is_library_path(spec) {
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

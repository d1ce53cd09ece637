//! An `--algo NAME[:key=value,…]` argument resolved to its plugin, and a rebuilt plugin library
//! loaded again for the arguments that use it: shared by `compare` (and `compare --watch`) and
//! the viewer window (`view --algo`, `edit --window --algo`).
//!
//! A rebuilt library is loaded as a fresh copy (`host::load_fresh_copy`) beside the one in use,
//! which stays loaded: libraries are never unloaded, because code or static data of the old one
//! may still be referenced (an instance being dropped, a string it handed out), and unloading a
//! library whose initialisers ran is never safe. Each reload costs the memory of one more copy
//! of the library's code — a few MB per rebuild of a debug build — for the life of the process.
//! A library that fails to load (not a plugin, another ABI, an invalid header, a parameter an
//! argument names that it no longer has, another plugin's name where one was named) is refused
//! and the caller keeps the previous version.

use std::path::{Path, PathBuf};

use flarebench_sdk::abi::host::{self, LoadedPlugin};
use flarebench_sdk::abi::params::parse_values;

use crate::file_watch::WatchedFile;
use crate::plugin_dirs::{self, is_library_path};
use crate::sweep::points::split_algo as split_spec;

/// An `--algo` argument and the plugin it names.
#[derive(Debug)]
pub struct Algo {
    /// As given to `--algo`.
    pub spec: String,
    /// The plugin in use (loaded at the start or by the last good reload), or why none is.
    pub plugin: Result<LoadedPlugin, String>,
    /// The library file to watch: the plugin's, or the path the spec names.
    pub library: Option<PathBuf>,
    /// When watched: the library's version when it was loaded (taken before the load for a
    /// path, just after discovery for a name), so a rebuild during the first render is not
    /// missed.
    pub watched: Option<WatchedFile>,
}

impl Algo {
    /// Resolves `spec` (a plugin name or a library path, with parameters) to its plugin, among
    /// the discovered plugins and the `explicit` libraries (`--plugin`). When `watch`, a library
    /// given by path is loaded as a fresh copy from the start, so the file watched is never the
    /// one mapped into the process (a tool that rewrites a loaded library in place, rather than
    /// replacing it as cargo does, would change code under it).
    pub fn resolve(spec: &str, explicit: &[PathBuf], watch: bool) -> Algo {
        let (name, _) = split_spec(spec);
        let by_path = is_library_path(name);
        let mut watched = (watch && by_path).then(|| WatchedFile::new(Path::new(name)));
        let plugin = if watch && by_path {
            host::load_fresh_copy(Path::new(name)).map_err(|e| format!("plugin `{name}`: {e}"))
        } else {
            plugin_dirs::find(name, explicit).map_err(|e| format!("{e:#}"))
        };
        let library = match &plugin {
            Ok(p) => Some(p.path.clone()),
            Err(_) if by_path => Some(PathBuf::from(name)),
            Err(_) => None,
        };
        if watch && watched.is_none() {
            watched = library.as_deref().map(WatchedFile::new);
        }
        Algo {
            spec: spec.to_string(),
            plugin,
            library,
            watched,
        }
    }

    /// The plugin name (or library path) and the parameter text of the spec.
    pub fn split(&self) -> (&str, &str) {
        split_spec(&self.spec)
    }
}

/// Checks that `plugin` can stand for every spec in `specs` (each naming the library it came
/// from): the plugin a spec names by name, and the spec's parameters.
pub fn accepts<'a>(
    plugin: &LoadedPlugin,
    specs: impl IntoIterator<Item = &'a str>,
) -> Result<(), String> {
    for spec in specs {
        let (name, params) = split_spec(spec);
        if !is_library_path(name) && plugin.name != name {
            return Err(format!(
                "it now holds the plugin `{}`, not `{name}` (--algo {spec})",
                plugin.name
            ));
        }
        parse_values(&plugin.params, params).map_err(|e| format!("--algo {spec}: {e}"))?;
    }
    Ok(())
}

/// Loads a fresh copy of the library at `path` and checks it against `specs`, the arguments
/// that use it ([`accepts`]); the plugin, or why it is refused (the caller then keeps the
/// previous one).
pub fn load_for<'a>(
    path: &Path,
    specs: impl IntoIterator<Item = &'a str>,
) -> Result<LoadedPlugin, String> {
    let plugin = host::load_fresh_copy(path).map_err(|e| e.to_string())?;
    accepts(&plugin, specs)?;
    Ok(plugin)
}

/// Loads a fresh copy of the library at `path` for every algorithm that uses it, once all of
/// them accept it, else changes nothing. The plugin's name and parameter defaults, or why it
/// was refused.
pub fn reload(path: &Path, algos: &mut [Algo]) -> Result<(String, Vec<(String, String)>), String> {
    let specs: Vec<&str> = algos
        .iter()
        .filter(|a| a.library.as_deref() == Some(path))
        .map(|a| a.spec.as_str())
        .collect();
    let plugin = load_for(path, specs)?;
    for algo in algos
        .iter_mut()
        .filter(|a| a.library.as_deref() == Some(path))
    {
        algo.plugin = Ok(plugin.clone());
    }
    Ok((plugin.name.clone(), defaults(&plugin)))
}

/// The plugin's parameters with their defaults, as text.
pub fn defaults(plugin: &LoadedPlugin) -> Vec<(String, String)> {
    plugin
        .params
        .iter()
        .map(|p| (p.name.clone(), p.format_value(p.default)))
        .collect()
}

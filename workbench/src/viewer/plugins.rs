//! The viewer's ghost plugins (`view --algo`, `edit --window --algo`): each argument's plugin
//! with its parameter values and reload count, and the thread that watches their libraries,
//! loading a rebuilt one as a fresh copy beside the old (`crate::algo_spec`, as
//! `compare --watch` does) and handing it to the viewer.
//!
//! A loaded plugin's descriptor is kept for the life of the process (`Box::leak`), as its
//! library is: the render thread's instance borrows it from job to job, and a job may still be
//! rendering with a plugin after a reload has replaced it. One descriptor (a few hundred bytes)
//! per load, beside the copy of the library's code that stays mapped anyway.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::Context;
use flarebench_sdk::abi::host::LoadedPlugin;
use flarebench_sdk::abi::params::parse_values;

use super::flare_worker::PluginJob;
use crate::algo_spec::{self, Algo};
use crate::file_watch::{POLL_INTERVAL, WatchedFile};

/// Called (from the watch thread) after every event sent, to wake the window's event loop.
pub type SharedWaker = Arc<dyn Fn() + Send + Sync>;

/// One `--algo` argument in the viewer.
#[derive(Debug)]
pub struct ViewerAlgo {
    /// As given to `--algo`.
    pub spec: String,
    /// The plugin in use: as loaded at the start, or by the last good reload.
    pub plugin: &'static LoadedPlugin,
    /// Its parameter values (the spec's, defaults for the rest).
    pub values: Vec<f64>,
    /// The library file watched.
    pub library: PathBuf,
    /// Good reloads of the library so far.
    pub reloads: u32,
    /// Why the last reload failed, until a good one.
    pub reload_error: Option<String>,
}

/// Keeps `plugin` for the life of the process (module docs).
fn keep(plugin: LoadedPlugin) -> &'static LoadedPlugin {
    Box::leak(Box::new(plugin))
}

impl ViewerAlgo {
    /// The viewer's side of a resolved `--algo`: its plugin must have loaded and take the
    /// spec's parameters.
    pub fn new(algo: &Algo) -> anyhow::Result<ViewerAlgo> {
        let plugin = algo.plugin.as_ref().map_err(|e| anyhow::anyhow!("{e}"))?;
        let (_, params) = algo.split();
        let values = parse_values(&plugin.params, params)
            .with_context(|| format!("--algo {}", algo.spec))?;
        Ok(ViewerAlgo {
            spec: algo.spec.clone(),
            plugin: keep(plugin.clone()),
            values,
            library: algo.library.clone().unwrap_or_else(|| plugin.path.clone()),
            reloads: 0,
            reload_error: None,
        })
    }

    /// The render job's part for this plugin.
    pub fn job(&self) -> PluginJob {
        PluginJob {
            plugin: self.plugin,
            values: self.values.clone(),
            spec: self.spec.clone(),
            reloads: self.reloads,
        }
    }

    /// Takes a reloaded plugin (already checked against this spec by `algo_spec::load_for`).
    pub fn take(&mut self, plugin: &'static LoadedPlugin) -> Result<(), String> {
        let (_, params) = crate::sweep::points::split_algo(&self.spec);
        self.values = parse_values(&plugin.params, params)
            .map_err(|e| format!("--algo {}: {e}", self.spec))?;
        self.plugin = plugin;
        self.reloads += 1;
        self.reload_error = None;
        Ok(())
    }
}

/// What the watch thread found.
#[derive(Debug)]
pub enum WatchEvent {
    /// `library` changed and its fresh copy was loaded and accepted by every spec using it.
    Reloaded {
        library: PathBuf,
        plugin: &'static LoadedPlugin,
        /// When the change was noticed (for the reload's latency).
        noticed: Instant,
    },
    /// `library` changed but could not be loaded or was refused: the previous one stays.
    Failed { library: PathBuf, error: String },
}

/// The thread polling the plugins' libraries (`crate::file_watch`); stopped when dropped.
pub struct PluginWatcher {
    events: Receiver<WatchEvent>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for PluginWatcher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PluginWatcher").finish_non_exhaustive()
    }
}

impl PluginWatcher {
    /// Watches each library (with the specs that use it) every `POLL_INTERVAL`.
    pub fn start(libraries: Vec<(WatchedFile, Vec<String>)>, waker: SharedWaker) -> PluginWatcher {
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, events) = channel();
        let s = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("plugin-watch".into())
            .spawn(move || {
                let mut libraries = libraries;
                while !s.load(Ordering::Relaxed) {
                    std::thread::sleep(POLL_INTERVAL);
                    for (file, specs) in &mut libraries {
                        if !file.poll() {
                            continue;
                        }
                        let noticed = Instant::now();
                        let library = file.path().to_path_buf();
                        let event =
                            match algo_spec::load_for(&library, specs.iter().map(String::as_str)) {
                                Ok(p) => WatchEvent::Reloaded {
                                    library,
                                    plugin: keep(p),
                                    noticed,
                                },
                                Err(error) => WatchEvent::Failed { library, error },
                            };
                        if tx.send(event).is_err() {
                            return;
                        }
                        waker();
                    }
                }
            })
            .expect("spawning the plugin watch thread");
        PluginWatcher {
            events,
            stop,
            thread: Some(thread),
        }
    }

    /// The events that have arrived, oldest first, without waiting.
    pub fn poll(&self) -> Vec<WatchEvent> {
        self.events.try_iter().collect()
    }
}

impl Drop for PluginWatcher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The viewer's plugins and their watch from resolved `--algo`s: each must have loaded with its
/// parameters; one watch per library (several specs may share one).
pub fn from_algos(
    algos: Vec<Algo>,
    waker: SharedWaker,
) -> anyhow::Result<(Vec<ViewerAlgo>, Option<PluginWatcher>)> {
    let mut viewer_algos = Vec::new();
    let mut libraries: Vec<(WatchedFile, Vec<String>)> = Vec::new();
    for mut algo in algos {
        let v = ViewerAlgo::new(&algo)?;
        match libraries.iter_mut().find(|(w, _)| w.path() == v.library) {
            Some((_, specs)) => specs.push(v.spec.clone()),
            None => {
                let w = algo
                    .watched
                    .take()
                    .unwrap_or_else(|| WatchedFile::new(&v.library));
                libraries.push((w, vec![v.spec.clone()]));
            }
        }
        viewer_algos.push(v);
    }
    let watcher = (!libraries.is_empty()).then(|| PluginWatcher::start(libraries, waker));
    Ok((viewer_algos, watcher))
}

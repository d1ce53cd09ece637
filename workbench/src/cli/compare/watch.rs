//! `compare --watch`, the plugin author's loop: after the first comparison, the plugins'
//! library files and the lens file are watched (`crate::file_watch`); when one has been
//! rebuilt or saved it is loaded again and the comparison runs and prints again.
//!
//! A rebuilt library is loaded as a fresh copy beside the one in use, which stays loaded
//! (`crate::algo_spec::reload`, shared with the viewer window); a library that fails to load
//! leaves the previous version in use, with the error shown; a lens file that fails to load
//! leaves the previous lens.

use serde::Serialize;

use super::{Algo, CompareArgs, CompareReport, Setup, compare, text};
use crate::algo_spec::reload;
use crate::file_watch::{POLL_INTERVAL, WatchedFile};
use crate::flare::GhostBackend;

/// What the loop prints: as text, or with `--json` as one JSON object per line.
#[derive(Debug, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
enum Event<'a> {
    /// A changed file was loaded; `what` is `plugin` or `lens`, `name` the plugin's or lens's;
    /// for a plugin, `defaults` are its parameters' defaults as text.
    Reloaded {
        file: String,
        what: &'static str,
        name: String,
        #[serde(skip_serializing_if = "Vec::is_empty")]
        defaults: Vec<(String, String)>,
    },
    /// A changed file could not be loaded: the previous version stays in use.
    ReloadFailed {
        file: String,
        what: &'static str,
        error: String,
    },
    /// A comparison: the first, and one after each successful reload.
    Compared(&'a CompareReport),
}

fn print(event: &Event<'_>, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(event)?);
        return Ok(());
    }
    match event {
        Event::Reloaded {
            file,
            what,
            name,
            defaults,
        } => {
            println!("\nreloaded {what} `{name}` from {file}");
            if !defaults.is_empty() {
                let d: Vec<String> = defaults.iter().map(|(k, v)| format!("{k}={v}")).collect();
                println!("defaults: {}", d.join(", "));
            }
        }
        Event::ReloadFailed { file, what, error } => {
            println!("\ncould not reload {file}; the previous {what} stays in use: {error}");
        }
        Event::Compared(report) => print!("{}", text(report)),
    }
    Ok(())
}

/// Prints `first`, then watches and compares again on every change until Ctrl-C (or
/// `--watch-events` changes).
pub(super) fn watch(
    args: &CompareArgs,
    mut setup: Setup,
    mut lens: WatchedFile,
    mut algos: Vec<Algo>,
    mut backend: GhostBackend,
    first: &CompareReport,
    quiet: bool,
) -> anyhow::Result<()> {
    print(&Event::Compared(first), args.json)?;
    // One watch per library (several `--algo`s may name the same), the first one's.
    let mut libraries: Vec<WatchedFile> = Vec::new();
    for w in algos.iter_mut().filter_map(|a| a.watched.take()) {
        if !libraries.iter().any(|l| l.path() == w.path()) {
            libraries.push(w);
        }
    }
    if !quiet && !args.json {
        eprintln!(
            "watching {} plugin librar{} and the lens file; Ctrl-C ends",
            libraries.len(),
            if libraries.len() == 1 { "y" } else { "ies" }
        );
    }
    let mut events = 0;
    while args.watch_events.is_none_or(|n| events < n) {
        std::thread::sleep(POLL_INTERVAL);
        let mut changed = false;
        for lib in &mut libraries {
            if !lib.poll() {
                continue;
            }
            events += 1;
            let file = lib.path().display().to_string();
            let event = match reload(lib.path(), &mut algos) {
                Ok((name, defaults)) => {
                    changed = true;
                    Event::Reloaded {
                        file,
                        what: "plugin",
                        name,
                        defaults,
                    }
                }
                Err(error) => Event::ReloadFailed {
                    file,
                    what: "plugin",
                    error,
                },
            };
            print(&event, args.json)?;
        }
        if lens.poll() {
            events += 1;
            let file = lens.path().display().to_string();
            let event = match Setup::new(args, quiet) {
                Ok(s) => {
                    setup = s;
                    changed = true;
                    Event::Reloaded {
                        file,
                        what: "lens",
                        name: setup.sys.name.clone(),
                        defaults: Vec::new(),
                    }
                }
                Err(e) => Event::ReloadFailed {
                    file,
                    what: "lens",
                    error: format!("{e:#}"),
                },
            };
            print(&event, args.json)?;
        }
        if changed {
            let report = compare(args, &setup, &algos, &mut backend, quiet)?;
            print(&Event::Compared(&report), args.json)?;
        }
    }
    Ok(())
}

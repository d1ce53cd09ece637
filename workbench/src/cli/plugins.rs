//! `flarebench plugins list`: every plugin library found (beside the binary, in
//! `FLAREBENCH_PLUGIN_PATH`, or given with `--plugin`), with its kind, ABI version and
//! parameters — and every broken one with the reason. `plugins new` is in [`new`].

mod new;

use std::path::PathBuf;

use clap::{Args, Subcommand};
use flarebench_sdk::abi::params::ParamInfo;
use serde::Serialize;

use crate::plugin_dirs::{self, Found};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct PluginsArgs {
    #[command(subcommand)]
    pub command: PluginsCommand,
}

#[derive(Debug, Subcommand)]
pub enum PluginsCommand {
    /// List the plugins found and their parameters; broken ones with the reason.
    List(ListArgs),
    /// Write a new plugin crate made from the plugin guide's example (docs/plugins.md), ready
    /// to build and load.
    New(new::NewArgs),
}

#[derive(Debug, Args)]
pub struct ListArgs {
    /// Also load this plugin library (repeatable).
    #[arg(long = "plugin")]
    pub plugins: Vec<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// One line of the listing (`--json`).
#[derive(Debug, Serialize)]
pub struct PluginEntry {
    pub path: String,
    /// `ok`, `broken` or `shadowed` (another library has the same name).
    pub status: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub abi: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub version: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sdk_version: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rustc_version: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub params: Vec<ParamInfo>,
}

fn entry(f: &Found) -> PluginEntry {
    let path = f.path.display().to_string();
    match &f.plugin {
        Err(e) => PluginEntry {
            path,
            status: "broken",
            reason: Some(e.to_string()),
            name: None,
            kind: None,
            abi: None,
            version: None,
            description: None,
            sdk_version: None,
            rustc_version: None,
            params: Vec::new(),
        },
        Ok(p) => PluginEntry {
            path,
            status: if f.shadowed_by.is_some() {
                "shadowed"
            } else {
                "ok"
            },
            reason: f
                .shadowed_by
                .as_ref()
                .map(|o| format!("`{}` is already provided by {}", p.name, o.display())),
            name: Some(p.name.clone()),
            kind: Some(p.kind.name()),
            abi: Some(format!("{}.{}", p.abi_major, p.abi_minor)),
            version: Some(p.version.clone()),
            description: Some(p.description.clone()),
            sdk_version: Some(p.sdk_version.clone()),
            rustc_version: Some(p.rustc_version.clone()),
            params: p.params.clone(),
        },
    }
}

pub fn run(args: &PluginsArgs, quiet: bool) -> anyhow::Result<()> {
    match &args.command {
        PluginsCommand::List(a) => list(a),
        PluginsCommand::New(a) => new::run(a, quiet),
    }
}

fn list(args: &ListArgs) -> anyhow::Result<()> {
    let found = plugin_dirs::discover(&args.plugins);
    let entries: Vec<PluginEntry> = found.iter().map(entry).collect();
    if args.json {
        let dirs: Vec<String> = plugin_dirs::search_dirs()
            .iter()
            .map(|d| d.display().to_string())
            .collect();
        let v = serde_json::json!({ "search_dirs": dirs, "plugins": entries });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    if entries.is_empty() {
        println!(
            "no plugin libraries found (searched the executable's directory and {})",
            plugin_dirs::PLUGIN_PATH_VAR
        );
        return Ok(());
    }
    let mut t = Table::new(&["name", "kind", "abi", "version", "status", "path"]);
    for e in &entries {
        t.row(vec![
            e.name.clone().unwrap_or_else(|| "-".into()),
            e.kind.unwrap_or("-").to_string(),
            e.abi.clone().unwrap_or_else(|| "-".into()),
            e.version.clone().unwrap_or_else(|| "-".into()),
            e.status.to_string(),
            e.path.clone(),
        ]);
    }
    print!("{}", t.render());
    for e in &entries {
        match (&e.name, &e.reason) {
            (Some(name), reason) => {
                println!();
                println!("{name}: {}", e.description.as_deref().unwrap_or(""));
                if let Some(r) = reason {
                    println!("  ({r})");
                }
                // Names in a column as wide as the longest (at least 12).
                let w = e
                    .params
                    .iter()
                    .map(|p| p.name.len())
                    .max()
                    .unwrap_or(0)
                    .max(12);
                for p in &e.params {
                    println!(
                        "  {:<w$} {:<28} default {:<8} {}",
                        p.name,
                        p.describe_type(),
                        p.format_value(p.default),
                        p.help
                    );
                }
            }
            (None, Some(reason)) => {
                println!();
                println!("broken: {reason}");
            }
            (None, None) => {}
        }
    }
    Ok(())
}

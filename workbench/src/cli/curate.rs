//! `flarebench curate` (hidden, for maintainers): rebuilds the bundled library's FlareSim
//! lenses from the selection list, checking each (`crate::curation`); a lens that fails a
//! check of its focal length or renders is not written, and the command exits 1. The quick
//! stability suite's result, pass or the findings outside their limits, goes into the notes.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use flarebench_sdk::io::save_xml;
use rayon::prelude::*;

use std::path::Path;

use crate::curation::{self, Curated};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct CurateArgs {
    /// The selection list (default: lenses/sources/flaresim-selection.txt of the source tree).
    #[arg(long, value_name = "FILE")]
    pub selection: Option<PathBuf>,
    /// FlareSim's lens_files/ (default: tests/data/flaresim-lenses/lens_files of the source
    /// tree).
    #[arg(long, value_name = "DIR")]
    pub corpus: Option<PathBuf>,
    /// Where the maker folders are written (default: the source tree's lenses/).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Only these lenses (names or maker/name of the list).
    #[arg(long, value_name = "NAME")]
    pub only: Vec<String>,
    /// Leave out the quick stability suite (about 9 s of CPU per lens); the notes then say it
    /// was not run.
    #[arg(long)]
    pub no_stability: bool,
    /// Leave alone the lenses whose file already exists in the output (to resume a run).
    #[arg(long)]
    pub keep_existing: bool,
}

pub fn run(args: &CurateArgs, quiet: bool) -> anyhow::Result<()> {
    let selection = args
        .selection
        .clone()
        .unwrap_or_else(curation::selection_path);
    let corpus = args.corpus.clone().unwrap_or_else(curation::corpus_dir);
    let out = args.out.clone().unwrap_or_else(curation::lenses_dir);
    let mut entries = curation::read_selection(&selection)?;
    if !args.only.is_empty() {
        entries.retain(|e| {
            args.only
                .iter()
                .any(|o| *o == e.name || *o == e.qualified())
        });
        anyhow::ensure!(
            !entries.is_empty(),
            "no lens of the list is named {:?}",
            args.only
        );
    }
    if args.keep_existing {
        entries.retain(|e| !out.join(format!("{}.xml", e.qualified())).is_file());
    }
    let start = std::time::Instant::now();
    // Each lens is written as soon as it passes, and reported on stderr, so that an
    // interrupted run keeps what it did.
    let rows: Vec<(bool, Vec<String>)> = entries
        .par_iter()
        .map(|e| {
            let row = match curation::curate(e, &corpus, !args.no_stability)
                .and_then(|c| write(&c, &out).map(|ok| (c, ok)))
            {
                Ok((c, ok)) => (ok, row(&c)),
                Err(err) => (
                    false,
                    vec![
                        e.qualified(),
                        "-".into(),
                        "-".into(),
                        "-".into(),
                        "-".into(),
                        "-".into(),
                        "-".into(),
                        format!("FAIL: {err:#}"),
                    ],
                ),
            };
            if !quiet {
                eprintln!("{}", row.1.join("  "));
            }
            row
        })
        .collect();
    let mut t = Table::new(&[
        "lens",
        "EFL mm",
        "stated",
        "Δ%",
        "edge°",
        "ghosts",
        "stability",
        "result",
    ]);
    let mut failed = Vec::new();
    for (ok, cells) in rows {
        if !ok {
            failed.push(cells[0].clone());
        }
        t.row(cells);
    }
    let written = entries.len() - failed.len();
    print!("{}", t.render());
    println!(
        "{} lenses checked in {:.0} s, {} written to {}, {} failed",
        entries.len(),
        start.elapsed().as_secs_f64(),
        written,
        out.display(),
        failed.len()
    );
    if !failed.is_empty() {
        bail!(
            "{} lenses failed their checks and were not written: {}",
            failed.len(),
            failed.join(", ")
        );
    }
    Ok(())
}

/// Writes `c` to `out/<folder>/<name>.xml` when it passes its checks; `Ok(false)` when it
/// does not (nothing is written).
fn write(c: &Curated, out: &Path) -> anyhow::Result<bool> {
    if !c.checks.failures().is_empty() {
        return Ok(false);
    }
    let dir = out.join(&c.entry.folder);
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("could not create `{}`", dir.display()))?;
    let path = dir.join(format!("{}.xml", c.entry.name));
    save_xml(&c.system, &path).with_context(|| format!("could not write `{}`", path.display()))?;
    Ok(true)
}

/// The lens's row of the table.
fn row(c: &Curated) -> Vec<String> {
    let failures = c.checks.failures();
    vec![
        c.entry.qualified(),
        format!("{:.2}", c.checks.efl_mm),
        c.checks.stated_mm.map_or("-".into(), |s| s.to_string()),
        c.checks
            .efl_deviation()
            .map_or("-".into(), |d| format!("{:+.3}", 100.0 * d)),
        format!("{:.1}", c.checks.edge_deg),
        c.checks
            .renders
            .iter()
            .map(|r| r.ghosts.to_string())
            .collect::<Vec<_>>()
            .join("/"),
        c.checks.stability.as_ref().map_or("-".into(), |s| {
            format!("{}/{}", s.failures.len(), s.findings)
        }),
        if failures.is_empty() && c.checks.stability_failures().is_empty() {
            "ok".into()
        } else if failures.is_empty() {
            format!(
                "ok; stability: {}",
                c.checks.stability_failures().join("; ")
            )
        } else {
            format!("FAIL: {}", failures.join("; "))
        },
    ]
}

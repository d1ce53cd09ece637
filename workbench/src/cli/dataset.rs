//! `flarebench dataset`: render samples `0..count` (or a range, or a shard of it) of a seeded
//! dataset into a directory, skipping those already done; `dataset verify DIR` checks it,
//! `dataset merge DIR` rebuilds its manifest. The work is in `crate::dataset`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::dataset::manifest::{self, DatasetInfo};
use crate::dataset::{Sampler, render_sample, verify};
use crate::sequence::{FrameRange, Shard};

#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct DatasetArgs {
    #[command(subcommand)]
    pub action: Option<DatasetAction>,
    /// Samples in the dataset: indices 0..N−1.
    #[arg(long, required = true)]
    pub count: Option<u64>,
    /// The dataset's seed: sample i is a function of (seed, i) and the sampler alone.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The sampler (TOML; docs/datasets.md § The sampler); default: every field's default.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// The dataset's directory (created; a run into one holding the same dataset resumes it).
    #[arg(short, long, value_name = "DIR", required = true)]
    pub output: Option<PathBuf>,
    /// Render only samples A..B (both included).
    #[arg(long, value_name = "A..B", value_parser = parse_range)]
    pub range: Option<FrameRange>,
    /// Render only this share of the samples (of --range, else of all): those with
    /// (i − A) % N == I.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse)]
    pub shard: Option<Shard>,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

#[derive(Debug, Subcommand)]
pub enum DatasetAction {
    /// Check that the manifest lists every sample of the dataset and every file matches its
    /// SHA-256; exits 1 with the list of what is wrong otherwise.
    Verify {
        dir: PathBuf,
        /// Print the findings as one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Rebuild DIR/manifest.jsonl from the samples' records (after shards ran in parallel).
    Merge { dir: PathBuf },
}

/// `A..B` (both included) or one index `A`.
fn parse_range(s: &str) -> Result<FrameRange, String> {
    FrameRange::parse(s).map_err(|_| {
        format!("--range `{s}` is not A..B with A ≤ B (both included) or one sample index A")
    })
}

pub fn run(args: &DatasetArgs, quiet: bool) -> anyhow::Result<()> {
    match &args.action {
        Some(DatasetAction::Verify { dir, json }) => return run_verify(dir, *json),
        Some(DatasetAction::Merge { dir }) => {
            let n = manifest::merge(dir)?;
            println!("{}: manifest.jsonl lists {n} samples", dir.display());
            return Ok(());
        }
        None => {}
    }
    let count = args.count.expect("clap requires --count");
    let dir = args.output.as_ref().expect("clap requires --output");
    if count == 0 {
        bail!("--count must be at least 1");
    }
    let sampler = match &args.config {
        Some(p) => Sampler::from_file(p)?,
        None => Sampler::with_defaults()?,
    };
    let range = args.range.unwrap_or(FrameRange {
        first: 0,
        last: count - 1,
    });
    if range.last >= count {
        bail!(
            "--range {}..{} reaches beyond the dataset's {count} samples (0..{})",
            range.first,
            range.last,
            count - 1
        );
    }
    let shard = args.shard.unwrap_or(Shard::ALL);
    let info = DatasetInfo {
        format: manifest::DATASET_FORMAT.into(),
        seed: args.seed,
        count,
        lenses: sampler
            .lenses()
            .iter()
            .map(|l| (l.name.clone(), l.weight))
            .collect(),
        sampler: sampler.config().clone(),
    };
    manifest::prepare(dir, &info)?;
    let own: Vec<u64> = shard.frames(range).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("could not start the worker threads")?;
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(own.len() as u64).with_style(
            ProgressStyle::with_template(
                "{msg} [{bar:30}] {pos}/{len} samples, {elapsed} (eta {eta})",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
    };
    bar.set_message("dataset");
    let t = Instant::now();
    let seed = args.seed;
    // Per sample: Ok(true) rendered, Ok(false) done already.
    let results: Vec<(u64, anyhow::Result<bool>)> = pool.install(|| {
        own.par_iter()
            .map(|&i| {
                let r = if manifest::done(dir, i).is_some() {
                    Ok(false)
                } else {
                    sampler
                        .sample(seed, i)
                        .and_then(|spec| render_sample(&spec))
                        .and_then(|out| manifest::write_sample(dir, i, &out))
                        .map(|_| true)
                        .with_context(|| format!("sample {i}"))
                };
                bar.inc(1);
                (i, r)
            })
            .collect()
    });
    bar.finish_and_clear();
    let seconds = t.elapsed().as_secs_f64();
    let mut rendered = 0;
    let mut skipped = 0;
    let mut first_error = None;
    for (_, r) in results {
        match r {
            Ok(true) => rendered += 1,
            Ok(false) => skipped += 1,
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    let listed = manifest::merge(dir)?;
    if let Some(e) = first_error {
        return Err(e);
    }
    let shard_text = if shard.count > 1 {
        format!(", shard {}/{}", shard.index, shard.count)
    } else {
        String::new()
    };
    println!(
        "{}: samples {}..{}{shard_text}: {rendered} rendered, {skipped} done already, in {seconds:.2} s, \
         {:.2} samples/s; the manifest lists {listed} of {count}",
        dir.display(),
        range.first,
        range.last,
        rendered as f64 / seconds,
    );
    Ok(())
}

fn run_verify(dir: &std::path::Path, json: bool) -> anyhow::Result<()> {
    let report = verify(dir)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        for i in &report.missing {
            println!("missing: sample {i}");
        }
        for l in &report.bad_lines {
            println!("manifest.jsonl {l}");
        }
        for f in &report.bad_files {
            println!("{f}");
        }
    }
    if report.ok() {
        if !json {
            println!(
                "{}: {} samples, every file matches the manifest",
                dir.display(),
                report.count
            );
        }
        Ok(())
    } else {
        bail!(
            "{}: {} of {} samples missing from the manifest, {} bad manifest lines, {} bad files",
            dir.display(),
            report.missing.len(),
            report.count,
            report.bad_lines.len(),
            report.bad_files.len()
        )
    }
}

//! `flarebench dataset verify DIR`: the manifest lists every sample of `0..count` once, and
//! every file it lists is there with its SHA-256.

use std::path::Path;

use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use super::manifest::{Record, check_file, read_info};

/// What `verify` found.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VerifyReport {
    /// Samples the dataset has (`dataset.json`).
    pub count: u64,
    /// Samples the manifest lists.
    pub listed: usize,
    /// Samples of `0..count` the manifest lacks.
    pub missing: Vec<u64>,
    /// Lines of the manifest that are not records, or list a sample twice or beyond the
    /// count: `line N: why`.
    pub bad_lines: Vec<String>,
    /// Files that are missing or whose hash differs: `path: why`.
    pub bad_files: Vec<String>,
}

impl VerifyReport {
    /// True when the dataset is complete and intact.
    pub fn ok(&self) -> bool {
        self.missing.is_empty() && self.bad_lines.is_empty() && self.bad_files.is_empty()
    }
}

/// Checks the dataset in `dir`.
pub fn verify(dir: &Path) -> anyhow::Result<VerifyReport> {
    let info = read_info(dir)?;
    let path = dir.join("manifest.jsonl");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("could not read `{}`", path.display()))?;
    let mut report = VerifyReport {
        count: info.count,
        ..VerifyReport::default()
    };
    let mut seen = vec![false; info.count as usize];
    let mut records: Vec<Record> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        match serde_json::from_str::<Record>(line) {
            Err(e) => report.bad_lines.push(format!("line {}: {e}", n + 1)),
            Ok(r) if r.index >= info.count => report.bad_lines.push(format!(
                "line {}: sample {} is beyond the dataset's {} samples",
                n + 1,
                r.index,
                info.count
            )),
            Ok(r) if seen[r.index as usize] => report.bad_lines.push(format!(
                "line {}: sample {} is listed again",
                n + 1,
                r.index
            )),
            Ok(r) => {
                seen[r.index as usize] = true;
                records.push(r);
            }
        }
    }
    report.listed = records.len();
    report.missing = (0..info.count).filter(|&i| !seen[i as usize]).collect();
    let mut bad: Vec<(u64, String)> = records
        .par_iter()
        .flat_map_iter(|r| {
            r.files.iter().filter_map(|f| {
                check_file(dir, f).map(|why| (r.index, format!("{}: {why}", f.path)))
            })
        })
        .collect();
    bad.sort();
    report.bad_files = bad.into_iter().map(|(_, s)| s).collect();
    Ok(report)
}

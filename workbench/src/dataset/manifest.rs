//! A dataset on disk, and its manifest.
//!
//! ```text
//! DIR/dataset.json             the seed, the count and the sampler (every default filled in)
//! DIR/samples/NNNNNNNN.exr     the layers (super::layers)
//! DIR/samples/NNNNNNNN.png     the tone-mapped flare (unless layers.png = false)
//! DIR/samples/NNNNNNNN.json    the annotation (super::annotation)
//! DIR/records/NNNNNNNN.json    the sample's manifest line, written last: the sample is done
//! DIR/manifest.jsonl           every record, sorted by index, one a line
//! ```
//!
//! Every file is written atomically (a temporary file beside it, synced, renamed over it), and
//! each process writes only its own samples' files, so processes rendering different shards
//! into one directory cannot corrupt each other's. The manifest is rebuilt from the records
//! ([`merge`]), sorted by index, at the end of every run (and by `flarebench dataset merge`):
//! the same bytes whichever processes made the samples.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flarebench_sdk::io::write_atomically;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::config::SamplerConfig;
use super::layers::{encode_exr, encode_preview};
use super::sample::SampleOutput;

/// The format name of `dataset.json`.
pub const DATASET_FORMAT: &str = "flarebench-dataset-1";

/// `dataset.json`: what every sample of the directory is drawn from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DatasetInfo {
    pub format: String,
    pub seed: u64,
    /// Samples `0..count` make the dataset.
    pub count: u64,
    /// The lenses drawn from (`maker/stem`) and their weights.
    pub lenses: Vec<(String, f64)>,
    pub sampler: SamplerConfig,
}

/// One file of a sample.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileEntry {
    /// Relative to the dataset's directory, `/`-separated.
    pub path: String,
    /// SHA-256 of its bytes, lower-case hex.
    pub sha256: String,
    pub bytes: u64,
}

/// One sample's line of the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    pub index: u64,
    pub files: Vec<FileEntry>,
    pub lens: String,
    /// The f-number drawn, the lights, and the ghosts drawn.
    pub f_number: f64,
    pub lights: usize,
    pub ghosts: usize,
}

/// The file-name stem of sample `index`: eight digits (more past 99,999,999).
pub fn stem(index: u64) -> String {
    format!("{index:08}")
}

/// Lower-case hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn record_path(dir: &Path, index: u64) -> PathBuf {
    dir.join("records").join(format!("{}.json", stem(index)))
}

/// Creates `dir`'s folders and its `dataset.json`, or checks that the one there describes the
/// same dataset (so a run resumes only its own dataset).
pub fn prepare(dir: &Path, info: &DatasetInfo) -> anyhow::Result<()> {
    for sub in ["samples", "records"] {
        let d = dir.join(sub);
        fs::create_dir_all(&d).with_context(|| format!("could not create `{}`", d.display()))?;
    }
    let path = dir.join("dataset.json");
    let text = serde_json::to_string_pretty(info)? + "\n";
    if path.exists() {
        let old = read_info(dir)?;
        if &old != info {
            bail!(
                "`{}` holds another dataset (seed {}, count {}, or another sampler): give a new \
                 directory, or the same seed, count and sampler to resume it",
                dir.display(),
                old.seed,
                old.count
            );
        }
        return Ok(());
    }
    write_atomically(&path, text.as_bytes())
        .with_context(|| format!("could not write `{}`", path.display()))
}

/// Reads `dir/dataset.json`.
pub fn read_info(dir: &Path) -> anyhow::Result<DatasetInfo> {
    let path = dir.join("dataset.json");
    let text = fs::read_to_string(&path)
        .with_context(|| format!("could not read `{}`", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("`{}` is not a dataset", path.display()))
}

/// Writes sample `index`'s files, then its record, each atomically; returns the record.
pub fn write_sample(dir: &Path, index: u64, out: &SampleOutput) -> anyhow::Result<Record> {
    let s = stem(index);
    let mut files: Vec<(String, Vec<u8>)> = vec![(format!("samples/{s}.exr"), encode_exr(out)?)];
    if out.annotation.sample.layers.png {
        let ev = out
            .annotation
            .sample
            .layers
            .png_exposure_ev
            .unwrap_or(out.annotation.figures.exposure_ev);
        files.push((format!("samples/{s}.png"), encode_preview(out, ev)?));
    }
    files.push((
        format!("samples/{s}.json"),
        (serde_json::to_string_pretty(&out.annotation)? + "\n").into_bytes(),
    ));
    let mut entries = Vec::with_capacity(files.len());
    for (rel, bytes) in &files {
        let path = dir.join(rel);
        write_atomically(&path, bytes)
            .with_context(|| format!("could not write `{}`", path.display()))?;
        entries.push(FileEntry {
            path: rel.clone(),
            sha256: sha256_hex(bytes),
            bytes: bytes.len() as u64,
        });
    }
    let a = &out.annotation;
    let record = Record {
        index,
        files: entries,
        lens: a.sample.lens.clone(),
        f_number: a.sample.f_number,
        lights: a.lights.len(),
        ghosts: a.ghosts.len(),
    };
    let path = record_path(dir, index);
    write_atomically(&path, (serde_json::to_string(&record)? + "\n").as_bytes())
        .with_context(|| format!("could not write `{}`", path.display()))?;
    Ok(record)
}

/// What is wrong with one file of a record, if anything.
pub fn check_file(dir: &Path, entry: &FileEntry) -> Option<String> {
    match fs::read(dir.join(&entry.path)) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some("missing".into()),
        Err(e) => Some(format!("unreadable: {e}")),
        Ok(bytes) if sha256_hex(&bytes) != entry.sha256 => Some(format!(
            "SHA-256 differs from the manifest's ({} bytes, {} recorded)",
            bytes.len(),
            entry.bytes
        )),
        Ok(_) => None,
    }
}

/// Sample `index`'s record, if the sample is done: its record reads and every file it lists
/// is there with its hash.
pub fn done(dir: &Path, index: u64) -> Option<Record> {
    let text = fs::read_to_string(record_path(dir, index)).ok()?;
    let record: Record = serde_json::from_str(&text).ok()?;
    (record.index == index && record.files.iter().all(|f| check_file(dir, f).is_none()))
        .then_some(record)
}

/// Every record in `dir/records`, sorted by index (files that do not read as records are
/// skipped: a sample without one is not done).
pub fn records(dir: &Path) -> anyhow::Result<Vec<Record>> {
    let rdir = dir.join("records");
    let mut out = Vec::new();
    for entry in
        fs::read_dir(&rdir).with_context(|| format!("could not read `{}`", rdir.display()))?
    {
        let path = entry?.path();
        if path.extension().is_some_and(|e| e == "json")
            && let Ok(text) = fs::read_to_string(&path)
            && let Ok(r) = serde_json::from_str::<Record>(&text)
        {
            out.push(r);
        }
    }
    out.sort_by_key(|r| r.index);
    out.dedup_by_key(|r| r.index);
    Ok(out)
}

/// Rebuilds `dir/manifest.jsonl` from the records (atomically); returns how many it holds.
pub fn merge(dir: &Path) -> anyhow::Result<usize> {
    let records = records(dir)?;
    let mut text = String::new();
    for r in &records {
        text += &serde_json::to_string(r)?;
        text.push('\n');
    }
    let path = dir.join("manifest.jsonl");
    write_atomically(&path, text.as_bytes())
        .with_context(|| format!("could not write `{}`", path.display()))?;
    Ok(records.len())
}

//! The bundled library's FlareSim lenses (`lenses/<maker>/`), made by `flarebench curate`: the
//! lenses named in the checked-in selection list (`lenses/sources/flaresim-selection.txt`,
//! [`selection`]) are read from FlareSim's library (`tests/data/flaresim-lenses/lens_files/`),
//! given their metadata, film and coatings ([`conversion`], [`film`]), checked ([`checks`])
//! and written as our XML with the checks' results in their notes. How the list was chosen
//! and what the checks found: `docs/lenses.md` § The bundled library.

pub mod checks;
pub mod conversion;
pub mod film;
pub mod selection;

use std::path::{Path, PathBuf};

use anyhow::Context;
use flarebench_sdk::LensSystem;

pub use selection::Entry;

/// The source tree's `lenses/`.
pub fn lenses_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses")
}

/// The selection list in the source tree.
pub fn selection_path() -> PathBuf {
    lenses_dir().join("sources/flaresim-selection.txt")
}

/// FlareSim's `lens_files/` in the source tree.
pub fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/flaresim-lenses/lens_files")
}

/// Reads the selection list at `path`.
pub fn read_selection(path: &Path) -> anyhow::Result<Vec<Entry>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("could not read the selection list `{}`", path.display()))?;
    selection::parse(&text, &path.display().to_string())
}

/// A curated lens: converted, checked, its notes ending with the checks' sentence.
#[derive(Debug)]
pub struct Curated {
    pub entry: Entry,
    pub system: LensSystem,
    pub checks: checks::Checks,
}

/// Converts and checks one entry (the quick stability suite only when `stability`).
pub fn curate(entry: &Entry, corpus: &Path, stability: bool) -> anyhow::Result<Curated> {
    let mut system = conversion::convert(entry, corpus)?;
    let checks = checks::run(&entry.name, &system, stability);
    system.notes = format!("{}\n{}", system.notes, checks.note());
    Ok(Curated {
        entry: entry.clone(),
        system,
        checks,
    })
}

/// The notes of a curated lens without the checks' sentence (the last line): what
/// [`conversion::convert`] writes, to compare a bundled file with a fresh conversion.
pub fn notes_without_checks(notes: &str) -> &str {
    match notes.rsplit_once('\n') {
        Some((rest, last)) if last.starts_with("Checks (flarebench curate)") => rest,
        _ => notes,
    }
}

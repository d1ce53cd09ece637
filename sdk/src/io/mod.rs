//! Lens file formats: reading OpenLensFlare XML and our superset of it, writing ours, and
//! saving atomically. Formats are described in `docs/formats.md`.
//!
//! Every reading error is a [`LensFileError`] naming the file, and where it applies the line,
//! column and field. Nothing here panics on bad input.

mod atomic;
mod error;
mod olf_xml;
mod text;
mod xml_tree;

use std::path::Path;

pub use atomic::save_xml;
pub use error::LensFileError;
pub use olf_xml::{parse_olf_xml, write_olf_xml, write_xml};

use crate::system::LensSystem;

/// A lens read from a file, with what the reader had to assume or ignore.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedLens {
    pub system: LensSystem,
    /// One line per assumption or ignored tag, as `file:line:column: message`.
    pub warnings: Vec<String>,
}

/// Reads a lens file, choosing the format by extension: `.xml` is OpenLensFlare XML or ours.
/// Zemax `.zmx` and PBRT `.dat` are not supported yet and give an error saying so.
pub fn read_lens(path: &Path) -> Result<LoadedLens, LensFileError> {
    let label = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "xml" => {
            let bytes = std::fs::read(path).map_err(|e| LensFileError::io(&label, &e))?;
            let text = text::decode(&bytes).map_err(|e| {
                let valid = std::str::from_utf8(&bytes[..e.offset.min(bytes.len())]).unwrap_or("");
                let (line, column) = text::LineIndex::new(valid).line_col(valid.len());
                LensFileError::at(&label, line, column, "", e.message)
            })?;
            parse_olf_xml(&text, &label)
        }
        "zmx" => Err(LensFileError::whole_file(
            label,
            "Zemax `.zmx` lens files are not supported yet; convert the lens to XML",
        )),
        "dat" => Err(LensFileError::whole_file(
            label,
            "PBRT `.dat` lens tables are not supported yet; convert the lens to XML",
        )),
        "" => Err(LensFileError::whole_file(
            label,
            "the file has no extension; lens files are read by extension (.xml)",
        )),
        other => Err(LensFileError::whole_file(
            label,
            format!("lens files with extension `.{other}` are not supported; use .xml"),
        )),
    }
}

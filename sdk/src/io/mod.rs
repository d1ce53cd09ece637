//! Lens file formats: reading OpenLensFlare XML and our superset of it, Zemax `.zmx`, PBRT
//! `.dat` lens tables and FlareSim `.lens` files; writing ours, and saving atomically. Formats
//! are described in `docs/formats.md`.
//!
//! Every reading error is a [`LensFileError`] naming the file, and where it applies the line,
//! column and field. Nothing here panics on bad input.

mod atomic;
mod error;
mod flaresim;
mod located;
mod olf_bounds;
pub(crate) mod olf_xml;
mod pbrt;
mod text;
mod xml_tree;
mod zmx;

use std::path::Path;

pub use atomic::{save_xml, write_atomically};
pub use error::LensFileError;
pub use flaresim::{LensApertureConvention, coating_stack as flaresim_coating, parse_flaresim};
pub use olf_bounds::{
    OlfAngleEntry, OlfGhostBounds, OlfGhostEntry, OlfRect, parse_olf_bounds, read_olf_bounds,
};
pub use olf_xml::{parse_olf_xml, write_olf_xml, write_xml};
pub use pbrt::{PbrtConvention, parse_pbrt};
pub use zmx::parse_zmx;

use crate::system::LensSystem;

/// A lens read from a file, with what the reader had to assume or ignore.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedLens {
    pub system: LensSystem,
    /// One line per assumption or ignored tag, as `file:line:column: message`.
    pub warnings: Vec<String>,
}

/// Choices a lens file cannot make for itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// The Zemax multi-configuration position to read (1-based, as Zemax numbers them);
    /// `None` reads the configuration that was active when the file was saved.
    pub zemax_config: Option<usize>,
    /// How to read the second column of a PBRT table; `None` detects it from the zeros in
    /// the first and last rows.
    pub pbrt_convention: Option<PbrtConvention>,
    /// What the `semi_ap` column of a FlareSim `.lens` file holds; `None` decides it from the
    /// data (with a warning saying which and why).
    pub lens_aperture: Option<LensApertureConvention>,
    /// For `.lens` files: clamp clear apertures that are still impossible (beyond |R|, or
    /// making neighbouring surfaces cross) to what the surfaces allow, each with a warning,
    /// instead of refusing the lens.
    pub lenient_apertures: bool,
}

/// Reads a lens file with default options; see [`read_lens_with`].
pub fn read_lens(path: &Path) -> Result<LoadedLens, LensFileError> {
    read_lens_with(path, &ReadOptions::default())
}

/// Reads a lens file, choosing the format by extension (case-insensitive): `.xml` is
/// OpenLensFlare XML or ours, `.zmx` Zemax OpticStudio, `.dat` a PBRT realistic-camera table,
/// `.lens` a FlareSim lens file.
/// An option that does not apply to the file's format is an error rather than being ignored.
pub fn read_lens_with(path: &Path, options: &ReadOptions) -> Result<LoadedLens, LensFileError> {
    let label = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if options.zemax_config.is_some() && ext != "zmx" {
        return Err(LensFileError::whole_file(
            label,
            "a configuration number applies to Zemax `.zmx` files only",
        ));
    }
    if options.pbrt_convention.is_some() && ext != "dat" {
        return Err(LensFileError::whole_file(
            label,
            "a PBRT thickness convention applies to PBRT `.dat` tables only",
        ));
    }
    if options.lens_aperture.is_some() && ext != "lens" {
        return Err(LensFileError::whole_file(
            label,
            "a `semi_ap` aperture convention applies to FlareSim `.lens` files only",
        ));
    }
    if options.lenient_apertures && ext != "lens" {
        return Err(LensFileError::whole_file(
            label,
            "lenient clear apertures apply to FlareSim `.lens` files only",
        ));
    }
    let read = || std::fs::read(path).map_err(|e| LensFileError::io(&label, &e));
    match ext.as_str() {
        "xml" => {
            let bytes = read()?;
            let text = text::decode(&bytes).map_err(|e| {
                let valid = std::str::from_utf8(&bytes[..e.offset.min(bytes.len())]).unwrap_or("");
                let (line, column) = text::LineIndex::new(valid).line_col(valid.len());
                LensFileError::at(&label, line, column, "", e.message)
            })?;
            parse_olf_xml(&text, &label)
        }
        "zmx" => {
            let bytes = read()?;
            let (text, _) = text::decode_legacy(&bytes)
                .map_err(|e| LensFileError::whole_file(&label, e.message))?;
            parse_zmx(&text, &label, options.zemax_config)
        }
        "dat" => {
            let bytes = read()?;
            let (text, _) = text::decode_legacy(&bytes)
                .map_err(|e| LensFileError::whole_file(&label, e.message))?;
            parse_pbrt(&text, &label, options.pbrt_convention)
        }
        "lens" => {
            let bytes = read()?;
            let (text, _) = text::decode_legacy(&bytes)
                .map_err(|e| LensFileError::whole_file(&label, e.message))?;
            parse_flaresim(
                &text,
                &label,
                options.lens_aperture,
                options.lenient_apertures,
            )
        }
        "" => Err(LensFileError::whole_file(
            label,
            "the file has no extension; lens files are read by extension (.xml, .zmx, .dat, .lens)",
        )),
        other => Err(LensFileError::whole_file(
            label,
            format!(
                "lens files with extension `.{other}` are not supported; use .xml, .zmx, .dat \
                 or .lens"
            ),
        )),
    }
}

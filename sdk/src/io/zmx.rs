//! Zemax OpticStudio lens files (`.zmx`, sequential mode): one record per line, a surface
//! block per `SURF`, object surface first and image surface last.
//!
//! Read: `UNIT` (MM, CM, IN, METER), `NAME`, `NOTE`, `GCAT`, `WAVM`/`PWAV` (the primary
//! wavelength, which paraxial data default to), `FTYP`/`XFLN`/`YFLN` (the largest field, to
//! derive missing semi-diameters), `ENPD`/`FNUM`/`OBNA`/`FLOA` (the stop size), `MNUM` and the
//! configuration operands `THIC`, `CRVT`, `CONN`, `SDIA`, `APER` (`--config N`); per surface
//! `TYPE` (STANDARD, EVENASPH, XASPHERE, COORDBRK without decenter or tilt), `CURV`, `DISZ`,
//! `CONI`, `PARM`, `XDAT`, `GLAS`, `DIAM`, `CLAP`, `FLAP`, `STOP`, `COAT` (the name, in the
//! notes). Mirrors are refused. Everything approximated is a warning; the mapping is in
//! `docs/formats.md`.

mod aperture;
mod build;
mod config;
mod glass;
mod header;
mod records;

#[cfg(test)]
mod tests;

use super::located::Reporter;
use super::{LensFileError, LoadedLens};

/// Parses a Zemax `.zmx` file (already decoded to text) and validates the system.
/// `file_label` names the file in errors and warnings; `config` selects a multi-configuration
/// position (1-based), `None` the one active when the file was saved.
pub fn parse_zmx(
    text: &str,
    file_label: &str,
    config: Option<usize>,
) -> Result<LoadedLens, LensFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ctx = Reporter::new(file_label, text);
    let recs = records::split(&ctx, text)?;
    let system = build::build(&mut ctx, &recs, config)?;
    Ok(LoadedLens {
        system,
        warnings: ctx.warnings,
    })
}

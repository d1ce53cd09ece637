//! Finding lens files: a path, or the name of a lens in the bundled library (`lenses/`).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use flarebench_sdk::io::{
    LensApertureConvention, LoadedLens, PbrtConvention, ReadOptions, read_lens_with,
};

/// Extensions tried when a bundled lens is named without one.
const EXTENSIONS: &[&str] = &["xml", "zmx", "dat", "lens"];

/// Directories searched for bundled lenses, in order: `$FLAREBENCH_LENS_DIR`, `lenses/` beside
/// the executable or two levels up (a cargo target dir), then the source tree's `lenses/`.
pub fn library_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("FLAREBENCH_LENS_DIR") {
        dirs.push(PathBuf::from(d));
    }
    if let Ok(exe) = std::env::current_exe()
        && let Some(bin_dir) = exe.parent()
    {
        dirs.push(bin_dir.join("lenses"));
        if let Some(up) = bin_dir.parent().and_then(Path::parent) {
            dirs.push(up.join("lenses"));
        }
    }
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses"));
    dirs.into_iter().filter(|d| d.is_dir()).collect()
}

/// The path of `spec`: an existing file, or a bundled lens name such as `heliar-tronnier`.
pub fn resolve(spec: &str) -> anyhow::Result<PathBuf> {
    let direct = Path::new(spec);
    if direct.is_file() {
        return Ok(direct.to_path_buf());
    }
    let dirs = library_dirs();
    for dir in &dirs {
        let candidate = dir.join(spec);
        if candidate.is_file() {
            return Ok(candidate);
        }
        for ext in EXTENSIONS {
            let candidate = dir.join(format!("{spec}.{ext}"));
            if candidate.is_file() {
                return Ok(candidate);
            }
        }
    }
    let names = bundled_names();
    if names.is_empty() {
        bail!("no lens file `{spec}` (and no bundled lens library was found)");
    }
    bail!(
        "no lens file `{spec}`; bundled lenses: {}",
        names.join(", ")
    )
}

/// Names of the bundled lenses (file stems), sorted.
pub fn bundled_names() -> Vec<String> {
    let mut names: Vec<String> = library_dirs()
        .iter()
        .take(1)
        .flat_map(|d| std::fs::read_dir(d).into_iter().flatten().flatten())
        .filter_map(|e| {
            let p = e.path();
            let ext = p.extension()?.to_str()?;
            EXTENSIONS
                .contains(&ext)
                .then(|| p.file_stem()?.to_str().map(str::to_string))?
        })
        .collect();
    names.sort();
    names.dedup();
    names
}

/// How to read lens files that leave a choice open: shared by every command that loads a lens
/// (flattened into its arguments).
#[derive(Clone, Debug, Default, Args)]
pub struct ReadArgs {
    /// Zemax multi-configuration (zoom or focus position) to read, 1-based; default: the one
    /// active when the file was saved.
    #[arg(long = "config", value_name = "N")]
    pub config: Option<usize>,
    /// What column 2 of a PBRT `.dat` table means; default: detected from the zeros in its
    /// first and last rows.
    #[arg(long, value_enum, value_name = "CONVENTION")]
    pub pbrt_convention: Option<PbrtConventionArg>,
    /// What the `semi_ap` column of a FlareSim `.lens` file holds; default: decided from the
    /// data (a warning says which and why).
    #[arg(long, value_enum, value_name = "CONVENTION")]
    pub lens_aperture: Option<LensApertureArg>,
    /// For FlareSim `.lens` files: clamp clear apertures that are still impossible (beyond
    /// |R|, or making neighbouring surfaces cross) to what the surfaces allow, each clamp a
    /// warning, instead of refusing the lens.
    #[arg(long)]
    pub lenient_apertures: bool,
}

/// `--lens-aperture` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LensApertureArg {
    /// Clear semi-diameters, as the column is named.
    Semi,
    /// Clear diameters (each value halved), as most files of FlareSim's library hold.
    Diameter,
}

/// `--pbrt-convention` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PbrtConventionArg {
    /// pbrt's own: the thickness after each surface (last row: film distance, 0 = focus).
    ThicknessAfter,
    /// The separation before each surface (first row 0), as in Modern Lens Design tables.
    SeparationBefore,
}

impl ReadArgs {
    /// The reader options these arguments ask for.
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            zemax_config: self.config,
            pbrt_convention: self.pbrt_convention.map(|c| match c {
                PbrtConventionArg::ThicknessAfter => PbrtConvention::ThicknessAfter,
                PbrtConventionArg::SeparationBefore => PbrtConvention::SeparationBefore,
            }),
            lens_aperture: self.lens_aperture.map(|c| match c {
                LensApertureArg::Semi => LensApertureConvention::Semi,
                LensApertureArg::Diameter => LensApertureConvention::Diameter,
            }),
            lenient_apertures: self.lenient_apertures,
        }
    }
}

/// Resolves and loads a lens with the default reader options; see [`load_with`].
pub fn load(spec: &str, quiet: bool) -> anyhow::Result<LoadedLens> {
    load_with(spec, quiet, &ReadOptions::default())
}

/// Resolves and loads a lens (OpenLensFlare/flarebench XML, Zemax `.zmx`, PBRT `.dat`,
/// FlareSim `.lens`);
/// warnings are printed to stderr unless `quiet`.
pub fn load_with(spec: &str, quiet: bool, options: &ReadOptions) -> anyhow::Result<LoadedLens> {
    let path = resolve(spec)?;
    let loaded = read_lens_with(&path, options)
        .map_err(anyhow::Error::new)
        .with_context(|| format!("could not load lens `{spec}`"))?;
    if !quiet {
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
    }
    Ok(loaded)
}

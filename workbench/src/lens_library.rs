//! Finding lens files: a path, or the name of a lens in the bundled library (`lenses/` and its
//! maker folders), matched by [`names`].

pub mod names;

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

/// The path of `spec`: an existing file, or a bundled lens named by its file stem
/// (`heliar-tronnier`, `ai-nikkor-135mm-f2`), by `maker/stem` (`nikon/ai-nikkor-135mm-f2`),
/// or by a unique prefix or substring of one ([`names::find`]): an ambiguous name is an error
/// listing the candidates, an unknown one suggests the nearest names.
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
    let lenses = bundled();
    if lenses.is_empty() {
        bail!("no lens file `{spec}` (and no bundled lens library was found)");
    }
    match names::find(spec, &lenses) {
        names::Found::One(i) => Ok(lenses[i].path.clone()),
        names::Found::Ambiguous(how, candidates) => {
            let shown: Vec<&str> = candidates
                .iter()
                .take(names::MAX_LISTED)
                .map(|&i| lenses[i].qualified.as_str())
                .collect();
            let more = match candidates.len().saturating_sub(names::MAX_LISTED) {
                0 => String::new(),
                n => format!(", … and {n} more (`flarebench lenses {spec}` lists them all)"),
            };
            bail!(
                "no lens file `{spec}`, and the name is ambiguous: it is {how} of {} bundled \
                 lenses ({}{more}); give more of the name",
                candidates.len(),
                shown.join(", ")
            )
        }
        names::Found::None(near) if near.is_empty() => bail!(
            "no lens file `{spec}`, and no bundled lens has a name like it (`flarebench \
             lenses` lists the {} bundled lenses)",
            lenses.len()
        ),
        names::Found::None(near) => {
            let near: Vec<&str> = near.iter().map(|&i| lenses[i].name.as_str()).collect();
            bail!(
                "no lens file `{spec}`, and no bundled lens of that name; did you mean {}? \
                 (`flarebench lenses` lists the {} bundled lenses)",
                near.join(", "),
                lenses.len()
            )
        }
    }
}

/// One lens of the bundled library.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BundledLens {
    /// Its name: the file stem (unique across the library).
    pub name: String,
    /// `maker/stem` for a lens in a maker folder, else the stem.
    pub qualified: String,
    /// The maker folder (`nikon`), `None` for the lenses at the top of `lenses/`.
    pub folder: Option<String>,
    pub path: PathBuf,
}

/// Folders of `lenses/` that hold no lenses.
const NOT_LENS_FOLDERS: &[&str] = &["sources", "masks"];

/// The lens files directly in `dir`, sorted by name.
fn lens_files(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut files: Vec<(String, PathBuf)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .filter_map(|p| {
            let ext = p.extension()?.to_str()?;
            let stem = p.file_stem()?.to_str()?.to_string();
            EXTENSIONS.contains(&ext).then_some((stem, p))
        })
        .collect();
    files.sort();
    files
}

/// The bundled library: the lenses at the top of the first library directory (the ones
/// `convert.py` writes) and those in its maker folders (`nikon/`, `canon/`, …; not `sources/`
/// or `masks/`), sorted by name.
pub fn bundled() -> Vec<BundledLens> {
    let Some(root) = library_dirs().into_iter().next() else {
        return Vec::new();
    };
    let mut out: Vec<BundledLens> = lens_files(&root)
        .into_iter()
        .map(|(name, path)| BundledLens {
            qualified: name.clone(),
            name,
            folder: None,
            path,
        })
        .collect();
    let mut folders: Vec<PathBuf> = std::fs::read_dir(&root)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| !NOT_LENS_FOLDERS.contains(&n))
        })
        .collect();
    folders.sort();
    for folder in folders {
        let Some(maker) = folder.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        for (name, path) in lens_files(&folder) {
            out.push(BundledLens {
                qualified: format!("{maker}/{name}"),
                name,
                folder: Some(maker.to_string()),
                path,
            });
        }
    }
    out.sort_by(|a, b| a.name.cmp(&b.name).then(a.qualified.cmp(&b.qualified)));
    out
}

/// Names of the bundled lenses (file stems), sorted: the whole library.
pub fn bundled_names() -> Vec<String> {
    let mut names: Vec<String> = bundled().into_iter().map(|l| l.name).collect();
    names.dedup();
    names
}

/// Names of the lenses at the top of `lenses/` (the 19 `convert.py` writes, which the tests
/// and docs name), sorted: what `stability` checks when given no lens.
pub fn core_names() -> Vec<String> {
    bundled()
        .into_iter()
        .filter(|l| l.folder.is_none())
        .map(|l| l.name)
        .collect()
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

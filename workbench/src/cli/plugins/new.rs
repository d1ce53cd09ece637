//! `flarebench plugins new NAME`: writes a new plugin crate made from the guide's example
//! (`crate::plugin_template`) and prints how to build, list and watch it.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail, ensure};
use clap::Args;

use crate::plugin_dirs::PLUGIN_PATH_VAR;
use crate::plugin_template::{check_name, plugin_crate};

/// The sdk this binary was built from, when its sources are still there.
const BUILT_FROM_SDK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../sdk");

#[derive(Debug, Args)]
pub struct NewArgs {
    /// The plugin's name: ASCII letters, digits, `-` and `_`, starting with a letter. It names
    /// the crate, its library (`-` as `_`) and the plugin (`--algo NAME`).
    pub name: String,
    /// The crate's directory (default `./NAME`); it must not exist or be empty.
    #[arg(long)]
    pub path: Option<PathBuf>,
    /// The flarebench sdk crate's directory to depend on (default: the sdk this binary was
    /// built from, when it is still there).
    #[arg(long)]
    pub sdk: Option<PathBuf>,
}

/// The sdk directory: `given`, else the one this binary was built from; checked to hold the
/// `flarebench-sdk` crate, made absolute.
fn sdk_dir(given: Option<&Path>) -> anyhow::Result<PathBuf> {
    let dir = given.unwrap_or(Path::new(BUILT_FROM_SDK));
    let manifest = dir.join("Cargo.toml");
    let text = match std::fs::read_to_string(&manifest) {
        Ok(t) => t,
        Err(e) if given.is_some() => {
            bail!(
                "--sdk {}: cannot read {}: {e}",
                dir.display(),
                manifest.display()
            )
        }
        Err(_) => bail!(
            "the flarebench sdk this binary was built from is no longer at {}; give the sdk \
             crate's directory with --sdk PATH",
            dir.display()
        ),
    };
    ensure!(
        text.lines()
            .any(|l| l.trim() == "name = \"flarebench-sdk\""),
        "{} is not the flarebench-sdk crate's manifest",
        manifest.display()
    );
    std::fs::canonicalize(dir).with_context(|| format!("resolving {}", dir.display()))
}

/// The manifest of the cargo workspace `dir` lies in, if any (the nearest ancestor's
/// `Cargo.toml` with a `[workspace]` table).
fn enclosing_workspace(dir: &Path) -> Option<PathBuf> {
    dir.ancestors().skip(1).find_map(|a| {
        let manifest = a.join("Cargo.toml");
        let text = std::fs::read_to_string(&manifest).ok()?;
        text.lines()
            .any(|l| l.trim() == "[workspace]")
            .then_some(manifest)
    })
}

/// Creates `dir`, refusing a file or a non-empty directory.
fn create_empty_dir(dir: &Path) -> anyhow::Result<()> {
    match std::fs::read_dir(dir) {
        Ok(mut entries) => ensure!(
            entries.next().is_none(),
            "{} already exists and is not empty; choose another --path or name",
            dir.display()
        ),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(_) if dir.exists() => bail!("{} exists and is not a directory", dir.display()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", dir.display())),
    }
    std::fs::create_dir_all(dir.join("src")).with_context(|| format!("creating {}", dir.display()))
}

pub fn run(args: &NewArgs, quiet: bool) -> anyhow::Result<()> {
    check_name(&args.name)?;
    let sdk = sdk_dir(args.sdk.as_deref())?;
    let c = plugin_crate(&args.name, &sdk);
    let dir = args
        .path
        .clone()
        .unwrap_or_else(|| PathBuf::from(&args.name));
    create_empty_dir(&dir)?;
    let dir =
        std::fs::canonicalize(&dir).with_context(|| format!("resolving {}", dir.display()))?;
    for (file, text) in [
        ("Cargo.toml", &c.cargo_toml),
        ("src/lib.rs", &c.lib_rs),
        (".gitignore", &c.gitignore),
    ] {
        let path = dir.join(file);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    if quiet {
        return Ok(());
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| dir.join("target"));
    let debug = target.join("debug");
    let lib = debug.join(format!(
        "{}{}{}",
        std::env::consts::DLL_PREFIX,
        c.lib_name,
        std::env::consts::DLL_SUFFIX
    ));
    let (d, l) = (dir.display(), lib.display());
    println!(
        "wrote the plugin crate `{}` in {d} (Cargo.toml, src/lib.rs, .gitignore): the glow of \
         docs/plugins.md, depending on the flarebench sdk at {}",
        c.name,
        sdk.display()
    );
    if let Some(ws) = enclosing_workspace(&dir) {
        let member = ws
            .parent()
            .and_then(|root| dir.strip_prefix(root).ok())
            .unwrap_or(&dir);
        println!(
            "note: {d} lies inside the cargo workspace of {}; the crate has a [workspace] table of \
             its own, so it builds on its own (to make it a member instead, remove that table and \
             add \"{}\" to `members` there)",
            ws.display(),
            member.display()
        );
    }
    println!();
    println!("next:");
    println!("  cargo build --manifest-path {d}/Cargo.toml");
    println!("      → {l}");
    println!("  flarebench plugins list --plugin {l}");
    println!(
        "  flarebench compare heliar-tronnier --light 8,30 --algo {l} -o {}.png --watch",
        c.name
    );
    println!("      (compares again whenever the library is rebuilt; Ctrl-C ends it)");
    println!(
        "or add {} to {PLUGIN_PATH_VAR} and name the plugin: --algo {}",
        debug.display(),
        c.name
    );
    Ok(())
}

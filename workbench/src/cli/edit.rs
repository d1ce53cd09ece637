//! `flarebench edit`: open the terminal prescription editor on a lens.

use anyhow::Context;
use clap::Args;

use crate::edit::{app::App, files, runner};

/// The bundled lens opened when no lens is given.
const DEFAULT_LENS: &str = "heliar-tronnier";

#[derive(Debug, Args)]
pub struct EditArgs {
    /// Lens file (`.xml`; `.zmx` and `.dat` are saved as `.xml` beside them) or the name of a
    /// bundled lens. Without one, a copy of the bundled Heliar-Tronnier (saving asks for a path).
    pub lens: Option<String>,
}

pub fn run(args: &EditArgs, _quiet: bool) -> anyhow::Result<()> {
    let spec = args.lens.as_deref().unwrap_or(DEFAULT_LENS);
    let opened = files::open(spec, args.lens.is_none())
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("could not open lens `{spec}`"))?;
    let app = App::new(opened).with_context(|| format!("cannot edit `{spec}`"))?;
    runner::run(app)
}

//! `flarebench convert`: read any lens file we read (OpenLensFlare/flarebench XML, Zemax
//! `.zmx`, PBRT `.dat`, FlareSim `.lens`) and write it as our XML, atomically. What the reader
//! approximated is printed as warnings and kept in the written file's notes.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use flarebench_sdk::io::save_xml;
use flarebench_sdk::paraxial::analyse;

use crate::lens_library::{self, ReadArgs};

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Lens file to read (`.xml`, Zemax `.zmx`, PBRT `.dat`, FlareSim `.lens`) or the name of a
    /// bundled lens.
    pub input: String,
    /// Where to write our XML (must end in `.xml`; replaced atomically if it exists).
    #[arg(short, long, value_name = "OUT.xml")]
    pub output: PathBuf,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

pub fn run(args: &ConvertArgs, quiet: bool) -> anyhow::Result<()> {
    let is_xml = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if !is_xml {
        bail!(
            "the output `{}` must end in .xml: convert writes flarebench XML",
            args.output.display()
        );
    }
    let loaded = lens_library::load_with(&args.input, quiet, &args.read.options())?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    save_xml(sys, &args.output)
        .with_context(|| format!("could not write `{}`", args.output.display()))?;
    if !quiet {
        let lambda = sys.default_wavelength_nm();
        let efl = analyse(sys, lambda)
            .map(|p| format!("EFL {:.4} mm at {lambda} nm", p.efl_mm))
            .unwrap_or_else(|e| e.to_string());
        let warnings = match loaded.warnings.len() {
            0 => String::new(),
            n => format!("; {n} warning(s) above, also described in the file's notes"),
        };
        println!(
            "wrote {}: {}, {} surfaces, {efl}{warnings}",
            args.output.display(),
            sys.name,
            sys.surfaces.len()
        );
    }
    Ok(())
}

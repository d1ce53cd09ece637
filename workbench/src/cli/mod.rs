//! Command-line interface: argument parsing and dispatch.

mod apply;
mod apply_sequence;
mod bench;
mod coatings;
mod compare;
mod convert;
mod crosscheck;
mod curate;
mod dataset;
#[cfg(feature = "tui")]
mod edit;
mod fit;
mod gallery;
mod info;
mod lenses;
mod plugins;
mod precompute;
// Public for the Python module (workbench/python): its frames take the same iris, starburst
// and light options, read by the same code.
pub mod render;
mod render_sequence;
mod stability;
mod sweep;
mod trace;
#[cfg(feature = "window")]
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// flarebench — physically based lens flare from real lens prescriptions.
#[derive(Debug, Parser)]
#[command(name = "flarebench", version, about, long_about = None)]
pub struct Cli {
    /// Print no warnings or progress (errors still go to stderr).
    #[arg(long, short, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Show a lens prescription and its paraxial data.
    Info(info::InfoArgs),
    /// List the bundled lenses (name, maker, focal length, f-number, kind, elements, ghosts),
    /// filtered by maker, focal length, f-number, kind or words.
    Lenses(lenses::LensesArgs),
    /// Render a seeded, sharded, resumable dataset of random flares with layers and
    /// annotations (docs/datasets.md); `dataset verify DIR` checks one.
    Dataset(dataset::DatasetArgs),
    /// Render lenses' flares side by side at a standard light into a folder: a contact sheet
    /// and an offline index.html with each lens's section and figures (cached, resumable).
    Gallery(gallery::GalleryArgs),
    /// Precompute ghost bounds over a range of incidence angles (for `render --precomputed`).
    Precompute(precompute::PrecomputeArgs),
    /// Render the ghost flares and starbursts of a lens for one or more lights to an HDR image.
    Render(render::RenderArgs),
    /// Find the bright lights in an image and add the lens's flare to it.
    Apply(apply::ApplyArgs),
    /// Fit a lens's coatings, and the light's intensity and colour, to a linear image of its
    /// flare.
    Fit(fit::FitArgs),
    /// Choose each surface's anti-reflection coating from a catalogue to cut the lens's
    /// flare.
    Coatings(coatings::CoatingsArgs),
    /// Trace one collimated ray through a lens and show every surface it meets.
    Trace(trace::TraceArgs),
    /// Time ghost rendering per lens and quality preset, with the error against the reference.
    Bench(bench::BenchArgs),
    /// Read a lens file (.xml, Zemax .zmx, PBRT .dat, FlareSim .lens) and write it as flarebench XML.
    Convert(convert::ConvertArgs),
    /// Edit a lens prescription in the terminal (spreadsheet, undo, live analysis).
    #[cfg(feature = "tui")]
    Edit(edit::EditArgs),
    /// Open the viewer window on a lens: its section with ray fans and ghost paths beside a
    /// live flare preview (docs/window.md).
    #[cfg(feature = "window")]
    View(view::ViewArgs),
    /// Render one scene with several algorithm plugins: side-by-side and difference images,
    /// median time, error against the reference, items drawn, peak memory.
    Compare(compare::CompareArgs),
    /// Every ghost of one light by the independent Monte-Carlo reference, the mesh reference
    /// and the renderer: energies, centroids, second moments, images.
    Crosscheck(crosscheck::CrosscheckArgs),
    /// Flare algorithm plugins: `plugins list`, `plugins new NAME`.
    Plugins(plugins::PluginsArgs),
    /// Error against run time over algorithms, presets and the planner's thresholds: CSV,
    /// JSON, plots with the Pareto front, contact sheets and an index.html.
    Sweep(sweep::SweepArgs),
    /// The stiff and extreme suite: every lens across its field and at 89°, f32 against f64,
    /// extreme f-numbers, near-flat, tiny and huge radii, near total internal reflection, thin
    /// air gaps, caustics, four reflections; exits 1 when a figure is outside its limit.
    Stability(stability::StabilityArgs),
    /// Rebuild the bundled library's FlareSim lenses from lenses/sources/flaresim-selection.txt,
    /// checking each (for maintainers; docs/lenses.md).
    #[command(hide = true)]
    Curate(curate::CurateArgs),
}

/// Runs the command line; errors are printed with their causes.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Info(a) => info::run(a, cli.quiet),
        Command::Lenses(a) => lenses::run(a, cli.quiet),
        Command::Gallery(a) => gallery::run(a, cli.quiet),
        Command::Dataset(a) => dataset::run(a, cli.quiet),
        Command::Curate(a) => curate::run(a, cli.quiet),
        Command::Trace(a) => trace::run(a, cli.quiet),
        Command::Render(a) => render::run(a, cli.quiet),
        Command::Apply(a) => apply::run(a, cli.quiet),
        Command::Fit(a) => fit::run(a, cli.quiet),
        Command::Coatings(a) => coatings::run(a, cli.quiet),
        Command::Precompute(a) => precompute::run(a, cli.quiet),
        Command::Convert(a) => convert::run(a, cli.quiet),
        Command::Plugins(a) => plugins::run(a, cli.quiet),
        Command::Compare(a) => compare::run(a, cli.quiet),
        Command::Bench(a) => bench::run(a, cli.quiet),
        Command::Sweep(a) => sweep::run(a, cli.quiet),
        Command::Crosscheck(a) => crosscheck::run(a, cli.quiet),
        Command::Stability(a) => stability::run(a, cli.quiet),
        #[cfg(feature = "tui")]
        Command::Edit(a) => edit::run(a, cli.quiet),
        #[cfg(feature = "window")]
        Command::View(a) => view::run(a, cli.quiet),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Checks a wavelength argument (nm).
/// Writes `report` as JSON to `path` (beside a command's other outputs), then prints it: as
/// JSON with `--json`, else as text by `print` unless quiet.
fn keep_report<T: serde::Serialize>(
    report: &T,
    path: &std::path::Path,
    json: bool,
    quiet: bool,
    print: impl FnOnce(&T),
) -> anyhow::Result<()> {
    use anyhow::Context;
    let text = serde_json::to_string_pretty(report)?;
    std::fs::write(path, &text).with_context(|| format!("could not write `{}`", path.display()))?;
    if json {
        println!("{text}");
    } else if !quiet {
        print(report);
    }
    Ok(())
}

/// `lens` with `note` added to its notes, on a line of its own.
fn with_note(mut lens: flarebench_sdk::LensSystem, note: &str) -> flarebench_sdk::LensSystem {
    if !lens.notes.is_empty() {
        lens.notes.push('\n');
    }
    lens.notes.push_str(note);
    lens
}

fn wavelength(nm: f64) -> anyhow::Result<f64> {
    anyhow::ensure!(
        nm.is_finite() && (200.0..=2500.0).contains(&nm),
        "--wavelength-nm must be between 200 and 2500 nm, got {nm}"
    );
    Ok(nm)
}

/// Formats a length for tables: `inf` for infinite values, else 4 decimals.
fn fmt_len(v: f64) -> String {
    if v.is_infinite() {
        if v > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        format!("{v:.4}")
    }
}

//! `flarebench crosscheck`: every ghost of one light by the independent Monte-Carlo reference
//! (`flarebench_sdk::ghost::monte_carlo`), the mesh reference and the renderer, side by side
//! (`ghost_raytrace::crosscheck`): energy share at 550 nm against the bounds search's, each
//! ghost's energy in the frame, centroid shift and second moments, and the images of all the
//! compared ghosts against the Monte-Carlo image.

use anyhow::Context;
use clap::Args;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::GhostPath;
use flarebench_sdk::ghost::monte_carlo::McSettings;
use ghost_raytrace::crosscheck::{Allot, Crosscheck, CrosscheckOptions, GhostRow, crosscheck};
use ghost_raytrace::scene::{LightSpec, Quality};

use super::render::parse_size;
use crate::flare::frame_for;
use crate::lens_library;
use crate::output::{ToneMap, save_image};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct CrosscheckArgs {
    /// Lens file or bundled lens name.
    pub lens: String,
    /// The light: THETA,PHI[,INTENSITY[,KELVIN or R:G:B]] (degrees).
    #[arg(long, default_value = "10,30", value_parser = LightSpec::parse)]
    pub light: LightSpec,
    /// Monte-Carlo rays per ghost (image estimate: each ghost's with `--allot even`, their mean
    /// with `flux`; the 550 nm energy share traces as many for each ghost).
    #[arg(long, default_value_t = 1 << 18)]
    pub rays: usize,
    /// How the Monte-Carlo image estimate shares `--rays` × the ghosts among them: `even`
    /// (the same error bar on every ghost's energy) or `flux` (in proportion to each ghost's
    /// flux in the frame, from a pilot of an eighth of the rays: the least noise in the whole
    /// image for the rays, dim ghosts' own error bars wider).
    #[arg(long, value_enum, default_value_t = AllotArg::Even)]
    pub allot: AllotArg,
    /// Sampling density, relative to the rest, of the entry cells whose rays all land outside
    /// the frame (1: uniform; below 1 the rays gather where the image is, each weighed by its
    /// density, so the estimates stay unbiased).
    #[arg(long, default_value_t = 0.0625)]
    pub outside_weight: f64,
    /// Independent batches the Monte-Carlo error bars come from.
    #[arg(long, default_value_t = 16)]
    pub batches: usize,
    /// Seed of the Monte-Carlo random streams.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Frame size, WxH (a low resolution keeps the Monte-Carlo image's noise low).
    #[arg(long, default_value = "160x90", value_parser = parse_size)]
    pub size: (usize, usize),
    /// The renderer's quality preset.
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Only these ghosts (e.g. `--ghost 8-0 --ghost 6-4`).
    #[arg(long = "ghost", value_parser = parse_ghost)]
    pub ghosts: Vec<GhostPath>,
    /// Leave out the mesh reference (slow on lenses of many ghosts).
    #[arg(long)]
    pub no_reference: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write the compared ghosts' images into this directory as OpenEXR: `mc.exr`,
    /// `reference.exr` (unless `--no-reference`) and `renderer.exr`.
    #[arg(long, value_name = "DIR")]
    pub export: Option<std::path::PathBuf>,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

/// `--allot` (`ghost_raytrace::crosscheck::Allot`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AllotArg {
    Even,
    Flux,
}

impl From<AllotArg> for Allot {
    fn from(a: AllotArg) -> Allot {
        match a {
            AllotArg::Even => Allot::Even,
            AllotArg::Flux => Allot::Flux,
        }
    }
}

fn parse_ghost(s: &str) -> Result<GhostPath, String> {
    s.parse::<GhostPath>().map_err(|e| e.to_string())
}

/// `a / b` as a ratio for the table, `-` when either is missing.
fn ratio(a: Option<f64>, b: f64) -> String {
    match a {
        Some(a) if b > 0.0 => format!("{:.4}", a / b),
        _ => "-".into(),
    }
}

/// The distance between two centroids (px), `-` when either is missing.
fn shift(a: Option<[f64; 2]>, b: [f64; 2]) -> String {
    match a {
        Some(a) if a.iter().chain(&b).all(|v| v.is_finite()) => {
            format!("{:.3}", (a[0] - b[0]).hypot(a[1] - b[1]))
        }
        _ => "-".into(),
    }
}

/// The ratio of the traces of two second-moment matrices, `-` when either is missing.
fn spread(a: Option<[f64; 3]>, b: [f64; 3]) -> String {
    match a {
        Some(a) if b[0] + b[2] > 0.0 => format!("{:.4}", (a[0] + a[2]) / (b[0] + b[2])),
        _ => "-".into(),
    }
}

fn row(g: &GhostRow) -> Vec<String> {
    let e = g.mc_energy.mean;
    vec![
        g.path.clone(),
        format!("{:.4e}", g.mc_share.mean),
        format!("{:.2}%", 100.0 * g.mc_share.relative_error()),
        g.bounds_share
            .map_or("no light".into(), |b| format!("{b:.4e}")),
        ratio(g.bounds_share, g.mc_share.mean),
        format!("{e:.4e}"),
        format!("{:.2}%", 100.0 * g.mc_energy.relative_error()),
        ratio(g.reference.map(|r| r.energy), e),
        ratio(g.renderer.map(|r| r.energy), e),
        shift(g.reference.map(|r| r.centroid_px), g.mc_centroid_px),
        shift(g.renderer.map(|r| r.centroid_px), g.mc_centroid_px),
        spread(g.reference.map(|r| r.moments_px2), g.mc_image.moments_px2),
        spread(g.renderer.map(|r| r.moments_px2), g.mc_image.moments_px2),
        g.dropped
            .map(|d| format!("{d:?}"))
            .unwrap_or_default()
            .to_lowercase(),
    ]
}

/// Writes the three images of `c` into `dir` (created if missing).
fn export(dir: &std::path::Path, c: &Crosscheck) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("could not create `{}`", dir.display()))?;
    let tone = ToneMap::default();
    let images = &c.images;
    save_image(&images.mc.image, &dir.join("mc.exr"), &tone)?;
    if let Some(r) = &images.reference {
        save_image(r, &dir.join("reference.exr"), &tone)?;
    }
    save_image(&images.renderer, &dir.join("renderer.exr"), &tone)?;
    Ok(())
}

pub fn run(args: &CrosscheckArgs, quiet: bool) -> anyhow::Result<()> {
    anyhow::ensure!(args.rays >= 1, "--rays must be at least 1");
    anyhow::ensure!(args.batches >= 2, "--batches must be at least 2");
    anyhow::ensure!(
        args.outside_weight > 0.0 && args.outside_weight <= 1.0,
        "--outside-weight must be in (0, 1]"
    );
    let sys = args
        .sensor_stack
        .apply(lens_library::load(&args.lens, quiet || args.json)?.system)?;
    let frame = frame_for(&sys, args.size);
    let opts = CrosscheckOptions {
        mc: McSettings {
            rays: args.rays,
            batches: args.batches,
            seed: args.seed,
            outside_weight: args.outside_weight,
            ..McSettings::default()
        },
        quality: args.quality,
        reference: !args.no_reference,
        ghosts: args.ghosts.clone(),
        allot: args.allot.into(),
    };
    let c = crosscheck(&sys, &Aperture::Circular, frame, &args.light, &opts)?;
    if let Some(dir) = &args.export {
        export(dir, &c)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    let mut t = Table::new(&[
        "ghost",
        "MC share",
        "±",
        "bounds share",
        "bounds/MC",
        "MC energy",
        "±",
        "ref/MC",
        "render/MC",
        "Δc ref px",
        "Δc render px",
        "σ² ref/MC",
        "σ² render/MC",
        "render",
    ]);
    for g in &c.ghosts {
        t.row(row(g));
    }
    print!("{}", t.render());
    println!(
        "direct flux (550 nm, on axis): MC {:.6} ± {:.3}% mm², bounds {:.6} mm² (bounds/MC {:.4})",
        c.direct_mc.mean,
        100.0 * c.direct_mc.relative_error(),
        c.direct_bounds,
        c.direct_bounds / c.direct_mc.mean
    );
    let rmse = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3}%", 100.0 * v));
    println!(
        "images against MC ({}x{}): reference {}, renderer {}; MC noise {:.3}%",
        frame.width,
        frame.height,
        rmse(c.reference_rmse),
        rmse(Some(c.renderer_rmse)),
        100.0 * c.mc_noise
    );
    Ok(())
}

//! `flarebench coatings`: each air–glass surface's coating chosen from the catalogue to cut
//! the lens's flare over a set of light angles (`flarebench_coatings::choice`,
//! docs/coatings.md), against MgF₂ on every surface; the choice checked by rendering both.

use std::path::PathBuf;

use anyhow::{Context, Result, ensure};
use clap::{Args, ValueEnum};
use flarebench_coatings::catalogue::Design;
use flarebench_coatings::choice::{Choice, Chooser, Objective};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::save_xml;
use ghost_raytrace::ghosts::render;
use ghost_raytrace::plan::{PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use super::render::IrisArgs;
use crate::flare::exposure::ghost_exposure;
use crate::lens_library;
use crate::output::{ToneMap, ToneOperator, encode_png, save_image};
use crate::stability::field::edge_deg;

/// What to minimise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObjectiveArg {
    /// The ghosts' energy on the frame, summed over the angles.
    Total,
    /// The brightest ghost's energy (the largest over the angles).
    Brightest,
    /// The energy of the ghosts that stand out: peak above --threshold × the brightest
    /// ghost's peak with MgF₂ everywhere.
    Visible,
}

#[derive(Debug, Args)]
pub struct CoatingsArgs {
    /// Lens file or the name of a bundled lens.
    pub lens: String,
    /// Directory for the lens with the chosen coatings (chosen.xml), the before/after images
    /// and the report (coatings.json).
    #[arg(short, long)]
    pub output: PathBuf,
    /// A light THETA,PHI (repeatable; default: a quarter, half and three quarters of the
    /// lens's field edge at 30° azimuth).
    #[arg(long)]
    pub light: Vec<String>,
    #[arg(long, value_enum, default_value_t = ObjectiveArg::Total)]
    pub objective: ObjectiveArg,
    /// For --objective visible: the fraction of the brightest MgF₂ ghost's peak above which
    /// a ghost stands out.
    #[arg(long, default_value_t = 0.05)]
    pub threshold: f64,
    /// At most this many surfaces take a premium design (broadband or multicoat; default:
    /// any number).
    #[arg(long)]
    pub max_premium: Option<usize>,
    /// Frame the ghosts are measured and drawn in, WxH.
    #[arg(long, default_value = "240x160")]
    pub size: String,
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    #[command(flatten)]
    pub iris: IrisArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct Report<'a> {
    lens: String,
    lights: Vec<(f64, f64)>,
    objective: Objective,
    max_premium: Option<usize>,
    #[serde(flatten)]
    choice: &'a Choice,
    /// The ghosts' energy on the frame at each angle as the renderer draws them, with MgF₂
    /// everywhere and with the choice; and the factor between their sums.
    rendered_before: Vec<f64>,
    rendered_after: Vec<f64>,
    rendered_factor: f64,
    outputs: Vec<String>,
}

pub fn run(args: &CoatingsArgs, quiet: bool) -> Result<()> {
    let loaded = lens_library::load(&args.lens, quiet || args.json)?;
    let sys = &loaded.system;
    let (w, h) = parse_size(&args.size)?;
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    let lights = lights_of(args, sys)?;
    let objective = match args.objective {
        ObjectiveArg::Total => Objective::Total,
        ObjectiveArg::Brightest => Objective::Brightest,
        ObjectiveArg::Visible => {
            ensure!(
                args.threshold > 0.0 && args.threshold.is_finite(),
                "--threshold must be positive, got {}",
                args.threshold
            );
            Objective::Visible(args.threshold)
        }
    };
    let aperture = args.iris.aperture()?;
    let t = std::time::Instant::now();
    let chooser = Chooser::new(sys, &aperture, frame, &lights, args.quality, objective)
        .with_context(|| format!("measuring the ghosts of `{}`", sys.name))?;
    let basis_ms = t.elapsed().as_secs_f64() * 1e3;
    let max_premium = args.max_premium.unwrap_or(usize::MAX);
    let mut choice = chooser.choose(max_premium);
    choice.basis_ms = basis_ms;
    let designs: Vec<Design> = choice.after.designs.iter().map(|(_, d)| *d).collect();
    let before_lens = chooser.lens(&vec![Design::Mgf2; designs.len()]);
    let mut after_lens = chooser.lens(&designs);
    after_lens.notes = format!(
        "{}{}Coatings chosen by `flarebench coatings` (objective {:?}): {}.",
        after_lens.notes,
        if after_lens.notes.is_empty() {
            ""
        } else {
            "\n"
        },
        args.objective,
        choice
            .after
            .designs
            .iter()
            .map(|(s, d)| format!("s{s} {}", d.name()))
            .collect::<Vec<_>>()
            .join(", ")
    );

    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("could not create `{}`", args.output.display()))?;
    let lens_path = args.output.join("chosen.xml");
    save_xml(&after_lens, &lens_path)
        .with_context(|| format!("could not write `{}`", lens_path.display()))?;
    let mut outputs = vec![lens_path.display().to_string()];
    let (mut rendered_before, mut rendered_after) = (Vec::new(), Vec::new());
    for (k, light) in lights.iter().enumerate() {
        let before = ghosts_of(&before_lens, &aperture, frame, light)?;
        let after = ghosts_of(&after_lens, &aperture, frame, light)?;
        rendered_before.push(before.luminance_sum());
        rendered_after.push(after.luminance_sum());
        for (name, img) in [("before", &before), ("after", &after)] {
            let p = args.output.join(format!("{name}-{k}.exr"));
            save_image(img, &p, &ToneMap::default())?;
            outputs.push(p.display().to_string());
        }
        // Side by side at the MgF₂ frame's exposure: what the choice takes away shows.
        let tone = ToneMap {
            exposure_ev: ghost_exposure(&before).unwrap_or(0.0),
            operator: ToneOperator::Aces,
        };
        let pair = side_by_side(&before, &after);
        let p = args.output.join(format!("before-after-{k}.png"));
        std::fs::write(&p, encode_png(&pair, &tone)?)
            .with_context(|| format!("could not write `{}`", p.display()))?;
        outputs.push(p.display().to_string());
    }
    let sum = |v: &[f64]| v.iter().sum::<f64>();
    let report = Report {
        lens: sys.name.clone(),
        lights: lights.iter().map(|l| (l.theta_deg, l.phi_deg)).collect(),
        objective,
        max_premium: args.max_premium,
        choice: &choice,
        rendered_factor: sum(&rendered_before) / sum(&rendered_after).max(f64::MIN_POSITIVE),
        rendered_before,
        rendered_after,
        outputs,
    };
    let json_path = args.output.join("coatings.json");
    super::keep_report(&report, &json_path, args.json, quiet, print_report)
}

fn parse_size(s: &str) -> Result<(usize, usize)> {
    let parsed = s
        .split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)))
        .filter(|&(w, h): &(usize, usize)| w >= 16 && h >= 16);
    parsed.with_context(|| format!("--size wants WxH of at least 16x16, got `{s}`"))
}

/// The lights of `--light`, or three along the field at 30° azimuth.
fn lights_of(args: &CoatingsArgs, sys: &LensSystem) -> Result<Vec<LightSpec>> {
    if args.light.is_empty() {
        let edge = edge_deg(sys);
        ensure!(
            edge.is_finite() && edge > 0.0,
            "`{}` has no field to put lights in: give --light",
            sys.name
        );
        return Ok([0.25, 0.5, 0.75]
            .iter()
            .map(|f| LightSpec {
                theta_deg: (f * edge).min(80.0),
                phi_deg: 30.0,
                intensity: 1.0,
                spectrum: flarebench_sdk::color::LightSpectrum::D65,
            })
            .collect());
    }
    args.light
        .iter()
        .map(|s| LightSpec::parse(s).with_context(|| format!("--light `{s}`")))
        .collect()
}

/// The renderer's image of `system`'s ghosts under `light`, none culled.
fn ghosts_of(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    light: &LightSpec,
) -> Result<HdrImage> {
    let mut opts = PlanOptions::for_quality(Quality::Default, None);
    opts.cull = false;
    let plans = plan(system, std::slice::from_ref(light), &frame, &opts)?;
    Ok(render(system, aperture, frame, &plans)?.0)
}

/// `a` and `b` side by side, a black column between.
fn side_by_side(a: &HdrImage, b: &HdrImage) -> HdrImage {
    let gap = 4;
    let mut out = HdrImage::new(a.width + gap + b.width, a.height.max(b.height));
    for (img, x0) in [(a, 0), (b, a.width + gap)] {
        for y in 0..img.height {
            let row = &img.pixels[y * img.width..(y + 1) * img.width];
            out.pixels[y * out.width + x0..y * out.width + x0 + img.width].copy_from_slice(row);
        }
    }
    out
}

fn print_report(r: &Report<'_>) {
    let c = r.choice;
    println!(
        "{}: objective {:?} over {} light angle{}: {:.4e} with MgF₂ everywhere → {:.4e} ({:.2}× less)",
        r.lens,
        r.objective,
        r.lights.len(),
        if r.lights.len() == 1 { "" } else { "s" },
        c.before.objective,
        c.after.objective,
        c.factor
    );
    println!(
        "rendered ghost energy: {:.4e} → {:.4e} ({:.2}× less); {} evaluations in {:.0} ms, bases {:.0} ms",
        r.rendered_before.iter().sum::<f64>(),
        r.rendered_after.iter().sum::<f64>(),
        r.rendered_factor,
        c.evaluations,
        c.choice_ms,
        c.basis_ms
    );
    println!("\n{:<8} design", "surface");
    for (s, d) in &c.after.designs {
        println!("{:<8} {}", s, d.name());
    }
    println!("\n{:<8} {:>12} {:>12}", "ghost", "before", "after");
    let mut rows: Vec<(&str, f64, f64)> = c
        .before
        .ghosts
        .iter()
        .map(|g| {
            let after = c
                .after
                .ghosts
                .iter()
                .find(|a| a.path == g.path)
                .map_or(0.0, |a| a.energy.iter().sum());
            (g.path.as_str(), g.energy.iter().sum(), after)
        })
        .collect();
    rows.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (p, b, a) in rows.iter().take(10) {
        println!("{p:<8} {b:>12.4e} {a:>12.4e}");
    }
    if rows.len() > 10 {
        println!("({} more ghosts in the JSON report)", rows.len() - 10);
    }
    println!();
    for o in &r.outputs {
        println!("wrote {o}");
    }
}

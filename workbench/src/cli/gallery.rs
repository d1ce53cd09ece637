//! `flarebench gallery`: lenses' flares side by side, in a folder with a contact sheet and an
//! offline `index.html` (`crate::gallery`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use ghost_raytrace::scene::{LightSpec, Quality};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use super::lenses::FilterArgs;
use super::render::parse_size;
use crate::flare::StarburstMode;
use crate::gallery::{self, GalleryLens, Record, Settings, StandardLight, page};
use crate::lens_library::{self, BundledLens};
use crate::lens_listing;

#[derive(Debug, Args)]
pub struct GalleryArgs {
    /// Lens files or bundled lens names (a unique part of one will do).
    pub lenses: Vec<String>,
    /// Every bundled lens.
    #[arg(long)]
    pub all: bool,
    /// The bundled lenses these filters find (as `flarebench lenses` takes them).
    #[command(flatten)]
    pub filter: FilterArgs,
    /// Words each found in a bundled lens's name, maker or notes (repeat for several).
    #[arg(long = "text", value_name = "WORD")]
    pub text: Vec<String>,
    /// The folder written: `index.html`, `contact.png` and `lenses/` (each lens's flare,
    /// section and record).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Size of each flare in pixels, WxH.
    #[arg(long, value_parser = parse_size, default_value = "480x270")]
    pub size: (usize, usize),
    /// Speed against accuracy: fast, default or high.
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Where each lens's light is, as a fraction of the angle to the edge of its own field
    /// (where its chief ray lands on the film's corner): the light images inside every lens's
    /// frame.
    #[arg(long, default_value_t = 0.6, conflicts_with = "light")]
    pub field_fraction: f64,
    /// The light's azimuth (degrees; as `render --light` takes it).
    #[arg(
        long,
        default_value_t = 30.0,
        conflicts_with = "light",
        allow_negative_numbers = true
    )]
    pub azimuth_deg: f64,
    /// The same light for every lens, THETA,PHI[,INTENSITY[,COLOUR]] as `render --light`.
    #[arg(long, value_parser = LightSpec::parse)]
    pub light: Option<LightSpec>,
    /// Diffraction starburst: on, off (ghosts only) or only.
    #[arg(long, value_enum, default_value_t = StarburstMode::On)]
    pub starburst: StarburstMode,
    /// One PNG exposure (stops) for every lens, so their flares compare in brightness;
    /// default: each lens at its own automatic exposure.
    #[arg(long, allow_negative_numbers = true)]
    pub exposure_ev: Option<f32>,
    /// Render every lens again, even those whose record in the folder is up to date.
    #[arg(long)]
    pub force: bool,
}

/// The lenses the arguments name: those given, then the bundled ones `--all` or the filters
/// find, each once, in that order.
fn selection(args: &GalleryArgs) -> anyhow::Result<Vec<GalleryLens>> {
    let filtered = args.all || !args.filter.is_empty() || !args.text.is_empty();
    if args.lenses.is_empty() && !filtered {
        bail!(
            "name the lenses: lens files or bundled names, --all, or filters (--maker, --focal, \
             --fnum, --kind, --text)"
        );
    }
    let bundled = lens_library::bundled();
    let name_of = |path: &std::path::Path| -> Option<String> {
        let canon = path.canonicalize().ok()?;
        bundled
            .iter()
            .find(|b| b.path.canonicalize().ok().as_ref() == Some(&canon))
            .map(|b| b.qualified.clone())
    };
    let mut out: Vec<GalleryLens> = Vec::new();
    for spec in &args.lenses {
        let path = lens_library::resolve(spec)?;
        let name = name_of(&path).unwrap_or_else(|| spec.clone());
        out.push(GalleryLens { name, path });
    }
    if filtered {
        let filter = args.filter.filter(&args.text)?;
        let root = lens_library::library_dirs()
            .into_iter()
            .next()
            .context("no bundled lens library was found")?;
        let listed = lens_listing::load_all(&bundled, &root);
        for (b, l) in bundled.iter().zip(listed) {
            let l = l?;
            if filter.matches(&l) {
                out.push(lens_of(b));
            }
        }
    }
    let mut seen = std::collections::HashSet::new();
    out.retain(|l| seen.insert(l.slug()));
    anyhow::ensure!(!out.is_empty(), "no bundled lens matches the filters");
    Ok(out)
}

fn lens_of(b: &BundledLens) -> GalleryLens {
    GalleryLens {
        name: b.qualified.clone(),
        path: b.path.clone(),
    }
}

pub fn run(args: &GalleryArgs, quiet: bool) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.field_fraction.is_finite() && (0.0..=1.0).contains(&args.field_fraction),
        "--field-fraction {} must be between 0 and 1",
        args.field_fraction
    );
    let lenses = selection(args)?;
    let settings = Settings {
        size: args.size,
        quality: args.quality,
        light: match &args.light {
            Some(l) => StandardLight::Fixed(l.clone()),
            None => StandardLight::Field {
                fraction: args.field_fraction,
                phi_deg: args.azimuth_deg,
            },
        },
        starburst: args.starburst,
        exposure_ev: args.exposure_ev,
    };
    let lens_dir = args.output.join(gallery::LENS_DIR);
    std::fs::create_dir_all(&lens_dir)
        .with_context(|| format!("could not create `{}`", lens_dir.display()))?;

    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(lenses.len() as u64).with_style(
            ProgressStyle::with_template(
                "{msg:40} [{bar:30}] {pos}/{len} lenses, {elapsed} (eta {eta})",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
    };
    let start = Instant::now();
    // Each lens: its record from the folder when up to date, else rendered (in parallel
    // across lenses; a lens that fails is reported and the others go on).
    let results: Vec<(anyhow::Result<Record>, bool)> = lenses
        .par_iter()
        .map(|lens| {
            bar.set_message(lens.name.clone());
            let result = gallery::key(lens, &settings).and_then(|key| {
                match (!args.force)
                    .then(|| gallery::cached(lens, &key, &args.output))
                    .flatten()
                {
                    Some(r) => Ok((r, true)),
                    None => gallery::render(lens, key, &settings, &args.output).map(|r| (r, false)),
                }
            });
            bar.inc(1);
            match result {
                Ok((r, cached)) => (Ok(r), cached),
                Err(e) => (Err(e.context(format!("lens `{}`", lens.name))), false),
            }
        })
        .collect();
    bar.finish_and_clear();

    let mut records = Vec::new();
    let (mut rendered, mut reused, mut failed) = (0, 0, 0);
    for (result, cached) in results {
        match result {
            Ok(r) => {
                if cached {
                    reused += 1;
                } else {
                    rendered += 1;
                }
                records.push(r);
            }
            Err(e) => {
                failed += 1;
                eprintln!("error: {e:#}");
            }
        }
    }
    if !records.is_empty() {
        page::write_contact_sheet(&records, &args.output)?;
        page::write_index(&records, &settings, &args.output)?;
    }
    if !quiet {
        println!(
            "gallery of {} lenses in {}: {rendered} rendered, {reused} up to date, {failed} \
             failed, {:.1} s",
            records.len(),
            args.output.display(),
            start.elapsed().as_secs_f64()
        );
        println!(
            "wrote {} and {}",
            args.output.join("index.html").display(),
            args.output.join("contact.png").display()
        );
    }
    anyhow::ensure!(failed == 0, "{failed} lenses failed (above)");
    Ok(())
}

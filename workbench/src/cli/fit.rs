//! `flarebench fit`: the coatings of a lens, and the light's intensity and colour, fitted to a
//! linear image of its flare (`flarebench_coatings::fit`, docs/coatings.md).
//!
//! The image is read as `apply` reads it (EXR linear; PNG/BMP decoded by its stated response),
//! reduced by whole-pixel box averaging to at most `--fit-width` pixels across (centred, so the
//! optical axis stays at the middle), and a reduced pixel counts only when none of its pixels
//! is saturated or excluded. The light is `--light`, or the source at `--light-at`, or the
//! brightest source found in the image; a disc of `--light-mask` pixels around where its
//! own image lands is left out (the direct image and the starburst, which the fit does not
//! model).

use std::path::PathBuf;

use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use flarebench_coatings::catalogue::coatable_surfaces;
use flarebench_coatings::fit::{Fit, FitOptions, Target, fit};
use flarebench_coatings::model::{CoatingModel, Family};
use flarebench_sdk::color::srgb;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::save_xml;
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use super::render::IrisArgs;
use crate::input_image::read_input_image;
use crate::lens_library;
use crate::output::{ToneMap, save_image};
use crate::sources::{direction_of, find_sources};

/// How an 8-bit image's values map to light.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum Response {
    /// Linear: the values are the light.
    Linear,
    /// The sRGB transfer function (IEC 61966-2-1).
    Srgb,
}

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Lens file or the name of a bundled lens.
    pub lens: String,
    /// The image of its flare: .exr (linear) or .png/.bmp (see --response).
    pub image: PathBuf,
    /// Directory for the fitted lens (fitted.xml), the fitted and residual images and the
    /// report (fit.json).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The light: THETA,PHI[,INTENSITY[,COLOUR]] as `render --light` (default: found in the
    /// image, as `apply` finds sources).
    #[arg(long, conflicts_with = "light_at")]
    pub light: Option<String>,
    /// The light is the source whose image is at this pixel: X,Y.
    #[arg(long)]
    pub light_at: Option<String>,
    /// Response of a PNG/BMP: srgb (default) or linear. EXR is linear.
    #[arg(long, value_enum)]
    pub response: Option<Response>,
    /// Values at or above this (largest channel, linear) are saturated and left out (default:
    /// 0.99 for PNG/BMP; none for EXR).
    #[arg(long)]
    pub saturation: Option<f32>,
    /// Leave out a rectangle of the image: X0,Y0,X1,Y1 in its pixels (repeatable).
    #[arg(long)]
    pub exclude: Vec<String>,
    /// Radius (pixels of the image) left out around the light's own image (default 3% of the
    /// image's width).
    #[arg(long)]
    pub light_mask: Option<f64>,
    /// The coating model of every air–glass surface: single (a layer's index and thickness),
    /// a catalogue design whose layers' thicknesses are fitted (mgf2, v-coat, broadband,
    /// multicoat, uncoated), or fixed (the lens file's).
    #[arg(long, default_value = "single")]
    pub model: String,
    /// Another model for one surface: SURFACE=MODEL (repeatable; surfaces numbered as
    /// `flarebench info` numbers them).
    #[arg(long)]
    pub surface: Vec<String>,
    /// Keep the light's intensity and colour as given instead of fitting them.
    #[arg(long)]
    pub no_gains: bool,
    /// The image is reduced to at most this many pixels across for the fit.
    #[arg(long, default_value_t = 240)]
    pub fit_width: usize,
    /// Renders of the ghosts' band images per solution: the first with the lens's coatings,
    /// each next with the last fit's (the three best distinct solutions of the first are each
    /// refined so).
    #[arg(long, default_value_t = 3)]
    pub passes: usize,
    /// Starts spread over the parameters' bounds, besides four MgF₂-like ones; each start is
    /// scanned surface by surface (more: slower, less likely to stop in a wrong valley).
    #[arg(long, default_value_t = FitOptions::default().spread_starts)]
    pub spread_starts: usize,

    /// Defect corrections per solution at most: the ghost renderer's image at the solution's
    /// coatings against the basis's, the difference added to the model and the fit repeated
    /// (0: the basis alone)
    #[arg(long, default_value_t = FitOptions::default().corrections)]
    pub corrections: usize,
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Film width (mm) the image spans (default: the lens file's).
    #[arg(long)]
    pub film_width_mm: Option<f64>,
    #[command(flatten)]
    pub iris: IrisArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct FitReport<'a> {
    lens: String,
    image: String,
    light: LightLine,
    fit_width: usize,
    fit_height: usize,
    model: Vec<(usize, &'static str)>,
    #[serde(flatten)]
    fit: &'a Fit,
    outputs: Vec<String>,
}

#[derive(Debug, Serialize)]
struct LightLine {
    theta_deg: f64,
    phi_deg: f64,
    intensity: f64,
    /// Where it came from: given, at a pixel, or found.
    source: &'static str,
}

pub fn run(args: &FitArgs, quiet: bool) -> Result<()> {
    let loaded = lens_library::load(&args.lens, quiet || args.json)?;
    let sys = &loaded.system;
    let input = read_input_image(&args.image)?;
    let mut image = input.image;
    if !input.hdr && args.response == Some(Response::Linear) {
        // read_input_image decoded sRGB; undo it for a linear 8-bit image.
        for p in &mut image.pixels {
            *p = p.map(srgb::encode);
        }
    }
    let film_w = args.film_width_mm.unwrap_or(sys.film_width_mm);
    ensure!(
        film_w.is_finite() && film_w > 0.0,
        "--film-width-mm must be positive, got {film_w}"
    );
    let full = Frame::across_film(image.width, image.height, film_w);
    let saturation = args.saturation.or((!input.hdr).then_some(0.99));
    // The light: given, at a pixel, or the brightest source.
    let (light, source, light_px) = light_of(args, sys, &full, &image)?;
    let mut counted: Vec<bool> = image
        .pixels
        .iter()
        .map(|p| saturation.is_none_or(|s| p[0].max(p[1]).max(p[2]) < s))
        .collect();
    for spec in &args.exclude {
        let r = parse_numbers::<4>(spec, "--exclude", "X0,Y0,X1,Y1")?;
        for y in 0..image.height {
            for x in 0..image.width {
                let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
                if fx >= r[0].min(r[2])
                    && fx < r[0].max(r[2])
                    && fy >= r[1].min(r[3])
                    && fy < r[1].max(r[3])
                {
                    counted[y * image.width + x] = false;
                }
            }
        }
    }
    let radius = args.light_mask.unwrap_or(0.03 * image.width as f64);
    if let Some([lx, ly]) = light_px {
        for y in 0..image.height {
            for x in 0..image.width {
                if (x as f64 + 0.5 - lx).hypot(y as f64 + 0.5 - ly) <= radius {
                    counted[y * image.width + x] = false;
                }
            }
        }
    }
    let (target, frame) = reduce(&image, &counted, args.fit_width.max(8), film_w)?;
    ensure!(
        target.mask.iter().any(|&m| m),
        "no pixel of `{}` is left to fit (all saturated or excluded)",
        args.image.display()
    );
    let families = families(args, sys)?;
    let model = CoatingModel::new(sys, |c| {
        families
            .iter()
            .find(|(s, _)| *s == c.surface)
            .map_or(Family::Fixed, |(_, f)| *f)
    })?;
    let aperture = args.iris.aperture()?;
    let options = FitOptions {
        quality: args.quality,
        fit_gains: !args.no_gains,
        passes: args.passes.max(1),
        spread_starts: args.spread_starts,
        corrections: args.corrections,
        ..FitOptions::default()
    };
    if !quiet && !args.json {
        eprintln!(
            "fitting {} parameters of {} surfaces to {} × {} pixels ({} counted) …",
            model.len() + if options.fit_gains { 3 } else { 0 },
            model.surfaces.len(),
            frame.width,
            frame.height,
            target.mask.iter().filter(|&&m| m).count()
        );
    }
    let found = fit(&model, &aperture, &light, &target, &options)
        .with_context(|| format!("fitting `{}` to `{}`", sys.name, args.image.display()))?;

    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("could not create `{}`", args.output.display()))?;
    let lens = super::with_note(
        found.system.clone(),
        &format!(
            "Coatings fitted by `flarebench fit` to {} (relative RMSE {:.4}).",
            args.image.display(),
            found.relative_rmse
        ),
    );
    let lens_path = args.output.join("fitted.xml");
    save_xml(&lens, &lens_path)
        .with_context(|| format!("could not write `{}`", lens_path.display()))?;
    let fitted_path = args.output.join("fitted.exr");
    save_image(&found.image, &fitted_path, &ToneMap::default())?;
    let mut residual = HdrImage::new(frame.width, frame.height);
    for (i, r) in residual.pixels.iter_mut().enumerate() {
        if target.mask[i] {
            *r = std::array::from_fn(|c| found.image.pixels[i][c] - target.image.pixels[i][c]);
        }
    }
    let residual_path = args.output.join("residual.exr");
    save_image(&residual, &residual_path, &ToneMap::default())?;
    let target_path = args.output.join("target.exr");
    save_image(&target.image, &target_path, &ToneMap::default())?;
    let report = FitReport {
        lens: sys.name.clone(),
        image: args.image.display().to_string(),
        light: LightLine {
            theta_deg: light.theta_deg,
            phi_deg: light.phi_deg,
            intensity: light.intensity,
            source,
        },
        fit_width: frame.width,
        fit_height: frame.height,
        model: model
            .surfaces
            .iter()
            .map(|s| (s.coatable.surface, s.family.name()))
            .collect(),
        fit: &found,
        outputs: [&lens_path, &fitted_path, &residual_path, &target_path]
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    };
    let json_path = args.output.join("fit.json");
    super::keep_report(&report, &json_path, args.json, quiet, print_report)
}

/// The light, where it came from, and its image's pixel (when known).
fn light_of(
    args: &FitArgs,
    sys: &flarebench_sdk::LensSystem,
    frame: &Frame,
    image: &HdrImage,
) -> Result<(LightSpec, &'static str, Option<[f64; 2]>)> {
    if let Some(spec) = &args.light {
        let light = LightSpec::parse(spec).with_context(|| format!("--light `{spec}`"))?;
        return Ok((light, "given", None));
    }
    let (px, source) = match &args.light_at {
        Some(spec) => {
            let p = parse_numbers::<2>(spec, "--light-at", "X,Y")?;
            ([p[0], p[1]], "at a pixel")
        }
        None => {
            let peak = image.max();
            ensure!(peak > 0.0, "`{}` is black", args.image.display());
            let Some(s) = find_sources(image, 0.9 * peak, 1).into_iter().next() else {
                bail!(
                    "no light found in `{}`: give --light or --light-at",
                    args.image.display()
                );
            };
            (s.centroid_px, "found")
        }
    };
    let (theta_deg, phi_deg) = direction_of(sys, frame, px[0], px[1])?;
    Ok((
        LightSpec {
            theta_deg,
            phi_deg,
            intensity: 1.0,
            spectrum: flarebench_sdk::color::LightSpectrum::D65,
        },
        source,
        Some(px),
    ))
}

/// `N` comma-separated numbers.
fn parse_numbers<const N: usize>(spec: &str, flag: &str, shape: &str) -> Result<[f64; N]> {
    let v: Vec<f64> = spec
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()
        .filter(|v: &Vec<f64>| v.len() == N && v.iter().all(|x| x.is_finite()))
        .with_context(|| format!("{flag} wants {shape}, got `{spec}`"))?;
    Ok(std::array::from_fn(|i| v[i]))
}

/// Each coatable surface's family: `--model`, overridden by `--surface S=MODEL`.
fn families(args: &FitArgs, sys: &flarebench_sdk::LensSystem) -> Result<Vec<(usize, Family)>> {
    let parse = |s: &str| {
        Family::parse(s).with_context(|| {
            format!(
                "unknown coating model `{s}`: use single, fixed, uncoated, mgf2, v-coat, broadband or multicoat"
            )
        })
    };
    let all = parse(&args.model)?;
    let coatable = coatable_surfaces(sys);
    let mut out: Vec<(usize, Family)> = coatable.iter().map(|c| (c.surface, all)).collect();
    for spec in &args.surface {
        let (s, m) = spec
            .split_once('=')
            .with_context(|| format!("--surface wants SURFACE=MODEL, got `{spec}`"))?;
        let s: usize = s
            .trim()
            .parse()
            .with_context(|| format!("--surface `{spec}`: `{s}` is not a surface number"))?;
        let Some(slot) = out.iter_mut().find(|(i, _)| *i == s) else {
            bail!(
                "--surface `{spec}`: surface {s} is not between air and glass (coatable: {})",
                coatable
                    .iter()
                    .map(|c| c.surface.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        };
        slot.1 = parse(m.trim())?;
    }
    Ok(out)
}

/// The image reduced by whole-pixel boxes to at most `width` across, centred, with the
/// frame it spans; a reduced pixel counts when every pixel of its box does.
fn reduce(
    image: &HdrImage,
    counted: &[bool],
    width: usize,
    film_w: f64,
) -> Result<(Target, Frame)> {
    let f = image.width.div_ceil(width).max(1);
    let (w, h) = (image.width / f, image.height / f);
    ensure!(
        w >= 8 && h >= 8,
        "the image is too small to fit ({} × {})",
        image.width,
        image.height
    );
    let (x0, y0) = ((image.width - w * f) / 2, (image.height - h * f) / 2);
    let mut out = HdrImage::new(w, h);
    let mut mask = vec![true; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0f64; 3];
            for dy in 0..f {
                for dx in 0..f {
                    let i = (y0 + y * f + dy) * image.width + x0 + x * f + dx;
                    mask[y * w + x] &= counted[i];
                    for (s, &v) in sum.iter_mut().zip(&image.pixels[i]) {
                        *s += f64::from(v);
                    }
                }
            }
            out.pixels[y * w + x] = sum.map(|s| (s / (f * f) as f64) as f32);
        }
    }
    let frame = Frame::across_film(w, h, film_w * (w * f) as f64 / image.width as f64);
    Ok((Target { image: out, mask }, frame))
}

fn print_report(r: &FitReport<'_>) {
    let f = r.fit;
    println!(
        "{}: fitted to {} ({} × {} px, {} counted), light {} at {:.2}°, {:.1}°",
        r.lens,
        r.image,
        r.fit_width,
        r.fit_height,
        f.pixels_counted,
        r.light.source,
        r.light.theta_deg,
        r.light.phi_deg
    );
    println!(
        "relative RMSE {:.4}; {} band images; {} evaluations in {:.0} ms ({:.0}/s); basis {:.0} ms over {} renders; {} corrections{}",
        f.relative_rmse,
        f.band_images,
        f.evaluations,
        f.fit_ms,
        f.evaluations_per_s,
        f.basis_ms,
        f.renders,
        f.corrections,
        if f.converged { "" } else { " (not converged)" }
    );
    println!("\n{:<28} {:>12} {:>12}", "parameter", "value", "σ");
    for p in &f.params {
        let sigma = p.sigma.map_or("—".to_string(), |s| format!("{s:.4}"));
        println!("{:<28} {:>12.4} {:>12}", p.name, p.value, sigma);
    }
    if !f.unconstrained.is_empty() {
        println!("\nnot constrained by the image:");
        for u in &f.unconstrained {
            let names: Vec<String> = u
                .params
                .iter()
                .map(|(n, w)| format!("{w:+.2}·{n}"))
                .collect();
            println!("  {}", names.join(" "));
        }
    }
    println!(
        "\n{:<8} {:>12} {:>12} {:>12} {:>10} {:>10}",
        "ghost", "R", "G", "B", "σ/E", "residual"
    );
    for g in &f.ghosts {
        let rel = if g.relative_sigma.is_finite() {
            format!("{:.4}", g.relative_sigma)
        } else {
            "free".to_string()
        };
        let res = g.residual.map_or("—".to_string(), |v| format!("{v:+.4}"));
        println!(
            "{:<8} {:>12.4e} {:>12.4e} {:>12.4e} {:>10} {:>10}",
            g.path, g.energy[0], g.energy[1], g.energy[2], rel, res
        );
    }
    println!();
    for o in &r.outputs {
        println!("wrote {o}");
    }
}

//! `flarebench apply`: put a lens's flare on an image — find its bright light sources, work
//! out where each light comes from, render their ghosts and starbursts, add them on.
//!
//! Per source (`sources::find_sources`): the direction from its centroid, the lens's focal
//! length and the film size (`sources::direction_of`, which traces the chief ray so the
//! flare centres on the source); its colour (the region's mean, as a smooth spectrum); and
//! its intensity such that the starburst carries the source's own energy in the image
//! (`Σ Y` over the region × `--gain`): `I = gain · energy / direct_flux(θ)`. The ghosts follow
//! from the same intensity, so their brightness relative to the source is the lens's. In an
//! 8-bit image the sources are clipped, so their energy is a lower bound: raise `--gain`.

use std::path::PathBuf;

use clap::Args;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds::direct_flux;
use flarebench_sdk::starburst::StarburstCache;
use flarebench_sdk::trace::InterfaceTableSet;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use super::render::{IrisArgs, StarburstArgs, StarburstMode};
use crate::compose::{StarburstLine, StarburstSetup, add_onto, add_starbursts};
use crate::input_image::read_input_image;
use crate::lens_library;
use crate::output::{ExrPrecision, ToneMap, ToneOperator, save_image_as};
use crate::sources::{Source, direction_of, find_sources};

#[derive(Debug, Args)]
pub struct ApplyArgs {
    /// The image: .exr (linear HDR) or .png/.bmp (sRGB; bright sources are clipped).
    pub image: PathBuf,
    /// Lens file or the name of a bundled lens.
    #[arg(long)]
    pub lens: String,
    /// Output image: .exr (linear) or .png (the input's values kept where there is no flare).
    #[arg(short, long)]
    pub output: PathBuf,
    /// A pixel belongs to a light when its largest linear channel is at least this (default
    /// 1 for EXR, 0.95 for PNG/BMP: clipped white).
    #[arg(long)]
    pub threshold: Option<f32>,
    /// At most this many sources, the brightest.
    #[arg(long, default_value_t = 8)]
    pub max_lights: usize,
    /// Multiplies each source's energy (clipped 8-bit sources need more than 1).
    #[arg(long, default_value_t = 1.0)]
    pub gain: f64,
    /// Film width (mm) the image spans (default: the lens file's).
    #[arg(long)]
    pub film_width_mm: Option<f64>,
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    #[command(flatten)]
    pub iris: IrisArgs,
    #[command(flatten)]
    pub starburst: StarburstArgs,
    /// Write EXR as 16-bit half floats.
    #[arg(long)]
    pub exr_half: bool,
    /// PNG exposure in stops (default 0).
    #[arg(long, allow_negative_numbers = true)]
    pub exposure_ev: Option<f32>,
    /// PNG tone curve (default clamp: the input's values are kept).
    #[arg(long, value_enum)]
    pub tone: Option<ToneOperator>,
    /// Print what was found and added as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// One detected light.
#[derive(Debug, Serialize)]
struct AppliedLight {
    #[serde(flatten)]
    source: Source,
    theta_deg: f64,
    phi_deg: f64,
    intensity: f64,
}

#[derive(Debug, Serialize)]
struct ApplyReport {
    lens: String,
    image: String,
    output: String,
    width: usize,
    height: usize,
    hdr: bool,
    threshold: f32,
    lights: Vec<AppliedLight>,
    /// Sources whose direction could not be found (their centroid and the reason).
    skipped: Vec<(Source, String)>,
    starbursts: Vec<StarburstLine>,
    ghosts_traced: usize,
}

pub fn run(args: &ApplyArgs, quiet: bool) -> anyhow::Result<()> {
    let loaded = lens_library::load(&args.lens, quiet || args.json)?;
    let sys = &loaded.system;
    let input = read_input_image(&args.image)?;
    let bg = &input.image;
    anyhow::ensure!(
        args.gain.is_finite() && args.gain > 0.0,
        "--gain must be positive, got {}",
        args.gain
    );
    let film_w = args.film_width_mm.unwrap_or(sys.film_width_mm);
    anyhow::ensure!(
        film_w.is_finite() && film_w > 0.0,
        "--film-width-mm must be positive, got {film_w}"
    );
    let frame = Frame {
        width: bg.width,
        height: bg.height,
        film_width_mm: film_w,
        film_height_mm: film_w * bg.height as f64 / bg.width as f64,
    };
    let threshold = args.threshold.unwrap_or(if input.hdr { 1.0 } else { 0.95 });
    anyhow::ensure!(
        threshold.is_finite() && threshold > 0.0,
        "--threshold must be positive, got {threshold}"
    );
    let aperture = args.iris.aperture()?;
    let (settings, dust) = args.starburst.load()?;

    let tables = InterfaceTableSet::for_system(sys, 550.0);
    let mut scratch = GridTrace::default();
    let mut lights = Vec::new();
    let mut applied = Vec::new();
    let mut skipped = Vec::new();
    for s in find_sources(bg, threshold, args.max_lights) {
        let [px, py] = s.centroid_px;
        match direction_of(sys, &frame, px, py) {
            Ok((theta_deg, phi_deg)) => {
                let flux = direct_flux(sys, &tables, theta_deg.to_radians(), &mut scratch);
                if flux.is_nan() || flux <= 0.0 {
                    skipped.push((s, "no light reaches the sensor from there".to_string()));
                    continue;
                }
                let intensity = args.gain * s.energy / flux;
                let c = s.colour.map(|v| v.max(0.0) as f32);
                let spectrum = if LightSpectrum::Rgb(c).validate().is_ok() {
                    LightSpectrum::Rgb(c)
                } else {
                    LightSpectrum::D65
                };
                lights.push(LightSpec {
                    theta_deg,
                    phi_deg,
                    intensity,
                    spectrum,
                });
                applied.push(AppliedLight {
                    source: s,
                    theta_deg,
                    phi_deg,
                    intensity,
                });
            }
            Err(e) => skipped.push((s, format!("{e:#}"))),
        }
    }

    let mode = args.starburst.starburst;
    let opts = PlanOptions::for_quality(args.quality, None);
    let plans = if mode == StarburstMode::Only || lights.is_empty() {
        Vec::new()
    } else {
        plan::plan(sys, &lights, &frame, &opts)?
    };
    let (mut flare, _) = ghosts::render(sys, &aperture, frame, &plans)?;
    let starbursts = if mode == StarburstMode::Off {
        Vec::new()
    } else {
        let setup = StarburstSetup {
            aperture: &aperture,
            dust: dust.as_ref(),
            settings,
        };
        add_starbursts(
            &mut flare,
            sys,
            &frame,
            &lights,
            &setup,
            &mut StarburstCache::new(),
        )?
    };
    anyhow::ensure!(
        !flare.has_non_finite(),
        "internal error: the flare has non-finite pixels"
    );
    let out = add_onto(bg, &flare)?;
    let tone = ToneMap {
        exposure_ev: args.exposure_ev.unwrap_or(0.0),
        operator: args.tone.unwrap_or(ToneOperator::Clamp),
    };
    let precision = if args.exr_half {
        ExrPrecision::Half
    } else {
        ExrPrecision::Float
    };
    save_image_as(&out, &args.output, &tone, precision)?;

    let report = ApplyReport {
        lens: sys.name.clone(),
        image: args.image.display().to_string(),
        output: args.output.display().to_string(),
        width: bg.width,
        height: bg.height,
        hdr: input.hdr,
        threshold,
        ghosts_traced: plans.iter().map(|p| p.ghosts.len()).sum(),
        lights: applied,
        skipped,
        starbursts,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !quiet {
        for l in &report.lights {
            eprintln!(
                "light at pixel ({:.1}, {:.1}), {} px, energy {:.4e}: θ {:.3}°, φ {:.2}°",
                l.source.centroid_px[0],
                l.source.centroid_px[1],
                l.source.pixels,
                l.source.energy,
                l.theta_deg,
                l.phi_deg
            );
        }
        for (s, why) in &report.skipped {
            eprintln!(
                "skipped the source at pixel ({:.1}, {:.1}): {why}",
                s.centroid_px[0], s.centroid_px[1]
            );
        }
        eprintln!(
            "wrote {} ({} lights, {} ghosts)",
            args.output.display(),
            report.lights.len(),
            report.ghosts_traced
        );
    }
    Ok(())
}

//! `flarebench apply`: put a lens's flare on an image — find its bright light sources, work
//! out where each light comes from, render their ghosts and starbursts, add them on.
//!
//! Per source (`sources::find_sources`): the direction from its centroid, the lens's focal
//! length and the film size (`sources::direction_of`, which traces the chief ray so the
//! flare centres on the source); its colour (the region's mean, as a smooth spectrum); and
//! its intensity such that the starburst carries the source's own energy in the image
//! (`Σ Y` over the region × the gain): `I = gain · energy / direct_flux(θ)`. The ghosts follow
//! from the same intensity, so their brightness relative to the source is the lens's.
//!
//! **Gain.** An EXR's lights keep their energy (gain 1). In an 8-bit image the sources are
//! clipped: their pixels say only that they are at least white, and the flare computed from
//! that energy stays under one 8-bit step (a clipped disc of radius 4 on a background of 20
//! changed 0.00% of the pixels more than 12 px from it). A clipped source is taken to be
//! [`CLIPPED_SOURCE_STOPS`] stops brighter than its pixels — a street light or a lamp in a
//! photograph exposed for its scene is some 6–12 stops above white, the sun 15 or more. The
//! gain used is printed; `--gain` sets it instead. When the flare still changes no pixel of a
//! PNG output more than [`AWAY_FROM_LIGHT_PX`] beyond the lights, a warning says so.

use std::path::PathBuf;

use clap::Args;
use flarebench_sdk::LensSystem;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds::direct_flux;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::trace::InterfaceTableSet;
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use super::render::{IrisArgs, StarburstArgs};
use crate::flare::compose::{StarburstLine, add_onto};
use crate::flare::{BackendChoice, BackendReport, Flare, Preset, Rendered, Scene};
use crate::input_image::{InputImage, read_input_image};
use crate::lens_library;
use crate::output::{ExrPrecision, OutputFormat, ToneMap, ToneOperator, save_image_as};
use crate::precomputed::load_precomputed;
use crate::sequence::{FrameRange, Shard};
use crate::sources::{Source, direction_of, find_sources};

/// How many stops brighter than its pixels a clipped source of an 8-bit image is taken to be
/// (module docs).
pub const CLIPPED_SOURCE_STOPS: f64 = 10.0;

#[derive(Debug, Args)]
pub struct ApplyArgs {
    /// The image: .exr (linear HDR) or .png/.bmp (sRGB; bright sources are clipped). With
    /// --frames, a pattern whose `####` (or `%04d`) is the frame number (`plate.####.exr`).
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
    /// Multiplies each source's energy. Default: 1 for EXR input; for 8-bit input 2^10, a
    /// clipped source being taken as 10 stops brighter than its pixels.
    #[arg(long)]
    pub gain: Option<f64>,
    /// Film width (mm) the image spans (default: the lens file's).
    #[arg(long)]
    pub film_width_mm: Option<f64>,
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Where the ghosts are drawn and the starbursts composited: auto (a hardware GPU if
    /// there is one, else the CPU), cpu or gpu (as `render --backend`; docs/gpu.md).
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
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
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
    /// Ghost bounds precomputed over a range of angles (else traced for each light), as
    /// `render --precomputed`: `flarebench precompute`'s JSON or OpenLensFlare's XML. With
    /// --frames and without it, one table is built for the lens and used for every frame.
    #[arg(long, value_name = "FILE")]
    pub precomputed: Option<PathBuf>,
    /// Apply to a numbered sequence: frames A..B, both included (or one frame A), of the
    /// image pattern, written to the output pattern (`-o out.####.exr`). One exposure and one
    /// bounds table for every frame. docs/cli.md § Sequences.
    #[arg(long, value_name = "A..B", value_parser = FrameRange::parse)]
    pub frames: Option<FrameRange>,
    /// Apply only to this share of --frames: the frames with (frame − A) % N == I. Each
    /// frame is the same whichever shard writes it.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse, requires = "frames")]
    pub shard: Option<Shard>,
}

/// One detected light.
#[derive(Debug, Serialize)]
struct AppliedLight {
    #[serde(flatten)]
    source: Source,
    theta_deg: f64,
    phi_deg: f64,
    /// The factor the source's energy was multiplied by.
    gain: f64,
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
    /// With a PNG output: how many pixels away from the lights ([`AWAY_FROM_LIGHT_PX`]) the
    /// flare changes by at least one 8-bit step (`null` for EXR output).
    changed_pixels: Option<usize>,
    /// Where the ghosts were drawn (`crate::flare::backend`).
    backend: BackendReport,
}

pub fn run(args: &ApplyArgs, quiet: bool) -> anyhow::Result<()> {
    if args.frames.is_some() {
        return super::apply_sequence::run(args, quiet);
    }
    let loaded = lens_library::load(&args.lens, quiet || args.json)?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let table = match &args.precomputed {
        Some(p) => Some(load_precomputed(p, sys, quiet || args.json)?),
        None => None,
    };
    let input = read_input_image(&args.image)?;
    let bg = &input.image;
    let mut flare = Flare::open(args.backend)?;
    let applied = apply_to(args, sys, &input, table.as_ref(), &mut flare)?;
    let tone = ToneMap {
        exposure_ev: args.exposure_ev.unwrap_or(0.0),
        operator: args.tone.unwrap_or(ToneOperator::Clamp),
    };
    save_image_as(&applied.out, &args.output, &tone, args.precision())?;
    let out = &applied.out;
    let found = applied.found;
    let changed_pixels = (OutputFormat::from_path(&args.output)? == OutputFormat::Png)
        .then(|| changed_away_from_lights(bg, out, &found.applied, &tone));

    let report = ApplyReport {
        lens: sys.name.clone(),
        image: args.image.display().to_string(),
        output: args.output.display().to_string(),
        width: bg.width,
        height: bg.height,
        hdr: input.hdr,
        threshold: applied.threshold,
        ghosts_traced: applied.rendered.ghosts_drawn(),
        changed_pixels,
        lights: found.applied,
        skipped: found.skipped,
        starbursts: applied.rendered.starbursts,
        backend: flare.backend().report().clone(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !quiet {
        report.print(&args.output);
    }
    if !quiet && !report.lights.is_empty() && report.changed_pixels == Some(0) {
        eprintln!(
            "warning: the flare changes no pixel more than {AWAY_FROM_LIGHT_PX} px from the \
             lights by one 8-bit step (gain {}): raise --gain or --exposure-ev to see it",
            applied.gain
        );
    }
    Ok(())
}

impl ApplyArgs {
    /// The EXR output's precision.
    pub(super) fn precision(&self) -> ExrPrecision {
        if self.exr_half {
            ExrPrecision::Half
        } else {
            ExrPrecision::Float
        }
    }
}

/// One image with the flare added: the image, the lights found, what the flare was, and the
/// threshold and gain used.
pub(super) struct Applied {
    pub out: HdrImage,
    pub found: FoundLights,
    pub rendered: Rendered,
    pub threshold: f32,
    pub gain: f64,
}

/// Finds the lights of `input` and adds their flare through `sys` (ghost bounds from `table`
/// when given), drawn by `flare`: what `apply` does to one image, and to each frame of a
/// sequence.
pub(super) fn apply_to(
    args: &ApplyArgs,
    sys: &LensSystem,
    input: &InputImage,
    table: Option<&BoundsTable>,
    flare: &mut Flare,
) -> anyhow::Result<Applied> {
    let bg = &input.image;
    let gain = match args.gain {
        Some(g) => g,
        None if input.hdr => 1.0,
        None => CLIPPED_SOURCE_STOPS.exp2(),
    };
    anyhow::ensure!(
        gain.is_finite() && gain > 0.0,
        "--gain must be positive, got {gain}"
    );
    let frame = frame_of(args, sys, bg)?;
    let threshold = args.threshold.unwrap_or(if input.hdr { 1.0 } else { 0.95 });
    anyhow::ensure!(
        threshold.is_finite() && threshold > 0.0,
        "--threshold must be positive, got {threshold}"
    );
    let aperture = args.iris.aperture()?;
    let (starburst_settings, dust) = args.starburst.load()?;
    let found = lights_of(sys, &frame, bg, threshold, args.max_lights, gain);

    let scene = Scene {
        starburst: args.starburst.starburst,
        starburst_settings,
        dust: dust.as_ref(),
        ..Scene::new(sys, &found.lights, &aperture, frame)
    };
    let rendered = flare.render(
        &scene,
        &Preset::new(PlanOptions::for_quality(args.quality, table)),
    )?;
    let out = add_onto(bg, flare.image())?;
    Ok(Applied {
        out,
        found,
        rendered,
        threshold,
        gain,
    })
}

/// The frame an image of `bg`'s size spans: `--film-width-mm` (default the lens file's)
/// across its width.
pub(super) fn frame_of(args: &ApplyArgs, sys: &LensSystem, bg: &HdrImage) -> anyhow::Result<Frame> {
    let film_w = args.film_width_mm.unwrap_or(sys.film_width_mm);
    anyhow::ensure!(
        film_w.is_finite() && film_w > 0.0,
        "--film-width-mm must be positive, got {film_w}"
    );
    Ok(Frame {
        width: bg.width,
        height: bg.height,
        film_width_mm: film_w,
        film_height_mm: film_w * bg.height as f64 / bg.width as f64,
    })
}

/// The lights found in an image, the sources they came from and those left out.
pub(super) struct FoundLights {
    pub lights: Vec<LightSpec>,
    applied: Vec<AppliedLight>,
    skipped: Vec<(Source, String)>,
}

/// The bright sources of `bg` (`sources::find_sources`) as lights: each aimed by the chief
/// ray at its centroid, coloured by its mean, as intense as its energy × `gain` through the
/// lens (module docs).
fn lights_of(
    sys: &LensSystem,
    frame: &Frame,
    bg: &HdrImage,
    threshold: f32,
    max_lights: usize,
    gain: f64,
) -> FoundLights {
    let tables = InterfaceTableSet::for_system(sys, 550.0);
    let mut scratch = GridTrace::default();
    let mut found = FoundLights {
        lights: Vec::new(),
        applied: Vec::new(),
        skipped: Vec::new(),
    };
    for s in find_sources(bg, threshold, max_lights) {
        let [px, py] = s.centroid_px;
        match direction_of(sys, frame, px, py) {
            Ok((theta_deg, phi_deg)) => {
                let flux = direct_flux(sys, &tables, theta_deg.to_radians(), &mut scratch);
                if flux.is_nan() || flux <= 0.0 {
                    found
                        .skipped
                        .push((s, "no light reaches the sensor from there".to_string()));
                    continue;
                }
                let intensity = gain * s.energy / flux;
                let c = s.colour.map(|v| v.max(0.0) as f32);
                let spectrum = if LightSpectrum::Rgb(c).validate().is_ok() {
                    LightSpectrum::Rgb(c)
                } else {
                    LightSpectrum::D65
                };
                found.lights.push(LightSpec {
                    theta_deg,
                    phi_deg,
                    intensity,
                    spectrum,
                });
                found.applied.push(AppliedLight {
                    source: s,
                    theta_deg,
                    phi_deg,
                    gain,
                    intensity,
                });
            }
            Err(e) => found.skipped.push((s, format!("{e:#}"))),
        }
    }
    found
}

impl ApplyReport {
    /// What was found and written, on stderr.
    fn print(&self, output: &std::path::Path) {
        for l in &self.lights {
            eprintln!(
                "light at pixel ({:.1}, {:.1}), {} px, energy {:.4e} × gain {}: θ {:.3}°, φ {:.2}°",
                l.source.centroid_px[0],
                l.source.centroid_px[1],
                l.source.pixels,
                l.source.energy,
                l.gain,
                l.theta_deg,
                l.phi_deg
            );
        }
        for (s, why) in &self.skipped {
            eprintln!(
                "skipped the source at pixel ({:.1}, {:.1}): {why}",
                s.centroid_px[0], s.centroid_px[1]
            );
        }
        eprintln!(
            "wrote {} ({} lights, {} ghosts)",
            output.display(),
            self.lights.len(),
            self.ghosts_traced
        );
    }
}

/// How far beyond a light's own radius a pixel must be to count as away from it (px): the
/// starburst's core and the light's own glow lie within.
pub const AWAY_FROM_LIGHT_PX: f64 = 12.0;

/// Pixels away from every light (more than [`AWAY_FROM_LIGHT_PX`] beyond the radius of a disc
/// of its area, from its centroid) whose 8-bit value under `tone` differs between `bg` and
/// `out` in some channel.
fn changed_away_from_lights(
    bg: &HdrImage,
    out: &HdrImage,
    lights: &[AppliedLight],
    tone: &ToneMap,
) -> usize {
    let w = bg.width;
    let near = |k: usize| {
        let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        lights.iter().any(|l| {
            let [cx, cy] = l.source.centroid_px;
            let r = (l.source.pixels as f64 / std::f64::consts::PI).sqrt() + AWAY_FROM_LIGHT_PX;
            (x - cx).hypot(y - cy) <= r
        })
    };
    bg.pixels
        .iter()
        .zip(&out.pixels)
        .enumerate()
        .filter(|&(k, (b, o))| {
            (0..3).any(|c| tone.map_channel(b[c]) != tone.map_channel(o[c])) && !near(k)
        })
        .count()
}

//! `flarebench render`: ghost flares and diffraction starbursts of a lens for one or more
//! lights, to EXR or PNG, optionally added onto a background image.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::table::BoundsTable;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::StarburstSettings;
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};

use crate::aperture_file::{MaskEncoding, load_aperture_mask};
use crate::flare::compose::add_onto;
use crate::flare::{BackendChoice, Flare, Preset, Scene, StarburstMode, frame_for};
use crate::input_image::read_input_image;
use crate::lens_library;
use crate::output::{
    ExrPrecision, OutputFormat, ToneMap, ToneOperator, save_image_as, save_png_rgb8,
};
use crate::precomputed::load_precomputed;
use crate::reference_file::{ReferenceSource, reference_for};
use crate::report::{ErrorReport, RenderReport, Timings};
use crate::sequence::{FrameRange, Shard};
use flarebench_sdk::ghost::ReflectionOrder;

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Lens file or the name of a bundled lens.
    pub lens: String,
    /// A light at infinity: THETA,PHI[,INTENSITY[,COLOUR]] — angle to the axis and azimuth in
    /// degrees (PHI turns counter-clockwise from the image's downward direction: its image
    /// lies below the centre at 0, right of it at 90, above at 180, left at 270), irradiance
    /// (default 1), colour as a blackbody temperature in kelvin (e.g.
    /// 3200) or linear sRGB R:G:B (e.g. 1:0.8:0.6); default daylight D65. Repeat for several
    /// lights.
    #[arg(
        long = "light",
        required_unless_present_any = ["lights_at", "light_path"],
        value_parser = LightSpec::parse
    )]
    pub lights: Vec<LightSpec>,
    /// A light given by where it images: X,Y[,INTENSITY[,COLOUR]] — pixel coordinates in the
    /// output image ((0,0) its top-left corner, 960,540 the centre of 1920x1080), the rest as
    /// for --light. The direction is found by aiming the lens's real chief ray at that point
    /// (distortion included). Repeat for several lights; combines with --light.
    #[arg(long = "light-at", value_parser = LightAt::parse)]
    pub lights_at: Vec<LightAt>,
    /// Output size in pixels, WxH (default 1920x1080, or the background's size). The frame
    /// spans the film's width; its height follows the aspect ratio.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,
    /// Speed against accuracy: fast, default or high (docs/performance.md gives the fast and
    /// default presets' frame times and errors).
    #[arg(long, default_value_t = Quality::Default)]
    pub quality: Quality,
    /// Ghost paths: 2 (two reflections) or 4 (two and four reflections; four-reflection paths
    /// whose energy bound is under the quality's threshold are left out before tracing).
    #[arg(long, default_value_t = ReflectionOrder::Two)]
    pub reflections: ReflectionOrder,
    #[command(flatten)]
    pub iris: IrisArgs,
    /// Largest factor by which a large, smooth ghost may be drawn coarser than the output
    /// (a power of two; 1 draws every ghost at full resolution; the preset's when absent: 16
    /// for fast, 8 otherwise). See docs/performance.md.
    #[arg(long, value_parser = parse_downscale)]
    pub max_downscale: Option<usize>,
    /// Trace the ghosts in f64 instead of f32 (slower; for checking precision).
    #[arg(long)]
    pub f64: bool,
    /// Where the ghosts are drawn: auto (a hardware GPU if there is one, else the CPU), cpu,
    /// or gpu (any adapter, a software one such as lavapipe included). docs/gpu.md.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// Draw every wavelength band of a dispersive ghost on its own instead of groups of bands
    /// as one mesh with per-pixel colour fringes (slower; for comparison).
    #[arg(long)]
    pub band_by_band: bool,
    #[command(flatten)]
    pub starburst: StarburstArgs,
    /// Add the flare onto this image (.exr linear, .png/.bmp sRGB) in linear light; the
    /// output takes its size. A PNG output is then written with exposure 0 and the clamp
    /// curve unless --exposure-ev or --tone say otherwise, so untouched pixels keep their
    /// values.
    #[arg(long)]
    pub background: Option<PathBuf>,
    /// Write EXR as 16-bit half floats instead of 32-bit floats.
    #[arg(long)]
    pub exr_half: bool,
    /// Ghost bounds precomputed over a range of angles (else traced for each light): our
    /// JSON table from `flarebench precompute`, or OpenLensFlare's ghost-bounds XML
    /// (`<ghostList>`), told apart by content. Ghosts the file lacks are traced.
    #[arg(long, value_name = "FILE")]
    pub precomputed: Option<PathBuf>,
    /// Also render the dense reference and report the error against it.
    #[arg(long)]
    pub reference: bool,
    /// Keep the reference in this OpenEXR file (implies --reference): read it when it holds
    /// this scene's reference, else render it and write it there.
    #[arg(long, value_name = "FILE")]
    pub reference_file: Option<PathBuf>,
    /// Output image: .exr (linear, float) or .png (tone mapped).
    #[arg(short, long)]
    pub output: PathBuf,
    /// PNG exposure in stops; default: automatic, so the brightest 0.1% of the ghosts' pixels
    /// reach a quarter of white (without ghosts: the brightest 0.1% of the image reach white):
    /// a light in the frame clips, as in a photograph that shows its flare.
    #[arg(long, allow_negative_numbers = true)]
    pub exposure_ev: Option<f32>,
    /// PNG tone curve (default aces; clamp with --background).
    #[arg(long, value_enum)]
    pub tone: Option<ToneOperator>,
    /// Print the report (time per stage, ghosts traced and left out, energies).
    #[arg(long)]
    pub report: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
    /// Render a numbered sequence: frames A..B, both included (or one frame A), for the
    /// lights of --light-path; the output is a pattern whose `####` (or `%04d`) becomes the
    /// frame number (`out.####.exr`). One exposure for every PNG frame. docs/cli.md
    /// § Sequences.
    #[arg(long, value_name = "A..B", value_parser = FrameRange::parse, requires = "light_path")]
    pub frames: Option<FrameRange>,
    /// The lights of a sequence: keyframes of time (frame), θ, φ, intensity and colour, linear
    /// or smooth (TOML; docs/formats.md § Light paths). With --frames.
    #[arg(
        long,
        value_name = "FILE",
        requires = "frames",
        conflicts_with_all = ["lights", "lights_at", "background", "reference", "reference_file"]
    )]
    pub light_path: Option<PathBuf>,
    /// Render only this share of --frames: the frames with (frame − A) % N == I. Each frame is
    /// the same whichever shard renders it.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse, requires = "frames")]
    pub shard: Option<Shard>,
}

/// Starburst options shared by `render` and `apply`.
#[derive(Debug, Args)]
pub struct StarburstArgs {
    /// Diffraction starburst: on (with the ghosts), off (ghosts only) or only.
    #[arg(long, value_enum, default_value_t = StarburstMode::On)]
    pub starburst: StarburstMode,
    /// Texels across the pupil for the starburst's transform (padded 4×): the pattern reaches
    /// ±TEXELS·λ·N/2 on the sensor; 256 gives a 1024² transform.
    #[arg(long, default_value_t = 256)]
    pub starburst_texels: usize,
    /// Dust/scratch overlay on the aperture for the starburst (PNG or BMP, white clear).
    #[arg(long)]
    pub dust: Option<PathBuf>,
}

impl StarburstArgs {
    /// The settings (64 wavelengths, padding 4) and the dust overlay, read and checked.
    pub fn load(&self) -> anyhow::Result<(StarburstSettings, Option<ApertureMask>)> {
        let settings = StarburstSettings {
            pupil_texels: self.starburst_texels,
            ..StarburstSettings::default()
        };
        settings.validate().context("--starburst-texels")?;
        let dust = match &self.dust {
            Some(p) => Some(load_aperture_mask(p, MaskEncoding::Transmission)?.mask),
            None => None,
        };
        Ok((settings, dust))
    }
}

/// The iris of the aperture stop, shared by `render`, `apply` and `compare`.
#[derive(Debug, Args)]
pub struct IrisArgs {
    /// Iris blade count (0: a circular stop).
    #[arg(long, default_value_t = 0)]
    pub iris_blades: u32,
    /// Iris rotation (degrees).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub iris_rotation_deg: f64,
    /// Blade roundness, 0 (straight) to 1 (a circle).
    #[arg(long, default_value_t = 0.0)]
    pub iris_roundness: f64,
    /// The stop's shape as an image (BMP or PNG over [-1, 1]², white open; an OpenLensFlare
    /// distance map such as `lenses/masks/apertureDist.bmp` is recognised): used by the ghosts
    /// and the starburst instead of the iris.
    #[arg(long, value_name = "IMAGE", conflicts_with = "iris_blades")]
    pub aperture_mask: Option<PathBuf>,
}

impl IrisArgs {
    /// The aperture: the mask image if given, else a circle without blades, else the iris;
    /// checked.
    pub fn aperture(&self) -> anyhow::Result<Aperture> {
        if let Some(path) = &self.aperture_mask {
            let mask = load_aperture_mask(path, MaskEncoding::Auto)?.mask;
            return Ok(Aperture::Mask(mask));
        }
        let aperture = if self.iris_blades == 0 {
            Aperture::Circular
        } else {
            Aperture::Iris {
                blades: self.iris_blades,
                rotation_rad: self.iris_rotation_deg.to_radians(),
                roundness: self.iris_roundness,
            }
        };
        aperture.validate().context("iris")?;
        Ok(aperture)
    }
}

/// A light placed by its image position: `X,Y[,INTENSITY[,COLOUR]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightAt {
    /// Pixel coordinates in the output image, x right, y down.
    pub x: f64,
    pub y: f64,
    /// `INTENSITY[,COLOUR]` as `--light` takes them (may be empty).
    pub rest: String,
}

impl LightAt {
    pub fn parse(s: &str) -> Result<LightAt, String> {
        let parts: Vec<&str> = s.splitn(3, ',').map(str::trim).collect();
        if parts.len() < 2 {
            return Err(format!(
                "--light-at takes X,Y[,INTENSITY[,COLOUR]], got `{s}`"
            ));
        }
        let coord = |v: &str, what: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|c| c.is_finite())
                .ok_or_else(|| format!("--light-at `{s}`: {what} `{v}` is not a finite number"))
        };
        let light = LightAt {
            x: coord(parts[0], "X")?,
            y: coord(parts[1], "Y")?,
            rest: parts.get(2).map(|r| r.to_string()).unwrap_or_default(),
        };
        // Check INTENSITY and COLOUR now, with a placeholder direction.
        light.with_direction(0.0, 0.0)?;
        Ok(light)
    }

    /// The light with direction `(theta_deg, phi_deg)`.
    pub fn with_direction(&self, theta_deg: f64, phi_deg: f64) -> Result<LightSpec, String> {
        let spec = if self.rest.is_empty() {
            format!("{theta_deg},{phi_deg}")
        } else {
            format!("{theta_deg},{phi_deg},{}", self.rest)
        };
        LightSpec::parse(&spec).map_err(|e| e.to_string())
    }
}

/// The lights of `--light` followed by those of `--light-at`, aimed by the chief ray.
fn scene_lights(
    sys: &flarebench_sdk::LensSystem,
    frame: &Frame,
    args: &RenderArgs,
) -> anyhow::Result<Vec<LightSpec>> {
    let mut lights = args.lights.clone();
    for at in &args.lights_at {
        let (theta, phi) = crate::sources::direction_of(sys, frame, at.x, at.y)
            .with_context(|| format!("--light-at {},{}", at.x, at.y))?;
        lights.push(at.with_direction(theta, phi).map_err(anyhow::Error::msg)?);
    }
    Ok(lights)
}

pub(super) fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` is not WxH"))?;
    let w: usize = w
        .trim()
        .parse()
        .map_err(|_| format!("width `{w}` is not a whole number"))?;
    let h: usize = h
        .trim()
        .parse()
        .map_err(|_| format!("height `{h}` is not a whole number"))?;
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(format!(
            "size {w}x{h} must be between 1 and 16384 pixels per side"
        ));
    }
    Ok((w, h))
}

pub(super) fn parse_downscale(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(f) if f.is_power_of_two() && f <= 64 => Ok(f),
        _ => Err(format!("`{s}` is not a power of two from 1 to 64")),
    }
}

pub(super) fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

pub fn run(args: &RenderArgs, quiet: bool) -> anyhow::Result<()> {
    if args.frames.is_some() {
        return super::render_sequence::run(args, quiet);
    }
    let t_load = Instant::now();
    let loaded = lens_library::load(&args.lens, quiet || args.json)?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let background = match &args.background {
        Some(p) => Some(read_input_image(p)?.image),
        None => None,
    };
    let frame = frame_for(sys, output_size(background.as_ref(), args.size)?);
    let (starburst_settings, dust) = args.starburst.load()?;
    let aperture = args.iris.aperture()?;
    let table = match &args.precomputed {
        Some(p) => Some(load_precomputed(p, sys, quiet || args.json)?),
        None => None,
    };
    let mut timings = Timings {
        load_ms: ms(t_load),
        ..Timings::default()
    };
    let lights = scene_lights(sys, &frame, args)?;
    let scene = Scene {
        starburst: args.starburst.starburst,
        starburst_settings,
        dust: dust.as_ref(),
        ..Scene::new(sys, &lights, &aperture, frame)
    };
    let reference = args.reference || args.reference_file.is_some();
    let preset = Preset {
        render: RenderOptions {
            trace_f64: args.f64,
            band_by_band: args.band_by_band,
            ..RenderOptions::default()
        },
        exposure: background.is_none() && args.exposure_ev.is_none(),
        keep_ghosts: reference && scene.starburst.starbursts(),
        ..Preset::new(args.plan_options(table.as_ref()))
    };

    let t = Instant::now();
    let mut flare = Flare::open(args.backend)?;
    let open_ms = ms(t);
    let mut frame_out = flare.render(&scene, &preset)?;
    timings.plan_ms = frame_out.timings.plan_ms;
    timings.render_ms = open_ms + frame_out.timings.ghosts_ms;
    timings.starburst_ms = frame_out.timings.starburst_ms;

    // The reference holds the ghosts alone.
    let error = if reference {
        let ghosts = frame_out.ghosts_image.take();
        let ghosts = ghosts.as_ref().unwrap_or(flare.image());
        Some(reference_error(&scene, args, ghosts, quiet, &mut timings)?)
    } else {
        None
    };

    let t = Instant::now();
    let tone = ToneMap {
        exposure_ev: match &background {
            Some(_) => args.exposure_ev.unwrap_or(0.0),
            None => args.exposure_ev.or(frame_out.exposure_ev).unwrap_or(0.0),
        },
        operator: args.tone.unwrap_or(match &background {
            Some(_) => ToneOperator::Clamp,
            None => ToneOperator::Aces,
        }),
    };
    let flare_sum = flare.image().sum();
    let flare_max = flare.image().max();
    write_output(
        &mut flare,
        background.as_ref(),
        &tone,
        &args.output,
        args.exr_half,
    )?;
    timings.write_ms = ms(t);

    let report = RenderReport {
        lens: sys.name.clone(),
        width: frame.width,
        height: frame.height,
        quality: args.quality,
        output: args.output.display().to_string(),
        timings,
        rays_traced: frame_out.rays_traced(),
        triangles: frame_out.triangles(),
        image_sum_rgb: flare_sum,
        image_max: flare_max,
        exposure_ev: tone.exposure_ev,
        lights: frame_out.light_reports(),
        starbursts: frame_out.starbursts,
        error,
        backend: flare.backend().report().clone(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if args.report {
        print!("{}", report.text());
    } else if !quiet {
        eprintln!("wrote {}", args.output.display());
    }
    Ok(())
}

impl RenderArgs {
    /// The planner's options: the preset's, with `--max-downscale` and `--reflections`.
    pub(super) fn plan_options<'a>(&self, table: Option<&'a BoundsTable>) -> PlanOptions<'a> {
        let preset = PlanOptions::for_quality(self.quality, table);
        PlanOptions {
            max_downscale: self.max_downscale.unwrap_or(preset.max_downscale),
            reflections: self.reflections,
            ..preset
        }
    }
}

/// The output's size: `--size`, else the background's (they must agree), else 1920×1080.
fn output_size(
    background: Option<&HdrImage>,
    size: Option<(usize, usize)>,
) -> anyhow::Result<(usize, usize)> {
    Ok(match (background, size) {
        (Some(bg), Some(size)) => {
            anyhow::ensure!(
                size == (bg.width, bg.height),
                "--size {}x{} differs from the background's {}x{}",
                size.0,
                size.1,
                bg.width,
                bg.height
            );
            size
        }
        (Some(bg), None) => (bg.width, bg.height),
        (None, size) => size.unwrap_or((1920, 1080)),
    })
}

/// The error of the ghosts' image against the dense reference (read from or written to
/// `--reference-file`).
fn reference_error(
    scene: &Scene<'_>,
    args: &RenderArgs,
    ghosts: &HdrImage,
    quiet: bool,
    timings: &mut Timings,
) -> anyhow::Result<ErrorReport> {
    let t = Instant::now();
    let (reference, source) = reference_for(
        scene.system,
        scene.aperture,
        scene.frame,
        scene.lights,
        args.reference_file.as_deref(),
        args.reflections,
    )?;
    timings.reference_ms = Some(ms(t));
    if !quiet && !args.json && source != ReferenceSource::Rendered {
        eprintln!("reference {source}");
    }
    ErrorReport::between(ghosts, &reference)
}

/// Writes the frame to `--output`: onto the background when there is one; a PNG of the flare
/// alone tone mapped by the backend's own pass when it has one (the GPU's).
pub(super) fn write_output(
    flare: &mut Flare,
    background: Option<&HdrImage>,
    tone: &ToneMap,
    output: &Path,
    exr_half: bool,
) -> anyhow::Result<()> {
    let precision = if exr_half {
        ExrPrecision::Half
    } else {
        ExrPrecision::Float
    };
    let gpu_png = if background.is_none() && OutputFormat::from_path(output)? == OutputFormat::Png {
        flare.backend_mut().tone_map(tone)?
    } else {
        None
    };
    let img = flare.image();
    match (gpu_png, background) {
        (Some(rgb), _) => save_png_rgb8(rgb, img.width, img.height, output)?,
        (None, Some(bg)) => save_image_as(&add_onto(bg, img)?, output, tone, precision)?,
        (None, None) => save_image_as(img, output, tone, precision)?,
    }
    Ok(())
}

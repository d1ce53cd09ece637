//! `flarebench bench`: time ghost rendering per lens and quality preset, with the error
//! against the reference printed next to each time.
//!
//! For each lens and preset the scene is planned (bounds traced for the light) and rendered
//! `--runs` times; the table gives the median of each stage. With `--precomputed` (one lens)
//! the plan looks the bounds up in a table instead (`render --precomputed`), which is what a
//! renderer drawing many frames of one lens would do. With `--error`, the reference
//! (`ghost_raytrace::reference`) is rendered once per lens at `--error-size` (default: the
//! bench size) and each preset's image at that size is compared with it.

use std::time::Instant;

use crate::reference_file::{in_cache, reference_for};
use clap::Args;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::ReflectionOrder;
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::{LensTables, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use anyhow::Context;
use ghost_raytrace::plan::LightPlan;

use super::render::{parse_downscale, parse_size};
use crate::aperture_file::{MaskEncoding, load_aperture_mask};
use crate::flare::{BackendChoice, BackendReport, Flare, Preset, Scene, StarburstMode, frame_for};
use crate::lens_library;
use crate::precomputed::load_precomputed;
use crate::stats::median;
use crate::table::Table;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Lens files or bundled lens names.
    #[arg(default_values_t = ["heliar-tronnier".to_string(), "nikon-zoom-short".to_string()])]
    pub lenses: Vec<String>,
    /// The light: THETA,PHI[,INTENSITY[,KELVIN]] (degrees; PHI counter-clockwise from the
    /// image's downward direction: 0 below the centre, 90 right of it).
    #[arg(long, default_value = "10,30", value_parser = LightSpec::parse)]
    pub light: LightSpec,
    /// Frame size, WxH.
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    pub size: (usize, usize),
    /// Quality presets to time, comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = Quality::ALL)]
    pub quality: Vec<Quality>,
    /// Largest coarse-frame factor (as `render --max-downscale`; the preset's when absent).
    #[arg(long, value_parser = parse_downscale)]
    pub max_downscale: Option<usize>,
    /// Ghost paths: 2 (two reflections) or 4 (two and four reflections), as `render
    /// --reflections`; the reference then has the same paths.
    #[arg(long, default_value_t = ReflectionOrder::Two)]
    pub reflections: ReflectionOrder,
    /// Timed runs per lens and preset (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Also render the reference and report each preset's error against it (slow).
    #[arg(long)]
    pub error: bool,
    /// Frame size for the error measurement (default: --size).
    #[arg(long, value_parser = parse_size)]
    pub error_size: Option<(usize, usize)>,
    /// Ghost bounds precomputed over a range of angles (as `render --precomputed`: our JSON
    /// table or OpenLensFlare's XML), for the plan to look up instead of tracing them. Only
    /// with one lens.
    #[arg(long, value_name = "FILE")]
    pub precomputed: Option<std::path::PathBuf>,
    /// Draw every wavelength band of a dispersive ghost on its own (as `render
    /// --band-by-band`).
    #[arg(long)]
    pub band_by_band: bool,
    /// Backends to time, comma separated: cpu, gpu (any adapter, a software one included) or
    /// auto; each row gives its backend, and a GPU row the adapter, the CPU time of tracing
    /// and meshing, the bytes uploaded and the GPU time per frame.
    #[arg(long, value_delimiter = ',', default_values_t = [BackendChoice::Cpu])]
    pub backend: Vec<BackendChoice>,
    /// Apertures to time, comma separated: circle, iris (6 straight blades) or mask
    /// (OpenLensFlare's aperture image, lenses/masks/aperture.bmp).
    #[arg(long, value_delimiter = ',', default_values_t = [BenchAperture::Circle])]
    pub aperture: Vec<BenchAperture>,
    /// Also add the light's diffraction starburst every run and time it (64 wavelengths, 256
    /// texels; the pattern kept in a cache from run to run, as a live preview keeps it, so
    /// only the first run computes it). Give a light in the frame (e.g. `--light 8,60` for the
    /// Heliar): the default light's image is outside it.
    #[arg(long)]
    pub starburst: bool,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

/// An aperture the bench times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BenchAperture {
    Circle,
    Iris,
    Mask,
}

impl std::fmt::Display for BenchAperture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BenchAperture::Circle => "circle",
            BenchAperture::Iris => "iris",
            BenchAperture::Mask => "mask",
        })
    }
}

impl BenchAperture {
    fn aperture(self) -> anyhow::Result<Aperture> {
        Ok(match self {
            BenchAperture::Circle => Aperture::Circular,
            BenchAperture::Iris => Aperture::Iris {
                blades: 6,
                rotation_rad: 0.0,
                roundness: 0.0,
            },
            BenchAperture::Mask => {
                let path = lens_library::library_dirs()
                    .into_iter()
                    .map(|d| d.join("masks/aperture.bmp"))
                    .find(|p| p.is_file())
                    .context("OpenLensFlare's aperture mask, lenses/masks/aperture.bmp, is not found beside the bundled lenses")?;
                Aperture::Mask(load_aperture_mask(&path, MaskEncoding::Auto)?.mask)
            }
        })
    }
}

/// One lens × preset.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub lens: String,
    pub quality: Quality,
    pub aperture: BenchAperture,
    /// Where the ghosts were drawn, and on what (`crate::flare::BackendReport`: the GPU's
    /// adapter, meshing time, triangles and bytes uploaded, pass times of the last run).
    pub backend: BackendReport,
    /// GPU rows: medians over the runs of the CPU's tracing and meshing and of the GPU's
    /// passes (milliseconds; the render time also holds the readback).
    pub mesh_ms: Option<f64>,
    pub gpu_ms: Option<f64>,
    /// With `--starburst`: the median time of adding the starburst (milliseconds; part of the
    /// frame time).
    pub starburst_ms: Option<f64>,
    /// Reflections per ghost path planned for (2, or 4 for two and four).
    pub reflections: ReflectionOrder,
    /// True when the plan looked the bounds up in `--precomputed`'s table.
    pub precomputed: bool,
    pub width: usize,
    pub height: usize,
    pub ghosts_drawn: usize,
    pub ghosts_total: usize,
    /// Share of the ghosts' energy left out by the plan.
    pub dropped_energy_fraction: f64,
    /// Share of the frame's ghost energy culled as dim (`LightPlan::culled_share`).
    pub culled_energy_fraction: f64,
    /// Building the lens's interface tables once, before the runs (milliseconds): what a
    /// plugin does when the lens is prepared (`ghost_raytrace::plan::LensTables`).
    pub prepare_ms: f64,
    /// Medians over the runs (milliseconds).
    pub plan_ms: f64,
    pub render_ms: f64,
    pub frame_ms: f64,
    /// Against the reference at `error_width × error_height` (with `--error`).
    pub error_width: Option<usize>,
    pub error_height: Option<usize>,
    pub relative_rmse: Option<f64>,
    pub energy_error: Option<f64>,
}

pub fn run(args: &BenchArgs, quiet: bool) -> anyhow::Result<()> {
    anyhow::ensure!(args.runs >= 1, "--runs must be at least 1");
    anyhow::ensure!(
        args.precomputed.is_none() || args.lenses.len() == 1,
        "--precomputed needs exactly one lens (a table is made for one lens)"
    );
    let mut rows = Vec::new();
    for name in &args.lenses {
        rows.extend(bench_lens(name, args, quiet)?);
    }
    print_rows(&rows, args)
}

/// Every aperture, backend and preset of lens `name`: a row each.
fn bench_lens(name: &str, args: &BenchArgs, quiet: bool) -> anyhow::Result<Vec<BenchRow>> {
    let lights = std::slice::from_ref(&args.light);
    let mut rows = Vec::new();
    let sys = args
        .sensor_stack
        .apply(lens_library::load(name, quiet || args.json)?.system)?;
    let table = match &args.precomputed {
        Some(p) => Some(load_precomputed(p, &sys, quiet || args.json)?),
        None => None,
    };
    let frame = frame_for(&sys, args.size);
    let error_frame = frame_for(&sys, args.error_size.unwrap_or(args.size));
    // The lens's interface tables, built once per lens (as a plugin does when the lens
    // is prepared), for every frame's plan.
    let t = Instant::now();
    let lens_tables = LensTables::new(&sys);
    let prepare_ms = t.elapsed().as_secs_f64() * 1e3;
    for &ap in &args.aperture {
        let aperture = ap.aperture()?;
        let reference = if args.error {
            if !quiet
                && !args.json
                && !in_cache(&sys, &aperture, error_frame, lights, args.reflections)
            {
                eprintln!(
                    "{name}: rendering the reference at {}×{} ({ap}) …",
                    error_frame.width, error_frame.height
                );
            }
            let (img, _) =
                reference_for(&sys, &aperture, error_frame, lights, None, args.reflections)?;
            Some(img)
        } else {
            None
        };
        for &choice in &args.backend {
            let mut flare = Flare::open(choice)?;
            for &q in &args.quality {
                let preset = PlanOptions::for_quality(q, table.as_ref());
                let preset = Preset {
                    render: RenderOptions {
                        band_by_band: args.band_by_band,
                        ..RenderOptions::default()
                    },
                    ..Preset::new(PlanOptions {
                        max_downscale: args.max_downscale.unwrap_or(preset.max_downscale),
                        reflections: args.reflections,
                        lens_tables: Some(&lens_tables),
                        ..preset
                    })
                };
                let scene = Scene {
                    starburst: if args.starburst {
                        StarburstMode::On
                    } else {
                        StarburstMode::Off
                    },
                    ..Scene::new(&sys, lights, &aperture, frame)
                };
                let timed = time(&mut flare, &scene, &preset, args.runs)?;
                let error = reference
                    .as_ref()
                    .map(|r| -> anyhow::Result<_> {
                        let scene = Scene {
                            frame: error_frame,
                            starburst: StarburstMode::Off,
                            ..scene
                        };
                        flare.render(&scene, &preset)?;
                        Ok(flare.image().compare(r)?)
                    })
                    .transpose()?;
                let lp = &timed.plans[0];
                let (total, dropped) = lp.energy();
                rows.push(BenchRow {
                    lens: sys.name.clone(),
                    quality: q,
                    aperture: ap,
                    backend: timed.report,
                    mesh_ms: timed.mesh_ms,
                    gpu_ms: timed.gpu_ms,
                    starburst_ms: timed.starburst_ms,
                    reflections: args.reflections,
                    precomputed: table.is_some(),
                    width: frame.width,
                    height: frame.height,
                    ghosts_drawn: lp.ghosts.len(),
                    ghosts_total: lp.ghosts.len() + lp.dropped.len(),
                    dropped_energy_fraction: if total > 0.0 { dropped / total } else { 0.0 },
                    culled_energy_fraction: lp.culled_share,
                    prepare_ms,
                    plan_ms: timed.plan_ms,
                    render_ms: timed.render_ms,
                    frame_ms: timed.frame_ms,
                    error_width: error.map(|_| error_frame.width),
                    error_height: error.map(|_| error_frame.height),
                    relative_rmse: error.map(|c| c.relative_rmse),
                    energy_error: error.map(|c| c.energy_error),
                });
            }
        }
    }
    Ok(rows)
}

/// The rows as JSON, or as a table with the machine's adapters and the bench's settings.
fn print_rows(rows: &[BenchRow], args: &BenchArgs) -> anyhow::Result<()> {
    if args.json {
        println!("{}", serde_json::to_string_pretty(rows)?);
        return Ok(());
    }
    let mut t = Table::new(&[
        "lens",
        "quality",
        "aperture",
        "backend",
        "size",
        "ghosts",
        "dropped",
        "culled",
        "lens ms",
        "plan ms",
        "render ms",
        "frame ms",
        "mesh ms",
        "GPU ms",
        "starburst ms",
        "rel RMSE",
        "energy",
    ]);
    for r in rows {
        let pct = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{:.2}%", 100.0 * v));
        t.row(vec![
            r.lens.clone(),
            r.quality.to_string(),
            r.aperture.to_string(),
            r.backend.backend.clone(),
            format!("{}×{}", r.width, r.height),
            format!("{}/{}", r.ghosts_drawn, r.ghosts_total),
            format!("{:.2}%", 100.0 * r.dropped_energy_fraction),
            format!("{:.2}%", 100.0 * r.culled_energy_fraction),
            format!("{:.1}", r.prepare_ms),
            format!("{:.1}", r.plan_ms),
            format!("{:.1}", r.render_ms),
            format!("{:.1}", r.frame_ms),
            r.mesh_ms.map_or("—".to_string(), |v| format!("{v:.1}")),
            r.gpu_ms.map_or("—".to_string(), |v| format!("{v:.1}")),
            r.starburst_ms
                .map_or("—".to_string(), |v| format!("{v:.1}")),
            pct(r.relative_rmse),
            pct(r.energy_error),
        ]);
    }
    print!("{}", t.render());
    let mut adapters: Vec<String> = rows
        .iter()
        .filter_map(|r| r.backend.adapter.clone())
        .collect();
    adapters.dedup();
    for a in adapters {
        println!("gpu: {a}");
    }
    println!(
        "light {},{}{}{}; lens ms: the lens's interface tables, built once per lens before the runs; medians of {} runs on {} threads; errors against the reference{}",
        args.light.theta_deg,
        args.light.phi_deg,
        if args.reflections == ReflectionOrder::Four {
            "; two- and four-reflection ghosts"
        } else {
            ""
        },
        match &args.precomputed {
            Some(p) => format!("; bounds looked up in {}", p.display()),
            None => String::new(),
        },
        args.runs,
        rayon::current_num_threads(),
        match args.error_size {
            Some((w, h)) if args.error => format!(" at {w}×{h}"),
            _ if args.error => String::new(),
            _ => " not measured (--error)".to_string(),
        }
    );
    Ok(())
}

/// A case's medians over its runs, and the last run's plans and backend report.
struct Timed {
    plan_ms: f64,
    render_ms: f64,
    frame_ms: f64,
    mesh_ms: Option<f64>,
    gpu_ms: Option<f64>,
    starburst_ms: Option<f64>,
    plans: Vec<LightPlan>,
    report: BackendReport,
}

/// Plans and renders `runs` frames of `scene` with `flare`, which keeps its buffers from run
/// to run as a live preview does: on the CPU one frame buffer, its last frame replaced (no
/// clearing pass), the coarse frames kept too; on the GPU the renderer's buffers and targets,
/// each frame read back; the starburst patterns in their cache.
fn time(
    flare: &mut Flare,
    scene: &Scene<'_>,
    preset: &Preset<'_>,
    runs: usize,
) -> anyhow::Result<Timed> {
    let (mut plan_ms, mut render_ms, mut frame_ms) = (vec![], vec![], vec![]);
    let (mut mesh_ms, mut gpu_ms, mut starburst_ms) = (vec![], vec![], vec![]);
    let mut last = None;
    for _ in 0..runs {
        let r = flare.render(scene, preset)?;
        let t = r.timings;
        if flare.backend().is_gpu() {
            let report = flare.backend().report();
            mesh_ms.extend(report.mesh_ms);
            gpu_ms.extend(report.gpu_ms);
        }
        if scene.starburst.starbursts() {
            starburst_ms.push(t.starburst_ms);
        }
        plan_ms.push(t.plan_ms);
        render_ms.push(t.ghosts_ms + t.starburst_ms);
        frame_ms.push(t.total_ms());
        last = Some(r.plans);
    }
    Ok(Timed {
        plan_ms: median(&plan_ms),
        render_ms: median(&render_ms),
        frame_ms: median(&frame_ms),
        mesh_ms: (!mesh_ms.is_empty()).then(|| median(&mesh_ms)),
        gpu_ms: (!gpu_ms.is_empty()).then(|| median(&gpu_ms)),
        starburst_ms: (!starburst_ms.is_empty()).then(|| median(&starburst_ms)),
        plans: last.expect("at least one run"),
        report: flare.backend().report().clone(),
    })
}

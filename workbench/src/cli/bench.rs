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

use clap::Args;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, LensTables, PlanOptions};
use ghost_raytrace::reference::reference_image_of_order;
use ghost_raytrace::scene::{LightSpec, Quality};
use serde::Serialize;

use super::render::{frame_for, parse_downscale, parse_size};
use crate::lens_library;
use crate::precomputed::load_precomputed;
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
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One lens × preset.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub lens: String,
    pub quality: Quality,
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

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

pub fn run(args: &BenchArgs, quiet: bool) -> anyhow::Result<()> {
    anyhow::ensure!(args.runs >= 1, "--runs must be at least 1");
    let lights = std::slice::from_ref(&args.light);
    anyhow::ensure!(
        args.precomputed.is_none() || args.lenses.len() == 1,
        "--precomputed needs exactly one lens (a table is made for one lens)"
    );
    let aperture = Aperture::Circular;
    let mut rows = Vec::new();
    for name in &args.lenses {
        let sys = lens_library::load(name, quiet || args.json)?.system;
        let table = match &args.precomputed {
            Some(p) => Some(load_precomputed(p, &sys, quiet || args.json)?),
            None => None,
        };
        let frame = frame_for(&sys, args.size);
        let error_frame = frame_for(&sys, args.error_size.unwrap_or(args.size));
        let reference = if args.error {
            if !quiet && !args.json {
                eprintln!(
                    "{name}: rendering the reference at {}×{} …",
                    error_frame.width, error_frame.height
                );
            }
            Some(reference_image_of_order(
                &sys,
                &aperture,
                error_frame,
                lights,
                args.reflections,
            )?)
        } else {
            None
        };
        // The lens's interface tables, built once per lens (as a plugin does when the lens
        // is prepared), for every frame's plan.
        let t = Instant::now();
        let lens_tables = LensTables::new(&sys);
        let prepare_ms = t.elapsed().as_secs_f64() * 1e3;
        for &q in &args.quality {
            let preset = PlanOptions::for_quality(q, table.as_ref());
            let opts = PlanOptions {
                max_downscale: args.max_downscale.unwrap_or(preset.max_downscale),
                reflections: args.reflections,
                lens_tables: Some(&lens_tables),
                ..preset
            };
            let (mut plan_ms, mut render_ms, mut frame_ms) = (vec![], vec![], vec![]);
            let mut img = HdrImage::new(frame.width, frame.height);
            let mut last = None;
            let options = ghosts::RenderOptions {
                band_by_band: args.band_by_band,
                ..Default::default()
            };
            let mut scratch = ghosts::RenderScratch::default();
            for _ in 0..args.runs {
                let t0 = Instant::now();
                let plans = plan::plan(&sys, lights, &frame, &opts)?;
                let t1 = Instant::now();
                // Into one frame buffer kept from run to run, as a live preview draws into its
                // window's buffer: its last frame replaced (no clearing pass), the coarse
                // frames kept too.
                ghosts::render_into_reusing(
                    &sys,
                    &aperture,
                    frame,
                    &plans,
                    ghosts::RenderOptions {
                        replace: true,
                        ..options
                    },
                    &mut scratch,
                    &mut img.pixels,
                )?;
                let t2 = Instant::now();
                anyhow::ensure!(!img.has_non_finite(), "non-finite pixels");
                plan_ms.push((t1 - t0).as_secs_f64() * 1e3);
                render_ms.push((t2 - t1).as_secs_f64() * 1e3);
                frame_ms.push((t2 - t0).as_secs_f64() * 1e3);
                last = Some(plans);
            }
            let plans = last.expect("at least one run");
            let lp = &plans[0];
            let (total, dropped) = lp.energy();
            let error = reference
                .as_ref()
                .map(|r| -> anyhow::Result<_> {
                    let plans = plan::plan(&sys, lights, &error_frame, &opts)?;
                    let img = ghosts::render_with(&sys, &aperture, error_frame, &plans, options)?.0;
                    Ok(img.compare(r)?)
                })
                .transpose()?;
            rows.push(BenchRow {
                lens: sys.name.clone(),
                quality: q,
                reflections: args.reflections,
                precomputed: table.is_some(),
                width: frame.width,
                height: frame.height,
                ghosts_drawn: lp.ghosts.len(),
                ghosts_total: lp.ghosts.len() + lp.dropped.len(),
                dropped_energy_fraction: if total > 0.0 { dropped / total } else { 0.0 },
                prepare_ms,
                plan_ms: median(plan_ms),
                render_ms: median(render_ms),
                frame_ms: median(frame_ms),
                error_width: error.map(|_| error_frame.width),
                error_height: error.map(|_| error_frame.height),
                relative_rmse: error.map(|c| c.relative_rmse),
                energy_error: error.map(|c| c.energy_error),
            });
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    let mut t = Table::new(&[
        "lens",
        "quality",
        "size",
        "ghosts",
        "dropped",
        "lens ms",
        "plan ms",
        "render ms",
        "frame ms",
        "rel RMSE",
        "energy",
    ]);
    for r in &rows {
        let pct = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{:.2}%", 100.0 * v));
        t.row(vec![
            r.lens.clone(),
            r.quality.to_string(),
            format!("{}×{}", r.width, r.height),
            format!("{}/{}", r.ghosts_drawn, r.ghosts_total),
            format!("{:.2}%", 100.0 * r.dropped_energy_fraction),
            format!("{:.1}", r.prepare_ms),
            format!("{:.1}", r.plan_ms),
            format!("{:.1}", r.render_ms),
            format!("{:.1}", r.frame_ms),
            pct(r.relative_rmse),
            pct(r.energy_error),
        ]);
    }
    print!("{}", t.render());
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

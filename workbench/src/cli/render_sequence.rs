//! `flarebench render --frames A..B --light-path FILE -o out.####.exr`: a numbered sequence of
//! flare frames for lights moving along their keyframed paths (`crate::light_path`).
//!
//! One [`Flare`] renders every frame, so the lens's interface tables, the backend, the image
//! buffer and the starburst patterns are made once. Each frame is a pure function of its
//! frame number, so a frame rendered alone (`--shard`, or `--frames F..F`) has the same bits
//! as in a full run: the planner's warm start comes not from the frame before but from an
//! anchor, the plan (made without a warm start) of the first frame of the frame's block of
//! [`WARM_START_BLOCK`] frames — blocks counted from frame 0, not from A, so the anchor does
//! not depend on the range either. PNG frames share one exposure: `--exposure-ev`,
//! or the automatic exposure of the brightest frame of all of A..B (a first pass renders every
//! frame to find it; EXR frames are linear and need none).

use std::time::Instant;

use anyhow::Context;
use ghost_raytrace::ghosts::RenderOptions;
use ghost_raytrace::plan::{self, WarmStart};
use ghost_raytrace::scene::LightSpec;
use serde::Serialize;

use super::render::{RenderArgs, ms, write_output};
use crate::flare::compose::StarburstLine;
use crate::flare::{Flare, Preset, Scene, frame_for};
use crate::lens_library;
use crate::light_path::LightPath;
use crate::output::{OutputFormat, ToneMap, ToneOperator};
use crate::precomputed::load_precomputed;
use crate::sequence::{FramePattern, Shard, darkest_exposure, frames_bar as bar};

/// Frames per warm-start anchor: frame `f` plans from the rectangles of frame
/// `WARM_START_BLOCK · ⌊f / WARM_START_BLOCK⌋` (which may lie before A). Within a block a moving light stays
/// near its anchor; a ghost not found near its anchor's rectangle is searched in full.
pub const WARM_START_BLOCK: u64 = 8;

/// One light of a frame, as rendered.
#[derive(Debug, Serialize)]
struct FrameLight {
    theta_deg: f64,
    phi_deg: f64,
    intensity: f64,
}

/// What one frame was.
#[derive(Debug, Serialize)]
struct FrameRecord {
    frame: u64,
    output: String,
    lights: Vec<FrameLight>,
    /// Ghosts drawn over every light.
    ghosts_drawn: usize,
    /// Each light's starburst: where its chief ray lands.
    starbursts: Vec<StarburstLine>,
    /// Sum of the linear image, per channel.
    image_sum_rgb: [f64; 3],
}

/// The report of a sequence (`--json`).
#[derive(Debug, Serialize)]
struct SequenceReport {
    lens: String,
    width: usize,
    height: usize,
    quality: ghost_raytrace::scene::Quality,
    output: String,
    first: u64,
    last: u64,
    shard: [u64; 2],
    /// The PNG frames' exposure (stops), null for EXR.
    exposure_ev: Option<f32>,
    /// The frame the automatic exposure was taken from (the brightest), if automatic.
    exposure_frame: Option<u64>,
    frames: Vec<FrameRecord>,
    /// Rendering and writing this process's frames (s), and frames per second.
    seconds: f64,
    frames_per_second: f64,
}

/// Shortest of `x` to 4 decimals (`2`, `2.5`, `3.3333`).
fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

pub fn run(args: &RenderArgs, quiet: bool) -> anyhow::Result<()> {
    let range = args.frames.expect("run only with --frames");
    let shard = args.shard.unwrap_or(Shard::ALL);
    let path_file = args
        .light_path
        .as_ref()
        .expect("clap requires --light-path with --frames");
    let quiet = quiet || args.json;
    let pattern = FramePattern::parse(&args.output)?;
    let format = OutputFormat::from_path(&pattern.path(range.first))?;
    let path = LightPath::read(path_file)?;

    let loaded = lens_library::load(&args.lens, quiet)?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let frame = frame_for(sys, args.size.unwrap_or((1920, 1080)));
    let (starburst_settings, dust) = args.starburst.load()?;
    let aperture = args.iris.aperture()?;
    let table = match &args.precomputed {
        Some(p) => Some(load_precomputed(p, sys, quiet)?),
        None => None,
    };
    // Every frame's lights, checked before anything is rendered.
    let lights: Vec<(u64, Vec<LightSpec>)> = range
        .frames()
        .map(|f| Ok((f, path.lights_at(f as f64)?)))
        .collect::<anyhow::Result<_>>()
        .with_context(|| format!("light path `{}`", path_file.display()))?;
    let lights_of = |f: u64| &lights[(f - range.first) as usize].1;

    let plan_opts = args.plan_options(table.as_ref());
    let warm_start = table.is_none() && args.starburst.starburst.ghosts();
    let preset = Preset {
        render: RenderOptions {
            trace_f64: args.f64,
            band_by_band: args.band_by_band,
            ..RenderOptions::default()
        },
        lens_tables: true,
        warm_start,
        ..Preset::new(plan_opts)
    };
    let mut flare = Flare::open(args.backend)?;
    let mut anchor: Option<(u64, Vec<WarmStart>)> = None;
    // Renders frame `f` into `flare`, from its block's anchor.
    let mut render = |flare: &mut Flare, f: u64, exposure: bool| {
        let lights = lights_of(f);
        if warm_start {
            let a = f / WARM_START_BLOCK * WARM_START_BLOCK;
            if anchor.as_ref().is_none_or(|(at, _)| *at != a) {
                let anchor_lights = path
                    .lights_at(a as f64)
                    .with_context(|| format!("light path `{}`", path_file.display()))?;
                let opts = plan::PlanOptions {
                    lens_tables: Some(flare.prepare(sys)),
                    warm_start: None,
                    ..plan_opts
                };
                let plans = plan::plan(sys, &anchor_lights, &frame, &opts)
                    .with_context(|| format!("frame {a}"))?;
                anchor = Some((a, plans.iter().map(WarmStart::of).collect()));
            }
            let (_, warm) = anchor.as_ref().expect("just made");
            flare.set_warm_start(warm.clone());
        }
        let scene = Scene {
            starburst: args.starburst.starburst,
            starburst_settings,
            dust: dust.as_ref(),
            ..Scene::new(sys, lights, &aperture, frame)
        };
        let preset = Preset { exposure, ..preset };
        flare
            .render(&scene, &preset)
            .with_context(|| format!("frame {f}"))
    };

    // One exposure for every PNG frame: given, or the brightest frame's of all of A..B
    // (whichever shard this is), so every shard finds the same.
    let t = Instant::now();
    let (exposure_ev, exposure_frame) = match (format, args.exposure_ev) {
        (OutputFormat::Png, Some(ev)) => (Some(ev), None),
        (OutputFormat::Png, None) => {
            let (ev, f) = darkest_exposure(range, bar(quiet, range.len(), "exposure"), |f| {
                Ok(render(&mut flare, f, true)?.exposure_ev.unwrap_or(0.0))
            })?;
            (Some(ev), Some(f))
        }
        _ => (None, None),
    };
    let exposure_s = t.elapsed().as_secs_f64();
    let tone = ToneMap {
        exposure_ev: exposure_ev.unwrap_or(0.0),
        operator: args.tone.unwrap_or(ToneOperator::Aces),
    };

    if let Some(dir) = pattern.path(range.first).parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("could not create `{}`", dir.display()))?;
    }
    let own: Vec<u64> = shard.frames(range).collect();
    let bar = bar(quiet, own.len() as u64, "render");
    let t = Instant::now();
    let mut records = Vec::new();
    for &f in &own {
        let out = render(&mut flare, f, false)?;
        let file = pattern.path(f);
        let image_sum_rgb = flare.image().sum();
        write_output(&mut flare, None, &tone, &file, args.exr_half)
            .with_context(|| format!("frame {f}"))?;
        records.push(FrameRecord {
            frame: f,
            output: file.display().to_string(),
            lights: lights_of(f)
                .iter()
                .map(|l| FrameLight {
                    theta_deg: l.theta_deg,
                    phi_deg: l.phi_deg,
                    intensity: l.intensity,
                })
                .collect(),
            ghosts_drawn: out.ghosts_drawn(),
            starbursts: out.starbursts,
            image_sum_rgb,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = ms(t) / 1e3;
    let fps = own.len() as f64 / seconds;

    let report = SequenceReport {
        lens: sys.name.clone(),
        width: frame.width,
        height: frame.height,
        quality: args.quality,
        output: args.output.display().to_string(),
        first: range.first,
        last: range.last,
        shard: [shard.index, shard.count],
        exposure_ev,
        exposure_frame,
        frames: records,
        seconds,
        frames_per_second: fps,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    if args.report {
        for r in &report.frames {
            let lights: Vec<String> = r
                .lights
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    format!(
                        "light {i} at θ {}°, φ {}°, intensity {}",
                        short(l.theta_deg),
                        short(l.phi_deg),
                        short(l.intensity)
                    )
                })
                .collect();
            println!(
                "frame {} → {}: {}; {} ghosts drawn",
                r.frame,
                r.output,
                lights.join("; "),
                r.ghosts_drawn
            );
        }
    }
    let shard_text = if shard.count > 1 {
        format!(", shard {}/{}", shard.index, shard.count)
    } else {
        String::new()
    };
    println!(
        "{} → {}: {} frames of {}..{}{shard_text} ({}×{}, quality {:?}) in {:.2} s, {:.2} frames/s",
        sys.name,
        args.output.display(),
        own.len(),
        range.first,
        range.last,
        frame.width,
        frame.height,
        args.quality,
        seconds,
        fps
    );
    match (exposure_ev, exposure_frame) {
        (Some(ev), Some(f)) => println!(
            "exposure {ev:.3} EV for every frame: automatic, from frame {f} (the brightest; \
             that pass took {exposure_s:.2} s)"
        ),
        (Some(ev), None) => println!("exposure {ev:.3} EV for every frame (--exposure-ev)"),
        _ => {}
    }
    Ok(())
}

//! `flarebench apply plate.####.exr --lens L --frames A..B -o out.####.exr`: a lens's flare
//! added to every frame of a numbered image sequence, each frame as `apply` does it alone
//! ([`super::apply::apply_to`]) with what the sequence shares made once:
//!
//! - **One bounds table**: `--precomputed FILE`, or a table built for the lens at the start
//!   as `flarebench precompute` builds it by default (precise bounds every 0.25° from 0 to
//!   the film diagonal's field plus 10°, widened to the frame's diagonal with
//!   `--film-width-mm`). Every frame's lights look their ghosts' bounds up in it.
//! - **One exposure** for the PNG frames: `--exposure-ev`; else, for EXR plates, the
//!   automatic exposure of the brightest plate of all of A..B (the lowest of the plates'
//!   `auto_exposure`, found by reading every plate before anything is drawn, whichever shard
//!   this is); for 8-bit plates 0, their own values (as `apply` on one image). EXR frames are
//!   linear and need none.
//! - One renderer ([`Flare`]): backend, image buffer and starburst patterns.
//!
//! Each frame depends on its plate and these alone, so a frame written by any shard, or by
//! `apply` on that plate with the same `--precomputed` table and `--exposure-ev`, has the
//! same bytes. Every plate is checked to exist before the first is drawn.

use std::time::Instant;

use anyhow::{Context, bail};
use flarebench_sdk::ghost::bounds::BoundsMode;
use flarebench_sdk::ghost::table::{BoundsTable, TableOptions, angle_steps, default_max_angle_deg};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use super::apply::{ApplyArgs, apply_to, frame_of};
use crate::flare::Flare;
use crate::flare::exposure::auto_exposure;
use crate::input_image::read_input_image;
use crate::lens_library;
use crate::output::{OutputFormat, ToneMap, ToneOperator, save_image_as};
use crate::precomputed::load_precomputed;
use crate::sequence::{FramePattern, Shard, darkest_exposure, frames_bar as bar};

/// Angle step of the table built for a sequence (degrees): `precompute`'s default.
const TABLE_STEP_DEG: f64 = 0.25;

/// What one frame was.
#[derive(Debug, Serialize)]
struct FrameRecord {
    frame: u64,
    image: String,
    output: String,
    lights: usize,
    ghosts_drawn: usize,
}

/// The report of a sequence (`--json`).
#[derive(Debug, Serialize)]
struct SequenceReport {
    lens: String,
    image: String,
    output: String,
    width: usize,
    height: usize,
    first: u64,
    last: u64,
    shard: [u64; 2],
    /// The PNG frames' exposure (stops), null for EXR.
    exposure_ev: Option<f32>,
    /// The plate the automatic exposure was taken from (the brightest), if automatic.
    exposure_frame: Option<u64>,
    /// The bounds table: the file given, or `built` with the time it took (s).
    table: String,
    table_seconds: f64,
    frames: Vec<FrameRecord>,
    /// Drawing and writing this process's frames (s), and frames per second.
    seconds: f64,
    frames_per_second: f64,
}

pub fn run(args: &ApplyArgs, quiet: bool) -> anyhow::Result<()> {
    let range = args.frames.expect("run only with --frames");
    let shard = args.shard.unwrap_or(Shard::ALL);
    let quiet = quiet || args.json;
    let plates = FramePattern::parse_as(&args.image, "image")?;
    let outputs = FramePattern::parse(&args.output)?;
    let format = OutputFormat::from_path(&outputs.path(range.first))?;
    let own: Vec<u64> = shard.frames(range).collect();
    if own.is_empty() {
        if !quiet {
            println!(
                "shard {}/{} holds no frame of {}..{}",
                shard.index, shard.count, range.first, range.last
            );
        }
        return Ok(());
    }

    // Every plate this run reads is there before anything is drawn.
    let scan_all = format == OutputFormat::Png && args.exposure_ev.is_none();
    let needed: Vec<u64> = if scan_all {
        range.frames().collect()
    } else {
        own.clone()
    };
    for &f in &needed {
        let p = plates.path(f);
        if !p.is_file() {
            bail!("frame {f}: no image `{}`", p.display());
        }
    }

    let loaded = lens_library::load(&args.lens, quiet)?;
    let system = args.sensor_stack.apply(loaded.system.clone())?;
    let sys = &system;
    let read = |f: u64| {
        let p = plates.path(f);
        read_input_image(&p).with_context(|| format!("frame {f}"))
    };
    let first = read(own[0])?;

    // One exposure for every PNG frame.
    let t = Instant::now();
    let (exposure_ev, exposure_frame) = match (format, args.exposure_ev) {
        (OutputFormat::Png, Some(ev)) => (Some(ev), None),
        (OutputFormat::Png, None) if first.hdr => {
            let (ev, f) = darkest_exposure(range, bar(quiet, range.len(), "exposure"), |f| {
                Ok(auto_exposure(&read(f)?.image))
            })?;
            (Some(ev), Some(f))
        }
        (OutputFormat::Png, None) => (Some(0.0), None),
        _ => (None, None),
    };
    let exposure_s = t.elapsed().as_secs_f64();
    let tone = ToneMap {
        exposure_ev: exposure_ev.unwrap_or(0.0),
        operator: args.tone.unwrap_or(ToneOperator::Clamp),
    };

    // One bounds table.
    let t = Instant::now();
    let (table, table_name) = match &args.precomputed {
        Some(p) => (load_precomputed(p, sys, quiet)?, p.display().to_string()),
        None => {
            let frame = frame_of(args, sys, &first.image)?;
            let efl = analyse(sys, LAMBDA_D_NM)
                .context("paraxial analysis")?
                .efl_mm
                .abs();
            let half_diag = 0.5 * frame.film_width_mm.hypot(frame.film_height_mm);
            let field = ((half_diag / efl).atan().to_degrees() + 10.0).min(89.0);
            let max = default_max_angle_deg(sys)
                .context("paraxial analysis")?
                .max(field);
            let angles = angle_steps(max, TABLE_STEP_DEG);
            let bar = if quiet {
                ProgressBar::hidden()
            } else {
                ProgressBar::new(0).with_style(
                    ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ghosts, {elapsed}")
                        .expect("valid template")
                        .progress_chars("=> "),
                )
            };
            bar.set_message("bounds table");
            let table = BoundsTable::compute_with(
                sys,
                &angles,
                BoundsMode::Precise,
                550.0,
                &TableOptions::default(),
                &|n| bar.set_length(n as u64),
                &|| bar.inc(1),
            );
            bar.finish_and_clear();
            (table, "built".to_string())
        }
    };
    let table_s = t.elapsed().as_secs_f64();

    if let Some(dir) = outputs.path(range.first).parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("could not create `{}`", dir.display()))?;
    }
    let mut flare = Flare::open(args.backend)?;
    let size = (first.image.width, first.image.height);
    let mut first = Some(first);
    let bar = bar(quiet, own.len() as u64, "apply");
    let t = Instant::now();
    let mut records = Vec::with_capacity(own.len());
    for &f in &own {
        let input = match first.take() {
            Some(i) => i,
            None => read(f)?,
        };
        let plate = plates.path(f);
        anyhow::ensure!(
            (input.image.width, input.image.height) == size,
            "frame {f}: `{}` is {}×{}, frame {} {}×{}",
            plate.display(),
            input.image.width,
            input.image.height,
            own[0],
            size.0,
            size.1
        );
        let applied = apply_to(args, sys, &input, Some(&table), &mut flare)
            .with_context(|| format!("frame {f} (`{}`)", plate.display()))?;
        let file = outputs.path(f);
        save_image_as(&applied.out, &file, &tone, args.precision())
            .with_context(|| format!("frame {f}"))?;
        records.push(FrameRecord {
            frame: f,
            image: plate.display().to_string(),
            output: file.display().to_string(),
            lights: applied.found.lights.len(),
            ghosts_drawn: applied.rendered.ghosts_drawn(),
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = t.elapsed().as_secs_f64();
    let fps = own.len() as f64 / seconds;

    let report = SequenceReport {
        lens: sys.name.clone(),
        image: args.image.display().to_string(),
        output: args.output.display().to_string(),
        width: size.0,
        height: size.1,
        first: range.first,
        last: range.last,
        shard: [shard.index, shard.count],
        exposure_ev,
        exposure_frame,
        table: table_name,
        table_seconds: table_s,
        frames: records,
        seconds,
        frames_per_second: fps,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    if quiet {
        return Ok(());
    }
    let shard_text = if shard.count > 1 {
        format!(", shard {}/{}", shard.index, shard.count)
    } else {
        String::new()
    };
    let table_text = match &args.precomputed {
        Some(_) => format!("bounds from {}", report.table),
        None => format!("bounds table built in {table_s:.2} s"),
    };
    println!(
        "{} → {}: {} frames of {}..{}{shard_text} ({}×{}, quality {:?}; {table_text}) in {:.2} s, \
         {:.2} frames/s",
        sys.name,
        args.output.display(),
        own.len(),
        range.first,
        range.last,
        size.0,
        size.1,
        args.quality,
        seconds,
        fps
    );
    // The exposure in full (shortest round-trip form): given as --exposure-ev to a later run
    // or shard, it is the same f32.
    match (exposure_ev, exposure_frame) {
        (Some(ev), Some(f)) => println!(
            "exposure {ev} EV for every frame: automatic, from frame {f} (the brightest plate; \
             that pass took {exposure_s:.2} s)"
        ),
        (Some(ev), None) if args.exposure_ev.is_some() => {
            println!("exposure {ev} EV for every frame (--exposure-ev)")
        }
        (Some(ev), None) => println!("exposure {ev} EV for every frame (8-bit plates)"),
        _ => {}
    }
    Ok(())
}

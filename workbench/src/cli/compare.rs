//! `flarebench compare`: one scene rendered by several flare algorithm plugins, side by side
//! with the reference renderer, their differences from it, and a table of median time, error
//! against the reference, items drawn and peak memory. The plugins' meshes are drawn by the
//! backend `--backend` chooses (the CPU rasterizer or the GPU), with exact coverage either way.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::abi::host::LoadedPlugin;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::scene::LightSpec;
use serde::Serialize;

use super::render::{IrisArgs, parse_size};
pub(crate) use crate::algo_spec::Algo;
use crate::file_watch::WatchedFile;
use crate::flare::exposure::auto_exposure;
use crate::flare::{BackendChoice, BackendReport, GhostBackend};
use crate::label;
use crate::lens_library;
use crate::output::{ToneMap, ToneOperator, save_image};
use crate::reference_file::{ReferenceSource, in_cache, reference_for};
use crate::report::ErrorReport;
use crate::stats::median;
use crate::sweep::points::split_algo as split_spec;
use crate::table::Table;
use flarebench_sdk::ghost::ReflectionOrder;

mod watch;

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Lens file or the name of a bundled lens.
    pub lens: String,
    /// A light at infinity: THETA,PHI[,INTENSITY[,KELVIN]] (degrees; repeatable). PHI turns
    /// counter-clockwise from the image's downward direction: 0 images the light below the
    /// centre, 90 right of it, 180 above, 270 left.
    #[arg(long = "light", required = true, value_parser = LightSpec::parse)]
    pub lights: Vec<LightSpec>,
    /// An algorithm: a plugin name (or library path), optionally with parameters,
    /// NAME:key=value,key=value. Repeat to compare several (the same plugin may appear twice
    /// with different parameters).
    #[arg(long = "algo", required = true)]
    pub algos: Vec<String>,
    /// Side-by-side image (.png or .exr); the differences go to the same name with `-diff`.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Renders per algorithm; the table gives the median time.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Size of each tile in pixels, WxH (the frame spans the film's width).
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    pub size: (usize, usize),
    #[command(flatten)]
    pub iris: IrisArgs,
    /// Also load this plugin library (repeatable).
    #[arg(long = "plugin")]
    pub plugins: Vec<PathBuf>,
    /// Keep the reference in this OpenEXR file: read it when it holds this scene's reference,
    /// else render it and write it there (as `render --reference-file`).
    #[arg(long, value_name = "FILE", conflicts_with = "no_reference")]
    pub reference_file: Option<PathBuf>,
    /// Skip the reference renderer (no error figures, no difference image).
    #[arg(long)]
    pub no_reference: bool,
    /// Print the results as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Where the plugins' meshes are drawn: auto (a hardware GPU if there is one, else the
    /// CPU), cpu, or gpu (any adapter, a software one such as lavapipe included); the
    /// plugins' own pixels are theirs either way. docs/plugins.md.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// After the comparison, watch the plugins' library files and the lens file: when one is
    /// rebuilt or saved, load it afresh (beside the old, which stays loaded) and compare again.
    /// A library that fails to load leaves the previous one in use, with the error shown.
    /// Ctrl-C ends it. With --json, one JSON object per line and event.
    #[arg(long)]
    pub watch: bool,
    /// With --watch: end after this many changes (reloads and failed reloads), for tests.
    #[arg(long, hide = true, requires = "watch")]
    pub watch_events: Option<u32>,
    #[command(flatten)]
    pub sensor_stack: crate::sensor_stack::SensorStackArgs,
}

/// One algorithm's results.
#[derive(Debug, Serialize)]
pub struct AlgoResult {
    /// As given to `--algo`.
    pub spec: String,
    pub plugin: String,
    pub path: String,
    /// Every parameter's value (defaults included), as text.
    pub params: Vec<(String, String)>,
    pub prepare_ms: f64,
    /// Each run's render time (ms), in order.
    pub times_ms: Vec<f64>,
    pub median_ms: f64,
    /// Error against the reference (none without it, or when the render failed).
    pub error: Option<ErrorReport>,
    pub items_drawn: u32,
    pub mesh_triangles: usize,
    /// The process's peak resident memory during this algorithm's renders (MiB), from Linux's
    /// VmHWM after resetting it; none where that is not available.
    pub peak_rss_mib: Option<f64>,
    /// Why the algorithm failed, if it did (the others still run).
    pub failure: Option<String>,
}

/// The whole comparison (`--json`).
#[derive(Debug, Serialize)]
pub struct CompareReport {
    pub lens: String,
    pub width: usize,
    pub height: usize,
    pub runs: u32,
    pub reference_ms: Option<f64>,
    pub output: String,
    pub difference_output: Option<String>,
    /// What drew the plugins' meshes (`backend`: `cpu` or `gpu`, with the adapter).
    pub backend: BackendReport,
    pub algorithms: Vec<AlgoResult>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Resets the process's peak resident set size (Linux ≥ 4.0: `5` to `/proc/self/clear_refs`).
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The process's peak resident set size since the last reset (MiB).
fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Runs one algorithm: prepare, `runs` renders, its mesh drawn by `backend`.
fn run_algo(
    algo: &Algo,
    args: &CompareArgs,
    lens: &flarebench_sdk::LensSystem,
    scene: &Scene,
    backend: &mut GhostBackend,
) -> (AlgoResult, Option<HdrImage>) {
    let spec = algo.spec.as_str();
    let (name, param_text) = split_spec(spec);
    let mut r = AlgoResult {
        spec: spec.to_string(),
        plugin: name.to_string(),
        path: String::new(),
        params: Vec::new(),
        prepare_ms: 0.0,
        times_ms: Vec::new(),
        median_ms: f64::NAN,
        error: None,
        items_drawn: 0,
        mesh_triangles: 0,
        peak_rss_mib: None,
        failure: None,
    };
    let mut run = |r: &mut AlgoResult| -> anyhow::Result<HdrImage> {
        let plugin: &LoadedPlugin = algo.plugin.as_ref().map_err(|e| anyhow::anyhow!("{e}"))?;
        r.plugin = plugin.name.clone();
        r.path = plugin.path.display().to_string();
        let values =
            parse_values(&plugin.params, param_text).with_context(|| format!("--algo {spec}"))?;
        r.params = plugin
            .params
            .iter()
            .zip(&values)
            .map(|(p, &v)| (p.name.clone(), p.format_value(v)))
            .collect();
        let mut inst = plugin.instantiate()?;
        let t = Instant::now();
        inst.prepare(lens)?;
        r.prepare_ms = ms(t);
        let rss = reset_peak_rss();
        // One buffer for every run, as an interactive host keeps it between frames.
        let mut image = HdrImage::new(0, 0);
        for _ in 0..args.runs {
            let t = Instant::now();
            let out = backend.render_plugin(&mut inst, scene, &values, &mut image)?;
            r.times_ms.push(ms(t));
            r.items_drawn = out.items_drawn;
            r.mesh_triangles = out.mesh_triangles;
        }
        r.peak_rss_mib = if rss { peak_rss_mib() } else { None };
        r.median_ms = median(&r.times_ms);
        Ok(image)
    };
    match run(&mut r) {
        Ok(img) => (r, Some(img)),
        Err(e) => {
            r.failure = Some(format!("{e:#}"));
            (r, None)
        }
    }
}

/// Height of the label strip above each tile (pixels) and the font scale.
const LABEL_SCALE: usize = 2;
const LABEL_STRIP: usize = label::GLYPH_H * LABEL_SCALE + 6;

/// Tiles side by side, each under its label; `white` is the linear value drawn for text.
fn side_by_side(tiles: &[(String, &HdrImage)], w: usize, h: usize, white: f32) -> HdrImage {
    let mut out = HdrImage::new(
        tiles.len() * w + (tiles.len().saturating_sub(1)) * 2,
        h + LABEL_STRIP,
    );
    for (i, (text, img)) in tiles.iter().enumerate() {
        let x0 = i * (w + 2);
        label::draw(&mut out, x0 + 3, 3, text, LABEL_SCALE, [white; 3]);
        for y in 0..h {
            for x in 0..w {
                if let (Some(p), Some(q)) = (img.get(x, y), out.get_mut(x0 + x, y + LABEL_STRIP)) {
                    *q = p;
                }
            }
        }
    }
    out
}

/// `|a − b|` per channel.
fn difference(a: &HdrImage, b: &HdrImage) -> HdrImage {
    let mut d = HdrImage::new(a.width, a.height);
    for ((o, p), q) in d.pixels.iter_mut().zip(&a.pixels).zip(&b.pixels) {
        *o = [
            (p[0] - q[0]).abs(),
            (p[1] - q[1]).abs(),
            (p[2] - q[2]).abs(),
        ];
    }
    d
}

/// `out.png` → `out-diff.png`.
fn diff_path(p: &Path) -> PathBuf {
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match p.extension() {
        Some(e) => format!("{stem}-diff.{}", e.to_string_lossy()),
        None => format!("{stem}-diff"),
    };
    p.with_file_name(name)
}

/// The lens, the scene and the reference of a comparison (made again when the lens file
/// changes under `--watch`).
#[derive(Debug)]
pub(crate) struct Setup {
    pub sys: flarebench_sdk::LensSystem,
    pub scene: Scene,
    pub reference: Option<HdrImage>,
    pub reference_ms: Option<f64>,
}

impl Setup {
    /// Loads the lens and renders (or reads) the reference.
    pub(crate) fn new(args: &CompareArgs, quiet: bool) -> anyhow::Result<Setup> {
        let loaded = lens_library::load(&args.lens, quiet || args.json)?;
        let sys = args.sensor_stack.apply(loaded.system)?;
        let (w, h) = args.size;
        let frame = Frame {
            width: w,
            height: h,
            film_width_mm: sys.film_width_mm,
            film_height_mm: sys.film_width_mm * h as f64 / w as f64,
        };
        let aperture = args.iris.aperture()?;
        let scene = Scene {
            lights: args.lights.iter().map(LightSpec::scene_light).collect(),
            frame,
            aperture: aperture.clone(),
        };
        let (reference, reference_ms) = if args.no_reference {
            (None, None)
        } else {
            let file = args.reference_file.as_deref();
            let ready = match file {
                Some(f) => f.exists(),
                None => in_cache(&sys, &aperture, frame, &args.lights, ReflectionOrder::Two),
            };
            if !quiet && !args.json && !ready {
                eprintln!("rendering the reference …");
            }
            let t = Instant::now();
            let (img, source) = reference_for(
                &sys,
                &aperture,
                frame,
                &args.lights,
                file,
                ReflectionOrder::Two,
            )?;
            if !quiet && !args.json && source != ReferenceSource::Rendered {
                eprintln!("reference {source}");
            }
            (Some(img), Some(ms(t)))
        };
        Ok(Setup {
            sys,
            scene,
            reference,
            reference_ms,
        })
    }
}

/// Renders every algorithm, writes the side-by-side and difference images, and returns the
/// report.
pub(crate) fn compare(
    args: &CompareArgs,
    setup: &Setup,
    algos: &[Algo],
    backend: &mut GhostBackend,
    quiet: bool,
) -> anyhow::Result<CompareReport> {
    let (w, h) = args.size;
    let reference = &setup.reference;
    let mut results = Vec::new();
    let mut images = Vec::new();
    for algo in algos {
        if !quiet && !args.json {
            eprintln!("{} …", algo.spec);
        }
        let (mut r, img) = run_algo(algo, args, &setup.sys, &setup.scene, backend);
        if let (Some(img), Some(reference)) = (&img, reference) {
            let c = img.compare(reference)?;
            r.error = Some(ErrorReport {
                relative_rmse: c.relative_rmse,
                relative_l1: c.relative_l1,
                energy_error: c.energy_error,
            });
        }
        results.push(r);
        images.push(img);
    }

    // Common exposure: the reference's, else the first image's.
    let base = reference.as_ref().or(images.iter().flatten().next());
    let exposure_ev = base.map(auto_exposure).unwrap_or(0.0);
    // Text far above the white point: white after any tone curve.
    let white = 16.0 * (-exposure_ev).exp2();
    let tone = ToneMap {
        exposure_ev,
        operator: ToneOperator::Aces,
    };
    let mut tiles: Vec<(String, &HdrImage)> = Vec::new();
    if let Some(r) = reference {
        tiles.push(("reference".into(), r));
    }
    for (r, img) in results.iter().zip(&images) {
        if let Some(img) = img {
            tiles.push((r.spec.clone(), img));
        }
    }
    if !tiles.is_empty() {
        save_image(&side_by_side(&tiles, w, h, white), &args.output, &tone)?;
    }
    let mut difference_output = None;
    if let Some(reference) = reference {
        let diffs: Vec<(String, HdrImage)> = results
            .iter()
            .zip(&images)
            .filter_map(|(r, img)| {
                Some((
                    format!("{} - reference", r.spec),
                    difference(img.as_ref()?, reference),
                ))
            })
            .collect();
        if !diffs.is_empty() {
            let tiles: Vec<(String, &HdrImage)> =
                diffs.iter().map(|(s, i)| (s.clone(), i)).collect();
            let path = diff_path(&args.output);
            save_image(&side_by_side(&tiles, w, h, white), &path, &tone)?;
            difference_output = Some(path.display().to_string());
        }
    }
    Ok(CompareReport {
        lens: setup.sys.name.clone(),
        width: w,
        height: h,
        runs: args.runs,
        reference_ms: setup.reference_ms,
        output: args.output.display().to_string(),
        difference_output,
        backend: backend.report().clone(),
        algorithms: results,
    })
}

pub fn run(args: &CompareArgs, quiet: bool) -> anyhow::Result<()> {
    // The lens file's version before it is read, so a save during the first comparison is seen.
    let lens_watch = if args.watch {
        Some(WatchedFile::new(&lens_library::resolve(&args.lens)?))
    } else {
        None
    };
    let setup = Setup::new(args, quiet)?;
    let mut backend = GhostBackend::open(args.backend)?;
    let algos: Vec<Algo> = args
        .algos
        .iter()
        .map(|spec| Algo::resolve(spec, &args.plugins, args.watch))
        .collect();
    let report = compare(args, &setup, &algos, &mut backend, quiet)?;
    if let Some(lens_watch) = lens_watch {
        return watch::watch(args, setup, lens_watch, algos, backend, &report, quiet);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", text(&report));
    }
    let failed = report.failed();
    if failed > 0 {
        bail!(
            "{failed} of {} algorithms failed (see above)",
            report.algorithms.len()
        );
    }
    Ok(())
}

impl CompareReport {
    /// How many algorithms failed.
    pub fn failed(&self) -> usize {
        self.algorithms
            .iter()
            .filter(|r| r.failure.is_some())
            .count()
    }
}

pub(crate) fn text(r: &CompareReport) -> String {
    let mut s = format!(
        "{} ({}×{}), {} run{} each",
        r.lens,
        r.width,
        r.height,
        r.runs,
        if r.runs == 1 { "" } else { "s" }
    );
    if let Some(t) = r.reference_ms {
        s.push_str(&format!("; reference {t:.1} ms"));
    }
    s.push('\n');
    // The first line of the backend's report, `backend: gpu on <adapter> (…)`.
    if let Some(line) = r.backend.text().lines().next() {
        let what = line.strip_prefix("backend: ").unwrap_or(line);
        s.push_str(&format!("plugin meshes drawn by: {what}\n"));
    }
    let mut t = Table::new(&[
        "algorithm",
        "median ms",
        "rel RMSE",
        "rel L1",
        "energy",
        "drawn",
        "peak MiB",
        "status",
    ]);
    for a in &r.algorithms {
        let pct = |v: f64| format!("{:.3}%", 100.0 * v);
        t.row(vec![
            a.spec.clone(),
            if a.median_ms.is_finite() {
                format!("{:.2}", a.median_ms)
            } else {
                "-".into()
            },
            a.error
                .as_ref()
                .map_or("-".into(), |e| pct(e.relative_rmse)),
            a.error.as_ref().map_or("-".into(), |e| pct(e.relative_l1)),
            a.error
                .as_ref()
                .map_or("-".into(), |e| format!("{:+.3}%", 100.0 * e.energy_error)),
            a.items_drawn.to_string(),
            a.peak_rss_mib.map_or("-".into(), |m| format!("{m:.0}")),
            if a.failure.is_some() {
                "failed".into()
            } else {
                "ok".into()
            },
        ]);
    }
    s.push_str(&t.render());
    for a in &r.algorithms {
        if let Some(f) = &a.failure {
            s.push_str(&format!("{}: {f}\n", a.spec));
        }
    }
    s.push_str(&format!("wrote {}", r.output));
    if let Some(d) = &r.difference_output {
        s.push_str(&format!(" and {d}"));
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn algorithm_specs_split_at_the_first_colon() {
        assert_eq!(split_spec("ghost-raytrace"), ("ghost-raytrace", ""));
        assert_eq!(
            split_spec("g:quality=fast,bands=3"),
            ("g", "quality=fast,bands=3")
        );
        assert_eq!(
            diff_path(Path::new("a/out.png")),
            Path::new("a/out-diff.png")
        );
    }

    /// The table names what drew the plugins' meshes, with the GPU's adapter (what
    /// workbench/tests/plugins.rs's GPU comparison reports in JSON).
    #[test]
    fn the_table_says_which_backend_drew_the_meshes() {
        let report = CompareReport {
            lens: "heliar-tronnier".into(),
            width: 64,
            height: 36,
            runs: 1,
            reference_ms: None,
            output: "cmp.exr".into(),
            difference_output: None,
            backend: BackendReport {
                backend: "gpu".into(),
                adapter: Some("llvmpipe".into()),
                driver: Some("Mesa".into()),
                api: Some("Vulkan".into()),
                software_adapter: true,
                ..BackendReport::default()
            },
            algorithms: Vec::new(),
        };
        let t = text(&report);
        assert!(
            t.contains("plugin meshes drawn by: gpu on llvmpipe (Mesa, Vulkan, software)\n"),
            "{t}"
        );
    }
}

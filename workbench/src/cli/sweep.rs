//! `flarebench sweep`: error against run time over lenses, lights, algorithms, presets and the
//! planner's thresholds, written as CSV, JSON, plots, contact sheets and an `index.html`
//! (`crate::sweep`; docs/accuracy.md § Sweeps).

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use anyhow::Context;
use clap::Args;
use flarebench_sdk::abi::params::{ParamInfo, parse_values};
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::plan::LensTables;
use ghost_raytrace::reference::reference_key;
use ghost_raytrace::scene::{LightSpec, Quality};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use super::render::{IrisArgs, parse_size};
use crate::flare::exposure::auto_exposure;
use crate::flare::{BackendChoice, Flare, frame_for};
use crate::lens_library;
use crate::output::{ToneMap, ToneOperator, save_image};
use crate::sweep::measure::{self, CaseScene, params_of};
use crate::sweep::points::{self, Point, Vary, split_algo};
use crate::sweep::sheet::{THUMB_WIDTH, Tile, contact_sheet, thumbnail};
use crate::sweep::store::Store;
use crate::sweep::{
    CaseInfo, CaseResult, CellResult, ReferenceRecord, aperture_text, plot, report,
};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Lens files or bundled lens names.
    #[arg(default_values_t = ["heliar-tronnier".to_string(), "nikon-zoom-short".to_string()])]
    pub lenses: Vec<String>,
    /// A light: THETA,PHI[,INTENSITY[,KELVIN]] (degrees; repeatable: each light is a case of
    /// its own, with its own plot). Default: 10,30.
    #[arg(long = "light", value_parser = LightSpec::parse)]
    pub lights: Vec<LightSpec>,
    /// Quality presets of the built-in renderer (ghost-raytrace), comma separated: one series.
    #[arg(long, value_delimiter = ',')]
    pub quality: Option<Vec<Quality>>,
    /// An algorithm, NAME[:key=value,…] (a plugin name or library path; `ghost-raytrace` is
    /// run in-process, so its ghosts are measured one by one too). Repeatable; each is a
    /// series, and the base of `--vary`.
    #[arg(long = "algo")]
    pub algos: Vec<String>,
    /// Vary a parameter, KEY=a,b,c: a series per algorithm that has the parameter (the
    /// default preset of ghost-raytrace without --algo). Repeatable.
    #[arg(long = "vary", value_parser = Vary::parse)]
    pub vary: Vec<Vary>,
    /// Vary the --vary parameters together (every combination) instead of one at a time.
    #[arg(long)]
    pub product: bool,
    /// Frame size, WxH (the reference is rendered at this size too).
    #[arg(long, default_value = "480x270", value_parser = parse_size)]
    pub size: (usize, usize),
    /// Timed runs per cell, after one untimed warm-up run (the median is plotted).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    #[command(flatten)]
    pub iris: IrisArgs,
    /// Where the ghosts are drawn: auto (a hardware GPU if there is one, else the CPU), cpu
    /// or gpu. Ghosts one by one are always measured on the CPU.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// Also load this plugin library (repeatable).
    #[arg(long = "plugin")]
    pub plugins: Vec<PathBuf>,
    /// Redo every cell and reference instead of reusing those the directory holds.
    #[arg(long)]
    pub fresh: bool,
    /// Also print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// The sweep's directory (created; results.csv, per_ghost.csv, results.json,
    /// plot-*.svg/png, contact-*.png, index.html, and the cache of cells and references).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `results.json`.
#[derive(Serialize)]
struct SweepReport<'a> {
    command: &'a str,
    date: &'a str,
    took_s: f64,
    cells_run: usize,
    cells_reused: usize,
    references_rendered: usize,
    cases: &'a [CaseResult],
}

/// Today's date (UTC), `YYYY-MM-DD`, from the system clock.
fn today() -> String {
    let days = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    civil_date(days)
}

/// The proleptic Gregorian date `days` after 1970-01-01 (counted in eras of 400 years).
fn civil_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

pub fn run(args: &SweepArgs, quiet: bool) -> anyhow::Result<()> {
    let started = Instant::now();
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let mut params = Params {
        plugins: &args.plugins,
        known: HashMap::new(),
    };
    let pts = points::build(
        args.quality.as_deref(),
        &args.algos,
        &args.vary,
        args.product,
        |name: &str| params.of(name),
    )?;
    let lights = if args.lights.is_empty() {
        vec![LightSpec::parse("10,30").map_err(anyhow::Error::msg)?]
    } else {
        args.lights.clone()
    };
    let aperture = args.iris.aperture()?;
    if args.fresh {
        for d in ["cells", "references"] {
            let p = args.output.join(d);
            if p.exists() {
                std::fs::remove_dir_all(&p).with_context(|| format!("removing {}", p.display()))?;
            }
        }
    }
    let show = !quiet && !args.json;
    let mut sweep = Sweep::open(args, params, show)?;
    sweep
        .bar
        .set_length((args.lenses.len() * lights.len() * pts.len()) as u64);
    let mut cases = Vec::new();
    for lens_arg in &args.lenses {
        let sys = lens_library::load(lens_arg, !show)?.system;
        let tables = LensTables::new(&sys);
        let frame = frame_for(&sys, args.size);
        for light in &lights {
            let scene = CaseScene {
                system: &sys,
                tables: &tables,
                aperture: &aperture,
                frame,
                light,
            };
            cases.push(sweep.case(lens_arg, &scene, &pts)?);
        }
    }
    sweep.bar.finish_and_clear();

    let took_s = started.elapsed().as_secs_f64();
    let json = sweep.write_results(&cases, &command, took_s)?;
    let failed = cases
        .iter()
        .flat_map(|c| &c.cells)
        .filter(|c| c.failure.is_some())
        .count();
    let all = cases.iter().map(|c| c.cells.len()).sum::<usize>();
    let outcome = if failed > 0 {
        Err(anyhow::anyhow!(
            "{failed} of {all} cells failed (their reasons are in the results); the rest were written to {}",
            args.output.display()
        ))
    } else {
        Ok(())
    };
    if args.json {
        println!("{json}");
    } else if !quiet {
        print_cases(&cases);
        println!(
            "{} cells run, {} reused, {} references rendered; {:.1} s; backend {}; medians of {} runs; written to {}",
            sweep.cells_run,
            sweep.cells_reused,
            sweep.references,
            took_s,
            sweep.backend_name,
            sweep.runs,
            args.output.join("index.html").display()
        );
    }
    outcome
}

/// Each algorithm's parameters, asked once (a plugin is loaded to tell them).
struct Params<'a> {
    plugins: &'a [PathBuf],
    known: HashMap<String, Vec<ParamInfo>>,
}

impl Params<'_> {
    fn of(&mut self, name: &str) -> anyhow::Result<Vec<ParamInfo>> {
        if let Some(p) = self.known.get(name) {
            return Ok(p.clone());
        }
        let p = params_of(name, self.plugins)?;
        self.known.insert(name.to_string(), p.clone());
        Ok(p)
    }
}

/// A sweep under way: where its results are kept, what draws its cells, its progress.
struct Sweep<'a> {
    args: &'a SweepArgs,
    params: Params<'a>,
    store: Store,
    flare: Flare,
    backend_name: String,
    runs: usize,
    show: bool,
    bar: ProgressBar,
    cells_run: usize,
    cells_reused: usize,
    references: usize,
}

impl<'a> Sweep<'a> {
    fn open(args: &'a SweepArgs, params: Params<'a>, show: bool) -> anyhow::Result<Sweep<'a>> {
        let store = Store::open(&args.output)?;
        let flare = Flare::open(args.backend)?;
        let backend_name = match &flare.backend().report().adapter {
            Some(a) => format!("gpu ({a})"),
            None => flare.backend().report().backend.clone(),
        };
        let bar = if show {
            ProgressBar::new(0).with_style(
                ProgressStyle::with_template(
                    "{msg:40} [{bar:30}] {pos}/{len} cells, {elapsed} (eta {eta})",
                )
                .expect("valid template")
                .progress_chars("=> "),
            )
        } else {
            ProgressBar::hidden()
        };
        Ok(Sweep {
            args,
            params,
            store,
            flare,
            backend_name,
            runs: args.runs as usize,
            show,
            bar,
            cells_run: 0,
            cells_reused: 0,
            references: 0,
        })
    }

    /// One lens and light: its reference (kept or rendered), every point's cell (kept or
    /// measured), its plot and contact sheet.
    fn case(
        &mut self,
        lens_arg: &str,
        scene: &CaseScene<'_>,
        pts: &[Point],
    ) -> anyhow::Result<CaseResult> {
        let case = CaseInfo {
            lens: scene.system.name.clone(),
            lens_arg: lens_arg.to_string(),
            theta_deg: scene.light.theta_deg,
            phi_deg: scene.light.phi_deg,
            width: scene.frame.width,
            height: scene.frame.height,
            aperture: aperture_text(scene.aperture),
        };
        let ref_key = reference_key(
            scene.system,
            scene.aperture,
            &scene.frame,
            std::slice::from_ref(scene.light),
            ReflectionOrder::Two,
        );
        let (reference, ref_img) = match self.store.load_reference(&ref_key) {
            Some(r) => r,
            None => {
                self.bar.set_message(format!("{}: reference", case.lens));
                let (mut rec, img) = measure::reference(scene)?;
                rec.key = ref_key.clone();
                self.store
                    .save_reference(&rec, &img, &thumbnail(&img, THUMB_WIDTH))?;
                self.references += 1;
                (rec, img)
            }
        };
        let mut cells = Vec::new();
        let mut thumbs = Vec::new();
        for p in pts {
            self.bar.set_message(format!("{}: {}", case.lens, p.label));
            let key = cell_key(
                &ref_key,
                p,
                &mut |n: &str| self.params.of(n),
                &self.backend_name,
                self.runs,
            )?;
            let cell = match self.store.load_cell(&key) {
                Some(c) => {
                    self.cells_reused += 1;
                    c
                }
                None => {
                    self.cells_run += 1;
                    self.cell(&case, scene, p, key.clone(), &reference, &ref_img)
                }
            };
            thumbs.push((cell.failure.is_none()).then(|| Store::cell_thumbnail(&key)));
            cells.push(cell);
            self.bar.inc(1);
        }
        let result = CaseResult {
            exposure_ev: auto_exposure(&ref_img),
            reference_thumbnail: Some(Store::reference_thumbnail(&ref_key)),
            case,
            reference,
            cells,
            thumbnails: thumbs,
        };
        write_case_files(&self.store, &result)?;
        Ok(result)
    }

    /// Point `p` measured on the case's scene against its reference and kept, or the reason it
    /// failed.
    fn cell(
        &mut self,
        case: &CaseInfo,
        scene: &CaseScene<'_>,
        p: &Point,
        key: String,
        reference: &ReferenceRecord,
        ref_img: &HdrImage,
    ) -> CellResult {
        let measured = measure::measure(scene, p, self.runs, &mut self.flare, &self.args.plugins)
            .and_then(|m| {
                let c =
                    measure::finish(key.clone(), p, &self.backend_name, &m, reference, ref_img)?;
                self.store
                    .save_cell(&c, Some(&thumbnail(&m.image, THUMB_WIDTH)))?;
                Ok(c)
            });
        match measured {
            Ok(c) => c,
            Err(e) => {
                self.bar.suspend(|| {
                    if self.show {
                        eprintln!("{}: {}: {e:#}", case.lens, p.algo)
                    }
                });
                measure::failed(key, p, &self.backend_name, format!("{e:#}"))
            }
        }
    }

    /// `results.csv`, `per_ghost.csv`, `results.json` and `index.html`; the JSON's text.
    fn write_results(
        &self,
        cases: &[CaseResult],
        command: &str,
        took_s: f64,
    ) -> anyhow::Result<String> {
        let date = today();
        let out = &self.args.output;
        let write = |name: &str, bytes: &[u8]| -> anyhow::Result<()> {
            let p = out.join(name);
            flarebench_sdk::io::write_atomically(&p, bytes)
                .with_context(|| format!("writing {}", p.display()))
        };
        write("results.csv", report::results_csv(cases).as_bytes())?;
        write("per_ghost.csv", report::per_ghost_csv(cases).as_bytes())?;
        let json = serde_json::to_string_pretty(&SweepReport {
            command,
            date: &date,
            took_s,
            cells_run: self.cells_run,
            cells_reused: self.cells_reused,
            references_rendered: self.references,
            cases,
        })?;
        write("results.json", json.as_bytes())?;
        write(
            "index.html",
            report::index_html(cases, command, took_s, &date).as_bytes(),
        )?;
        Ok(json)
    }
}

/// Each case's cells as a table, the Pareto front marked.
fn print_cases(cases: &[CaseResult]) {
    for case in cases {
        println!("{}", case.case.title());
        let front = case.pareto();
        let mut t = Table::new(&[
            "series",
            "point",
            "median ms",
            "min–max ms",
            "rel RMSE",
            "energy",
            "ghosts",
            "dropped",
            "front",
        ]);
        let pct = |v: f64| {
            if v.is_finite() {
                format!("{:.2}%", 100.0 * v)
            } else {
                "—".to_string()
            }
        };
        for (i, c) in case.cells.iter().enumerate() {
            t.row(vec![
                c.series.clone(),
                c.label.clone(),
                format!("{:.1}", c.median_ms),
                format!("{:.1}–{:.1}", c.min_ms, c.max_ms),
                pct(c.relative_rmse),
                pct(c.energy_error),
                match c.ghosts_total {
                    Some(n) => format!("{}/{n}", c.ghosts_drawn),
                    None => c.ghosts_drawn.to_string(),
                },
                c.dropped_energy_measured.map_or("—".to_string(), pct),
                if let Some(f) = &c.failure {
                    format!("failed: {f}")
                } else if front.contains(&i) {
                    "*".to_string()
                } else {
                    String::new()
                },
            ]);
        }
        print!("{}", t.render());
    }
}

/// The running executable as a build: its size and modification time. A rebuilt workbench
/// (a changed renderer) redoes the cells of an earlier build.
fn build_identity() -> String {
    std::env::current_exe()
        .and_then(std::fs::metadata)
        .map(|m| {
            let t = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            format!("{} bytes, modified {t}", m.len())
        })
        .unwrap_or_else(|_| "unknown build".to_string())
}

/// Everything a cell depends on: its scene (the reference's key), the algorithm with every
/// parameter's value, the backend, the runs and the workbench's version and build.
fn cell_key(
    reference_key: &str,
    p: &Point,
    params: &mut impl FnMut(&str) -> anyhow::Result<Vec<ParamInfo>>,
    backend: &str,
    runs: usize,
) -> anyhow::Result<String> {
    let (name, text) = split_algo(&p.algo);
    let info = params(name)?;
    let values = parse_values(&info, text)?;
    let canonical: Vec<String> = info
        .iter()
        .zip(&values)
        .map(|(i, &v)| format!("{}={}", i.name, i.format_value(v)))
        .collect();
    Ok(format!(
        "flarebench-sweep {} ({}); {reference_key}; algo {name} {}; backend {backend}; runs {runs}",
        env!("CARGO_PKG_VERSION"),
        build_identity(),
        canonical.join(",")
    ))
}

/// The case's plot and contact sheet.
fn write_case_files(store: &Store, case: &CaseResult) -> anyhow::Result<()> {
    let slug = case.case.slug();
    plot::save(case, &store.root().join(format!("plot-{slug}")))?;
    let front = case.pareto();
    let reference = case
        .reference_thumbnail
        .as_deref()
        .and_then(|r| store.read_thumbnail(r));
    let thumbs: Vec<_> = case
        .thumbnails
        .iter()
        .map(|t| t.as_deref().and_then(|t| store.read_thumbnail(t)))
        .collect();
    let (w, h) = reference
        .as_ref()
        .map_or((THUMB_WIDTH, THUMB_WIDTH * 9 / 16), |r| (r.width, r.height));
    let mut tiles = vec![Tile {
        image: reference.as_ref(),
        lines: [
            "reference".to_string(),
            format!("{:.1} s", case.reference.render_ms / 1e3),
        ],
    }];
    for (i, (c, t)) in case.cells.iter().zip(&thumbs).enumerate() {
        tiles.push(Tile {
            image: t.as_ref(),
            lines: [
                c.label.clone(),
                if c.failure.is_some() {
                    "failed".to_string()
                } else {
                    format!(
                        "{}{:.1} ms {:.2}%",
                        if front.contains(&i) { "* " } else { "" },
                        c.median_ms,
                        100.0 * c.relative_rmse
                    )
                },
            ],
        });
    }
    let white = 16.0 * (-case.exposure_ev).exp2();
    let sheet = contact_sheet(&tiles, 5, w, h, white);
    save_image(
        &sheet,
        &store.root().join(format!("contact-{slug}.png")),
        &ToneMap {
            exposure_ev: case.exposure_ev,
            operator: ToneOperator::Aces,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::civil_date;

    #[test]
    fn days_since_1970_as_dates() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(59), "1970-03-01");
        assert_eq!(civil_date(11_016), "2000-02-29");
        assert_eq!(civil_date(20_791), "2026-12-04");
        assert_eq!(civil_date(-1), "1969-12-31");
    }
}

//! Measures the fits of a bundled lens: per ghost, the sensor-position error over its domain
//! (rays of another seed, those that reach the sensor with light), and the fit's time.
//!
//! `cargo run --release -p flarebench-ghost-polynomial --example fit_error -- LENS [DEGREE
//! TERMS SAMPLES]` (defaults: the plugin's).

use std::time::Instant;

use flarebench_test_support::load_lens;
use ghost_polynomial::accuracy::position_error;
use ghost_polynomial::fit::FitSettings;
use ghost_polynomial::model::LensModel;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(stem) = args.first() else {
        eprintln!("usage: fit_error LENS [DEGREE TERMS SAMPLES]");
        std::process::exit(2);
    };
    let num = |i: usize, d: usize| args.get(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let d = FitSettings::default();
    let settings = FitSettings {
        degree: num(1, d.degree),
        terms: num(2, d.terms),
        samples: num(3, d.samples),
        ..d
    };
    let sys = load_lens(stem);
    let t = Instant::now();
    let model = LensModel::new(&sys, None).unwrap_or_else(|e| panic!("{e}"));
    let table_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let fits = model.fit_all(&settings);
    let fit_s = t.elapsed().as_secs_f64();
    let mut rms: Vec<f64> = Vec::new();
    let mut p99: Vec<f64> = Vec::new();
    let mut worst = (String::new(), 0.0_f64);
    for fit in &fits {
        let g = model
            .table
            .ghost_index(fit.path)
            .expect("a fitted ghost is in the table");
        let e = position_error(&sys, &model.table, g, fit, 2048, 99);
        if e.rays == 0 {
            continue;
        }
        println!(
            "{stem} {:>6} rays {:>5} rms {:>9.2} p99 {:>9.2} max {:>9.2} µm",
            fit.path.to_string(),
            e.rays,
            e.rms_um,
            e.p99_um,
            e.max_um
        );
        if e.rms_um > worst.1 {
            worst = (fit.path.to_string(), e.rms_um);
        }
        rms.push(e.rms_um);
        p99.push(e.p99_um);
    }
    rms.sort_by(f64::total_cmp);
    p99.sort_by(f64::total_cmp);
    let median = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{stem}: degree {} terms {} samples {}: {} ghosts to {:.1}°; table {:.2} s, fits {:.2} s; rms median {:.1} µm, worst {:.1} µm ({}); p99 median {:.1} µm, worst {:.1} µm",
        settings.degree,
        settings.terms,
        settings.samples,
        rms.len(),
        model.table.angles_deg.last().copied().unwrap_or(0.0),
        table_s,
        fit_s,
        median(&rms),
        worst.1,
        worst.0,
        median(&p99),
        p99.last().copied().unwrap_or(f64::NAN),
    );
}

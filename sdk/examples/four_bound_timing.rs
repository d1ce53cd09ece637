//! Times the traced four-reflection bound (`ghost::FourReflectionBounds::compute`) and the
//! precise bounds of the paths it keeps, for one lens at one angle:
//! `cargo run --release -p flarebench-sdk --example four_bound_timing -- [LENS] [DEG]`
//! (default `nikon-zoom-short 10`). Prints the median of 5 runs of each.

use std::path::Path;
use std::time::Instant;

use flarebench_sdk::ghost::enumerate_four_reflection_ghosts;
use flarebench_sdk::ghost::{FourReflectionBounds, GridTrace, bounds};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::trace::InterfaceTableSet;
use rayon::prelude::*;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let stem = args.next().unwrap_or_else(|| "nikon-zoom-short".into());
    let deg: f64 = args
        .next()
        .map_or(10.0, |a| a.parse().expect("an angle in degrees"));
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../lenses/{stem}.xml"));
    let sys = read_lens(&p).expect("a bundled lens").system;
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let theta = deg.to_radians();
    let reference = bounds::reference_flux(&sys, &tables, &mut GridTrace::default());
    let paths = enumerate_four_reflection_ghosts(&sys);
    let mut fb = FourReflectionBounds::default();
    let bound_ms = median(
        (0..5)
            .map(|_| {
                let t = Instant::now();
                fb = FourReflectionBounds::compute(&sys, &tables, theta, reference);
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    );
    let kept: Vec<_> = paths
        .iter()
        .copied()
        .filter(|p| fb.get(p).unwrap_or(f64::INFINITY) >= 1e-6)
        .collect();
    let precise = |list: &[flarebench_sdk::ghost::GhostPath]| {
        median(
            (0..5)
                .map(|_| {
                    let t = Instant::now();
                    list.par_iter().for_each_init(GridTrace::default, |s, &p| {
                        bounds::precise(&sys, p, &tables, theta, reference, s);
                    });
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        )
    };
    let kept_ms = precise(&kept);
    println!(
        "{stem} at {deg}°: {} paths, {} prefixes traced in {bound_ms:.0} ms; {} kept at 1e-6, their precise bounds {kept_ms:.0} ms",
        paths.len(),
        fb.prefixes(),
        kept.len()
    );
}

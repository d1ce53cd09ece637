//! The smallest plan time over many runs (default preset, bounds traced, or looked up in a
//! table of precise bounds at 0.25° steps when the fourth argument is `table`, as `render
//! --precomputed` plans): less sensitive to a shared machine than a median.
//! `cargo run --release -p flarebench-ghost-raytrace --example plan_min_time -- LENS
//! THETA,PHI RUNS [table]`.

use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::bounds::BoundsMode;
use flarebench_sdk::ghost::table::{BoundsTable, angle_steps, default_max_angle_deg};
use flarebench_sdk::io::read_lens;
use ghost_raytrace::plan::{LensTables, PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let stem = args.get(1).map_or("heliar-tronnier", String::as_str);
    let light = LightSpec::parse(args.get(2).map_or("10,30", String::as_str)).expect("a light");
    let runs: usize = args.get(3).map_or(20, |s| s.parse().expect("a count"));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../lenses")
        .join(format!("{stem}.xml"));
    let sys = read_lens(&path).expect("a bundled lens").system;
    let frame = Frame::across_film(960, 540, sys.film_width_mm);
    let tables = LensTables::new(&sys);
    let table = (args.get(4).map(String::as_str) == Some("table")).then(|| {
        let max = default_max_angle_deg(&sys).expect("a field angle");
        let angles = angle_steps(max, 0.25);
        BoundsTable::compute(&sys, &angles, BoundsMode::Precise, 550.0, &|| {})
    });
    let opts = PlanOptions {
        lens_tables: Some(&tables),
        precomputed: table.as_ref(),
        ..PlanOptions::for_quality(Quality::Default, None)
    };
    let mut best = f64::INFINITY;
    let mut drawn = 0;
    for _ in 0..runs {
        let t = std::time::Instant::now();
        let p = plan(&sys, std::slice::from_ref(&light), &frame, &opts).expect("a plan");
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        drawn = p[0].ghosts.len();
    }
    println!(
        "{stem} {}: plan min {best:.2} ms over {runs} runs, {drawn} ghosts drawn",
        args.get(2).map_or("10,30", String::as_str)
    );
}

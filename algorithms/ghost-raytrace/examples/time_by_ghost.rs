//! Where a preset's render time goes, ghost by ghost: each planned ghost is rendered alone
//! (median of a few runs) and listed, slowest first, with what the plan did to it and the
//! pixels its sensor rectangle spans at its drawn resolution.
//!
//! ```sh
//! cargo run --release -p flarebench-ghost-raytrace --example time_by_ghost -- \
//!     lenses/nikon-zoom-short.xml 10,30 1920x1080 default [RUNS]
//! ```
//!
//! With `BAND_BY_BAND` set in the environment, every band is drawn on its own
//! (`RenderOptions::band_by_band`). Rendering a ghost alone pays the frame's fixed costs
//! (its output image, the upsampling pass) once per ghost, so the times need not sum to a
//! frame's.

use std::path::Path;
use std::time::Instant;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, LightPlan, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

fn alone(lp: &LightPlan, g: usize) -> Vec<LightPlan> {
    vec![LightPlan {
        light: lp.light.clone(),
        bands: lp.bands.clone(),
        sampled: lp.sampled,
        reflections: lp.reflections,
        ghosts: vec![lp.ghosts[g].clone()],
        dropped: Vec::new(),
        not_in_table: Vec::new(),
        culled_share: 0.0,
    }]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [lens, light, size, quality, rest @ ..] = args.as_slice() else {
        eprintln!("usage: time_by_ghost LENS THETA,PHI WxH QUALITY [RUNS]");
        std::process::exit(2);
    };
    let runs: usize = rest.first().map_or(5, |r| r.parse().expect("runs")).max(1);
    let sys = read_lens(Path::new(lens)).expect("lens").system;
    let light = LightSpec::parse(light).expect("light");
    let (w, h) = size.split_once('x').expect("WxH");
    let (w, h): (usize, usize) = (w.parse().expect("width"), h.parse().expect("height"));
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    let quality: Quality = quality.parse().expect("quality");
    let opts = PlanOptions::for_quality(quality, None);
    let options = ghosts::RenderOptions {
        band_by_band: std::env::var_os("BAND_BY_BAND").is_some(),
        ..Default::default()
    };
    let aperture = Aperture::Circular;
    let lp = &plan::plan(&sys, &[light], &frame, &opts).expect("plan")[0];
    let time = |plans: &[LightPlan]| {
        let mut t: Vec<f64> = (0..runs)
            .map(|_| {
                let start = Instant::now();
                ghosts::render_with(&sys, &aperture, frame, plans, options).expect("render");
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[runs / 2]
    };
    let only = std::env::var("ONLY").ok();
    let whole = if only.is_none() {
        time(std::slice::from_ref(lp))
    } else {
        f64::NAN
    };
    // A frame's fixed cost with one (bandless) ghost at each coarse factor: the coarse
    // image and the upsampling pass.
    let mut empty = std::collections::BTreeMap::new();
    for job in lp
        .ghosts
        .iter()
        .filter(|j| only.as_ref().is_none_or(|o| j.path.to_string() == *o))
    {
        empty.entry(job.downscale).or_insert_with(|| {
            let mut p = alone(lp, 0);
            p[0].ghosts[0].downscale = job.downscale;
            p[0].ghosts[0].bands.clear();
            time(&p)
        });
    }
    let px = frame.pixel_mm();
    let mut rows: Vec<(f64, String)> = (0..lp.ghosts.len())
        .filter(|&g| {
            only.as_ref()
                .is_none_or(|o| lp.ghosts[g].path.to_string() == *o)
        })
        .map(|g| {
            let job = &lp.ghosts[g];
            let d = job.downscale.max(1) as f64;
            let t = time(&alone(lp, g)) - empty[&job.downscale];
            let what = format!(
                "{:>7} grid {:>3}² bands {:>2} at 1/{:<2} rect {:>9.0} px",
                job.path.to_string(),
                job.grid,
                job.bands.len(),
                job.downscale,
                job.bounds.sensor.area() / (px * px * d * d),
            );
            (t, what)
        })
        .collect();
    let sum: f64 = rows.iter().map(|r| r.0).sum();
    println!(
        "{lens} {size} {quality}: frame render {whole:.2} ms, an empty frame by factor {empty:.2?} ms, \
         ghosts alone (less that) sum to {sum:.2} ms over {} ghosts",
        rows.len()
    );
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut acc = 0.0;
    for (t, what) in rows {
        acc += t;
        println!("{t:>8.2} ms {:>5.1}%  {what}", 100.0 * acc / sum);
    }
}

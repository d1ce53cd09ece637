//! A whole frame's render time with every ghost meshed, every ghost splatted and each ghost
//! as the plan chose (`plan::DrawMethod`), the three alternated run by run (medians), with
//! each one's relative RMSE against the meshed frame.
//!
//! ```sh
//! cargo run --release -p flarebench-ghost-raytrace --example frame_methods -- \
//!     lenses/nikon-zoom-short.xml 10,30 1920x1080 default [RUNS]
//! ```

use std::path::Path;
use std::time::Instant;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, DrawMethod, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [lens, light, size, quality, rest @ ..] = args.as_slice() else {
        eprintln!("usage: frame_methods LENS THETA,PHI WxH QUALITY [RUNS]");
        std::process::exit(2);
    };
    let runs: usize = rest.first().map_or(5, |r| r.parse().expect("runs")).max(1);
    let sys = read_lens(Path::new(lens)).expect("lens").system;
    let lights = [LightSpec::parse(light).expect("light")];
    let (w, h) = size.split_once('x').expect("WxH");
    let (w, h): (usize, usize) = (w.parse().expect("width"), h.parse().expect("height"));
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    let quality: Quality = quality.parse().expect("quality");
    let preset = PlanOptions::for_quality(quality, None);
    let aperture = match std::env::var("APERTURE").as_deref() {
        Ok("iris") => Aperture::Iris {
            blades: 6,
            rotation_rad: 0.0,
            roundness: 0.0,
        },
        _ => Aperture::Circular,
    };
    let plans: Vec<(&str, Vec<plan::LightPlan>)> = [
        ("mesh", Some(DrawMethod::Mesh)),
        ("splat", Some(DrawMethod::Splat)),
        ("chosen", None),
    ]
    .into_iter()
    .map(|(name, method)| {
        let opts = PlanOptions { method, ..preset };
        (
            name,
            plan::plan(&sys, &lights, &frame, &opts).expect("plan"),
        )
    })
    .collect();
    let mut times = vec![Vec::new(); plans.len()];
    let mut images = Vec::new();
    for run in 0..runs {
        for (k, (_, p)) in plans.iter().enumerate() {
            let start = Instant::now();
            let (img, _) = ghosts::render(&sys, &aperture, frame, p).expect("render");
            times[k].push(start.elapsed().as_secs_f64() * 1e3);
            if run == 0 {
                images.push(img);
            }
        }
    }
    for (k, (name, p)) in plans.iter().enumerate() {
        times[k].sort_by(f64::total_cmp);
        let splatted = p[0]
            .ghosts
            .iter()
            .filter(|g| g.method == DrawMethod::Splat)
            .count();
        println!(
            "{name:>7}: {:8.2} ms median of {runs}, {splatted:>3} of {} ghosts splatted, \
             relative RMSE against meshed {:.4}%",
            times[k][runs / 2],
            p[0].ghosts.len(),
            100.0 * images[k].relative_rmse(&images[0]).expect("sizes"),
        );
    }
}

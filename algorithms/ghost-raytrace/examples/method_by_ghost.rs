//! Each ghost drawn each way: every planned ghost rendered alone meshed and splatted
//! (`plan::DrawMethod`), its time each way (median of a few runs, one thread), the error
//! splatting adds against meshing, what the plan predicted of both, and its mean triangle
//! area: the measurements the plan's cost and error model (`ghost_raytrace::method`) is
//! fitted to.
//!
//! ```sh
//! cargo run --release -p flarebench-ghost-raytrace --example method_by_ghost -- \
//!     lenses/nikon-zoom-short.xml 10,30 1920x1080 default [RUNS]
//! ```
//!
//! Output: one tab-separated row per ghost (header first). `err_splat` is the ghost's
//! splatted image's relative RMSE against its meshed one, `frame2_splat` that squared
//! difference over the whole meshed frame's Σ b² (the ghost's share of the frame's squared
//! relative RMSE), each beside what the plan predicted.

use std::path::Path;
use std::time::Instant;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, DrawMethod, LightPlan, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

fn alone(lp: &LightPlan, g: usize, method: DrawMethod) -> Vec<LightPlan> {
    let mut job = lp.ghosts[g].clone();
    job.method = method;
    if let Some(b) = std::env::var("ONE_BAND")
        .ok()
        .and_then(|b| b.parse::<usize>().ok())
    {
        job.bands = vec![job.bands[b.min(job.bands.len() - 1)]];
    }
    vec![LightPlan {
        light: lp.light.clone(),
        bands: lp.bands.clone(),
        sampled: lp.sampled,
        reflections: lp.reflections,
        ghosts: vec![job],
        dropped: Vec::new(),
        not_in_table: Vec::new(),
        culled_share: 0.0,
    }]
}

fn sq(a: &HdrImage, b: &HdrImage) -> f64 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..3).map(|c| f64::from(p[c] - q[c]).powi(2)).sum::<f64>())
        .sum()
}

fn norm2(a: &HdrImage) -> f64 {
    a.pixels
        .iter()
        .map(|p| p.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>())
        .sum()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [lens, light, size, quality, rest @ ..] = args.as_slice() else {
        eprintln!("usage: method_by_ghost LENS THETA,PHI WxH QUALITY [RUNS]");
        std::process::exit(2);
    };
    let runs: usize = rest.first().map_or(3, |r| r.parse().expect("runs")).max(1);
    let sys = read_lens(Path::new(lens.as_str())).expect("lens").system;
    let light = LightSpec::parse(light).expect("light");
    let (w, h) = size.split_once('x').expect("WxH");
    let (w, h): (usize, usize) = (w.parse().expect("width"), h.parse().expect("height"));
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    let quality: Quality = quality.parse().expect("quality");
    let opts = PlanOptions::for_quality(quality, None);
    let aperture = Aperture::Circular;
    let lights = [light];
    let lp = &plan::plan(&sys, &lights, &frame, &opts).expect("plan")[0];
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let options = ghosts::RenderOptions::default();
    let render = |plans: &[LightPlan]| -> (HdrImage, f64) {
        let mut t: Vec<(f64, HdrImage)> = (0..runs)
            .map(|_| {
                let start = Instant::now();
                let (img, _) = one
                    .install(|| ghosts::render_with(&sys, &aperture, frame, plans, options))
                    .expect("render");
                (start.elapsed().as_secs_f64() * 1e3, img)
            })
            .collect();
        t.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (ms, img) = t.swap_remove(runs / 2);
        (img, ms)
    };
    let mut meshed = lp.clone();
    for g in &mut meshed.ghosts {
        g.method = DrawMethod::Mesh;
    }
    let frame_b2 = norm2(
        &ghosts::render(&sys, &aperture, frame, &[meshed])
            .expect("frame")
            .0,
    );
    println!(
        "ghost\tgrid\tbands\tdown\ttri_px\tchosen\tms_mesh\tms_splat\tpred_mesh_ms\t\
         pred_splat_ms\terr_splat\tpred_err_splat\tframe2_splat\tpred_frame2_splat"
    );
    for (g, job) in lp.ghosts.iter().enumerate() {
        let (mesh, ms_mesh) = render(&alone(lp, g, DrawMethod::Mesh));
        let (splat, ms_splat) = render(&alone(lp, g, DrawMethod::Splat));
        if std::env::var("DUMP").is_ok_and(|d| d == job.path.to_string()) {
            dump(&mesh, &splat, &job.path.to_string());
        }
        let own = norm2(&mesh).max(f64::MIN_POSITIVE);
        let d2 = sq(&splat, &mesh);
        let p = &job.prediction;
        println!(
            "{}\t{}\t{}\t{}\t{:.3}\t{}\t{:.3}\t{:.3}\t{:.3}\t{:.3}\t{:.5}\t{:.5}\t{:.3e}\t{:.3e}",
            job.path,
            job.grid,
            job.bands.len(),
            job.downscale,
            p.triangle_px,
            job.method,
            ms_mesh,
            ms_splat,
            p.mesh_ns * 1e-6,
            p.splat_ns * 1e-6,
            (d2 / own).sqrt(),
            p.splat_error,
            d2 / frame_b2,
            p.frame_error2,
        );
    }
}

/// Writes both images (green channel, scaled by the meshed one's peak) and their difference
/// as PNGs under the temporary directory (`DUMP=GHOST`).
fn dump(mesh: &HdrImage, splat: &HdrImage, name: &str) {
    let peak = mesh
        .pixels
        .iter()
        .map(|p| p[1])
        .fold(0.0_f32, f32::max)
        .max(1e-30);
    let write = |what: &str, f: &dyn Fn(usize) -> f32| {
        let bytes: Vec<u8> = (0..mesh.pixels.len())
            .map(|i| (255.0 * f(i).clamp(0.0, 1.0).sqrt()) as u8)
            .collect();
        let path = std::env::temp_dir().join(format!("{name}-{what}.png"));
        image::GrayImage::from_raw(mesh.width as u32, mesh.height as u32, bytes)
            .expect("size")
            .save(&path)
            .expect("png");
        eprintln!("wrote {}", path.display());
    };
    write("mesh", &|i| mesh.pixels[i][1] / peak);
    write("splat", &|i| splat.pixels[i][1] / peak);
    write("diff", &|i| {
        10.0 * (splat.pixels[i][1] - mesh.pixels[i][1]).abs() / peak
    });
}

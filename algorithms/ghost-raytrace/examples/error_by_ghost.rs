//! Where a preset's error against the reference comes from, ghost by ghost: each ghost is
//! rendered alone by the reference and by the preset (zero when the preset left it out), and
//! its share of the total squared difference is listed with what the plan did to it.
//!
//! ```sh
//! cargo run --release -p flarebench-ghost-raytrace --example error_by_ghost -- \
//!     lenses/nikon-zoom-short.xml 10,30 480x270 default [BANDS]
//! ```
//!
//! With `BAND_BY_BAND` set in the environment, the preset draws every band on its own
//! (`RenderOptions::band_by_band`).
//!
//! Cross terms between ghosts are left out of the shares, so they need not sum to one; the
//! total is the whole image's relative RMSE.

use std::path::Path;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, LightPlan, PlanOptions};
use ghost_raytrace::reference::reference_plans;
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
        eprintln!("usage: error_by_ghost LENS THETA,PHI WxH QUALITY [BANDS]");
        std::process::exit(2);
    };
    let sys = read_lens(Path::new(lens)).expect("lens").system;
    let light = LightSpec::parse(light).expect("light");
    let (w, h) = size.split_once('x').expect("WxH");
    let (w, h): (usize, usize) = (w.parse().unwrap(), h.parse().unwrap());
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    let quality: Quality = quality.parse().expect("quality");
    let mut opts = PlanOptions::for_quality(quality, None);
    if let Some(b) = rest.first() {
        opts.bands = b.parse().expect("bands");
    }
    let aperture = Aperture::Circular;
    let lights = [light];
    let reference = reference_plans(&sys, &lights, &frame, 1.0).unwrap();
    let test = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let (rp, tp) = (&reference[0], &test[0]);

    let mut ref_total = HdrImage::new(w, h);
    let mut test_total = HdrImage::new(w, h);
    let mut rows = Vec::new();
    for g in 0..rp.ghosts.len() {
        let path = rp.ghosts[g].path;
        let (ri, _) = ghosts::render(&sys, &aperture, frame, &alone(rp, g)).unwrap();
        let (ti, what) = match tp.ghosts.iter().position(|j| j.path == path) {
            Some(k) => {
                let j = &tp.ghosts[k];
                let what = format!(
                    "grid {}² bands {} at 1/{}",
                    j.grid,
                    j.bands.len(),
                    j.downscale
                );
                (
                    ghosts::render_with(
                        &sys,
                        &aperture,
                        frame,
                        &alone(tp, k),
                        ghosts::RenderOptions {
                            band_by_band: std::env::var_os("BAND_BY_BAND").is_some(),
                            ..Default::default()
                        },
                    )
                    .unwrap()
                    .0,
                    what,
                )
            }
            None => {
                let why = tp
                    .dropped
                    .iter()
                    .find(|d| d.path == path)
                    .map(|d| format!("left out: {:?}", d.reason))
                    .unwrap_or_else(|| "not planned".into());
                (HdrImage::new(w, h), why)
            }
        };
        let d2: f64 = ri
            .pixels
            .iter()
            .zip(&ti.pixels)
            .flat_map(|(a, b)| (0..3).map(move |c| (f64::from(a[c]) - f64::from(b[c])).powi(2)))
            .sum();
        let (er, et) = (ri.sum(), ti.sum());
        rows.push((path, d2, er[1], et[1], what));
        ref_total.add_image(&ri).unwrap();
        test_total.add_image(&ti).unwrap();
    }
    let b2: f64 = ref_total
        .pixels
        .iter()
        .flat_map(|p| p.iter().map(|&v| f64::from(v).powi(2)))
        .sum();
    let c = test_total.compare(&ref_total).unwrap();
    println!(
        "{lens} {size} {quality}: relative RMSE {:.3}%, L1 {:.3}%, energy {:+.3}% over {} ghosts",
        100.0 * c.relative_rmse,
        100.0 * c.relative_l1,
        100.0 * c.energy_error,
        rows.len()
    );
    rows.sort_by(|a, b| b.1.total_cmp(&a.1));
    println!("ghost    share of d²  alone RMSE%  ref G energy  test/ref  plan");
    for (path, d2, er, et, what) in rows.iter().take(20) {
        println!(
            "{:>7}  {:>10.3}%  {:>10.3}  {:>12.4e}  {:>8.4}  {what}",
            path.to_string(),
            100.0 * d2 / (c.relative_rmse.powi(2) * b2),
            100.0 * (d2 / b2).sqrt(),
            er,
            if *er > 0.0 { et / er } else { f64::NAN }
        );
    }
}

//! How far a ghost's image is from its spectral limit: one ghost alone, rendered band by band
//! at the reference's grid with several spectral samplings, and as the default preset plans
//! it, against a render at `DENSE` bands (default 160), as a share of its own light.
//!
//! ```sh
//! cargo run --release -p flarebench-ghost-raytrace --example bands_by_ghost -- \
//!     lenses/nikon-zoom-short.xml 10,30 960x540 7-0 [DENSE]
//! ```
//!
//! The rows: the preset's plan (its grid, bands and coarse factor), the reference's own
//! sampling (`ghost_raytrace::reference`), and fixed band counts.

use std::path::Path;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, GhostJob, LightPlan, PlanOptions};
use ghost_raytrace::reference::{reference_options, reference_plans_dense};
use ghost_raytrace::scene::{LightSpec, Quality};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [lens, light, size, ghost, rest @ ..] = args.as_slice() else {
        eprintln!("usage: bands_by_ghost LENS THETA,PHI WxH GHOST [DENSE]");
        std::process::exit(2);
    };
    let dense: usize = rest
        .first()
        .map_or(160, |d| d.parse().expect("dense bands"));
    let sys = read_lens(Path::new(lens)).expect("lens").system;
    let lights = [LightSpec::parse(light).expect("light")];
    let (w, h) = size.split_once('x').expect("WxH");
    let (w, h): (usize, usize) = (w.parse().expect("width"), h.parse().expect("height"));
    let frame = Frame::across_film(w, h, sys.film_width_mm);
    // The plan of one ghost alone, from a plan of every ghost.
    let alone = |mut lp: LightPlan| -> LightPlan {
        let k = lp
            .ghosts
            .iter()
            .position(|j| j.path.to_string() == *ghost)
            .unwrap_or_else(|| panic!("no ghost {ghost} with light in the plan"));
        lp.ghosts = vec![lp.ghosts.swap_remove(k)];
        lp
    };
    let reference = alone(
        reference_plans_dense(&sys, &lights, &frame, 1.0, 1.0, ReflectionOrder::Two)
            .expect("reference plan")
            .remove(0),
    );
    let grid = reference.ghosts[0].grid;
    // Every ghost at exactly `bands` bands, on the reference's grid.
    let fixed = |bands: usize| {
        let opts = PlanOptions {
            bands,
            min_bands: bands,
            ..reference_options(ReflectionOrder::Two)
        };
        let mut lp = alone(
            plan::plan(&sys, &lights, &frame, &opts)
                .expect("plan")
                .remove(0),
        );
        lp.ghosts[0].grid = grid;
        lp
    };
    let render = |lp: &LightPlan, band_by_band: bool| -> HdrImage {
        let options = RenderOptions {
            band_by_band,
            ..Default::default()
        };
        ghosts::render_with(
            &sys,
            &Aperture::Circular,
            frame,
            std::slice::from_ref(lp),
            options,
        )
        .expect("render")
        .0
    };
    let truth = render(&fixed(dense), true);
    let light_sq: f64 = truth
        .pixels
        .iter()
        .flat_map(|p| p.iter().map(|&v| f64::from(v).powi(2)))
        .sum();
    let error = |img: &HdrImage| -> f64 {
        let d2: f64 = truth
            .pixels
            .iter()
            .zip(&img.pixels)
            .flat_map(|(a, b)| (0..3).map(move |c| (f64::from(a[c]) - f64::from(b[c])).powi(2)))
            .sum();
        100.0 * (d2 / light_sq).sqrt()
    };
    let describe = |j: &GhostJob| {
        format!(
            "grid {}², {} bands, at 1/{}",
            j.grid,
            j.bands.len(),
            j.downscale
        )
    };
    println!("{lens} {ghost} at {size}: against {dense} bands on the reference's grid ({grid}²)");
    let preset = alone(
        plan::plan(
            &sys,
            &lights,
            &frame,
            &PlanOptions::for_quality(Quality::Default, None),
        )
        .expect("plan")
        .remove(0),
    );
    println!(
        "{:>8.3}%  default preset ({})",
        error(&render(&preset, false)),
        describe(&preset.ghosts[0])
    );
    println!(
        "{:>8.3}%  the reference ({})",
        error(&render(&reference, true)),
        describe(&reference.ghosts[0])
    );
    for bands in [31, 40, 80] {
        if bands != dense {
            println!(
                "{:>8.3}%  {bands} bands",
                error(&render(&fixed(bands), true))
            );
        }
    }
}

//! The seam between meshing and drawing (`flarebench_sdk::ghost::sink`): a frame recorded as
//! its levels and meshes, then drawn by the CPU rasterizer, is the CPU renderer's image bit for
//! bit — the recording holds everything the drawing needs.

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::sink::FrameMeshes;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

fn check(lens: &str, lights: &[&str], aperture: Aperture, band_by_band: bool) {
    let sys = load_lens(lens);
    let frame = Frame::across_film(480, 270, sys.film_width_mm);
    let lights: Vec<LightSpec> = lights
        .iter()
        .map(|l| LightSpec::parse(l).unwrap())
        .collect();
    let opts = PlanOptions::for_quality(Quality::Default, None);
    let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let options = RenderOptions {
        band_by_band,
        ..RenderOptions::default()
    };
    let (img, stats) = ghosts::render_with(&sys, &aperture, frame, &plans, options).unwrap();
    let mut recorded = FrameMeshes::default();
    let stats2 = ghosts::draw_into(&sys, &aperture, frame, &plans, options, &mut recorded).unwrap();
    assert_eq!(stats, stats2);
    let (_, grids, _, _) = recorded.levels.as_ref().expect("a frame was begun");
    assert!(
        grids.len() >= 2,
        "{lens}: the frame should use coarse levels as well as full resolution: {grids:?}"
    );
    assert!(recorded.triangles() > 0);
    let replayed = recorded.draw_cpu();
    assert_eq!((replayed.width, replayed.height), (img.width, img.height));
    let differing = img
        .pixels
        .iter()
        .zip(&replayed.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "{lens}: pixels differ between render and replay"
    );
}

#[test]
fn a_recorded_frame_draws_the_renderers_image_exactly() {
    check(
        "heliar-tronnier",
        &["8,60", "3,200"],
        Aperture::Circular,
        false,
    );
    check(
        "heliar-tronnier",
        &["8,60"],
        Aperture::Iris {
            blades: 6,
            rotation_rad: 0.3,
            roundness: 0.2,
        },
        true,
    );
}

//! Ghost images traced in f32 agree with the same images traced in f64.

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{RenderOptions, render_with};
use ghost_raytrace::plan::{PlanOptions, plan};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Relative RMSE of a ghost image traced in f32 against the same traced in f64: f32 rounding
/// of the trace.
const F32_RMSE_TOL: f64 = 1e-3;
/// Energy error of the f32 image against the f64 one (relative): f32 rounding of the trace.
const F32_ENERGY_TOL: f64 = 1e-4;

fn compare(lens: &str, light: &str) -> (f64, f64) {
    let sys = load_lens(lens);
    let frame = Frame {
        width: 320,
        height: 180,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * 180.0 / 320.0,
    };
    let lights = [LightSpec::parse(light).unwrap()];
    let plans = plan(
        &sys,
        &lights,
        &frame,
        &PlanOptions::for_quality(Quality::Default, None),
    )
    .unwrap();
    let render = |trace_f64| {
        render_with(
            &sys,
            &Aperture::Circular,
            frame,
            &plans,
            RenderOptions {
                trace_f64,
                ..Default::default()
            },
        )
        .unwrap()
        .0
    };
    let (single, double) = (render(false), render(true));
    assert!(!single.has_non_finite() && !double.has_non_finite());
    let c = single.compare(&double).unwrap();
    eprintln!(
        "{lens} at {light}: f32 vs f64 relative RMSE {:.2e}, energy {:.2e}",
        c.relative_rmse, c.energy_error
    );
    (c.relative_rmse, c.energy_error)
}

#[test]
fn f32_ghost_images_match_f64() {
    for (lens, light) in [
        ("heliar-tronnier", "10,30"),
        ("nikon-zoom-short", "10,30"),
        ("fisheye-10mm", "60,0"),
    ] {
        let (rmse, energy) = compare(lens, light);
        assert!(rmse < F32_RMSE_TOL, "{lens}: relative RMSE {rmse}");
        assert!(energy.abs() < F32_ENERGY_TOL, "{lens}: energy {energy}");
    }
}

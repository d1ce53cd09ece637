//! The reference renderer converges: twice its rays change the image by under 0.1%.
//!
//! The Heliar (28 ghosts, all 31 bands, light at 5°, 160×90). Measured 8.3e-4 while edges were
//! still feathered over a grid cell (the one-pixel edges came later; the assertion is the
//! same). Not every lens converges as fast: the Cooke triplet's caustic ghosts gave 7.1e-3 at
//! the same density.

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::render::Frame;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts;
use ghost_raytrace::reference::reference_plans;
use ghost_raytrace::scene::LightSpec;

#[test]
fn doubling_the_reference_rays_changes_the_image_by_under_a_thousandth() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../lenses/heliar-tronnier.xml"
    );
    let sys = read_lens(std::path::Path::new(path)).unwrap().system;
    let frame = Frame {
        width: 160,
        height: 90,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * 90.0 / 160.0,
    };
    let lights = [LightSpec::parse("5,30").unwrap()];
    let render = |density: f64| {
        let plans = reference_plans(&sys, &lights, &frame, density).unwrap();
        ghosts::render(&sys, &Aperture::Circular, frame, &plans)
            .unwrap()
            .0
    };
    let base = render(1.0);
    let fine = render(std::f64::consts::SQRT_2);
    let c = base.compare(&fine).unwrap();
    eprintln!(
        "reference vs twice its rays: rel RMSE {:.2e}, rel L1 {:.2e}, energy {:.2e}",
        c.relative_rmse, c.relative_l1, c.energy_error
    );
    assert!(base.sum().iter().all(|&v| v > 0.0), "the reference is lit");
    assert!(c.relative_rmse < 1e-3, "relative RMSE {}", c.relative_rmse);
    assert!(c.energy_error.abs() < 1e-3, "energy {}", c.energy_error);
}

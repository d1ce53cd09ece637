//! The built plugin library (`libghost_raytrace.so`, from `cargo build --workspace`) renders
//! what a direct call renders: the plugin boundary changes nothing but who calls.

use std::path::{Path, PathBuf};

use flarebench_sdk::abi::author::{Scene, SceneLight};
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::io::read_lens;
use flarebench_test_support::plugin_library;
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};
use ghost_raytrace::{ghosts, plugin};

/// The cdylib beside this test's `deps/` directory.
fn library() -> PathBuf {
    plugin_library("ghost_raytrace")
}

/// Ghosts are summed over the cores in an order that varies between runs; measured
/// differences between two renders are under 1e-7 relative (f32 rounding of the sums).
const SAME_IMAGE_TOL: f64 = 1e-5;

#[test]
fn the_plugin_library_renders_what_the_direct_call_renders() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../lenses/heliar-tronnier.xml"
    );
    let sys = read_lens(Path::new(path)).unwrap().system;
    let frame = Frame {
        width: 160,
        height: 90,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * 90.0 / 160.0,
    };
    let aperture = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.2,
        roundness: 0.3,
    };
    let light = LightSpec::parse("8,30,1.5,4000").unwrap();

    let opts = PlanOptions::for_quality(Quality::Fast, None);
    let plans = plan::plan(&sys, std::slice::from_ref(&light), &frame, &opts).unwrap();
    let (direct, _) = ghosts::render(&sys, &aperture, frame, &plans).unwrap();
    assert!(direct.luminance_sum() > 0.0);

    let p = host::load(&library()).unwrap();
    assert_eq!(p.name, "ghost-raytrace");
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&sys).unwrap();
    let scene = Scene {
        lights: vec![SceneLight {
            theta_deg: light.theta_deg,
            phi_deg: light.phi_deg,
            intensity: light.intensity,
            spectrum: light.spectrum,
        }],
        frame,
        aperture,
    };
    assert_eq!(plugin::light_specs(&scene), vec![light]);
    let values = parse_values(&p.params, "quality=fast").unwrap();
    let out = inst.render(&scene, &values).unwrap();
    assert_eq!(out.items_drawn as usize, plans[0].ghosts.len());
    let c = out.image.compare(&direct).unwrap();
    assert!(
        c.relative_rmse < SAME_IMAGE_TOL && c.energy_error.abs() < SAME_IMAGE_TOL,
        "{c:?}"
    );
}

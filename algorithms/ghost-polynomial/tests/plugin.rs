//! The built library through the plugin host (after `cargo build --workspace`): it describes
//! itself, renders the Heliar's ghosts with the ray-traced renderer's energy and where it puts
//! them, and every fault — values out of range, the wrong number of values — comes back as an
//! error while the instance carries on.

use flarebench_sdk::abi::author::{Scene, SceneLight};
use flarebench_sdk::abi::host::{self, PluginCallError};
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::{load_lens, plugin_library};

/// The polynomial image's energy against the ray-traced renderer's (relative), Heliar at 10°,
/// 160 × 90, 7 bands, default fit. Measured 2026-12-05: −0.02% (+0.17% at degree 5, 40
/// terms); the bound leaves room for other seeds and settings.
const ENERGY_TOLERANCE: f64 = 0.005;
/// The two images' luminance centroids may differ by this much (pixels of 0.225 mm).
/// Measured 2026-12-05: 0.19 px (0.49 px at degree 5, 40 terms: the fits' position errors,
/// tens of µm, weighted by the ghosts' energies); the bound leaves a factor of about 3.
const CENTROID_TOLERANCE_PX: f64 = 0.6;

fn energy_and_centroid(img: &HdrImage) -> (f64, [f64; 2]) {
    let (mut e, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for (k, p) in img.pixels.iter().enumerate() {
        let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        e += l;
        cx += l * ((k % img.width) as f64 + 0.5);
        cy += l * ((k / img.width) as f64 + 0.5);
    }
    (e, [cx / e, cy / e])
}

#[test]
fn the_built_library_renders_the_heliars_ghosts_and_returns_every_fault_as_an_error() {
    // SAFETY: the only test of this binary, run before any other thread of it reads the
    // environment: the plugin's disk cache goes to a directory of its own.
    let dir = tempfile::tempdir().unwrap();
    unsafe { std::env::set_var("FLAREBENCH_GHOST_POLYNOMIAL_CACHE", dir.path()) };

    let p = host::load(&plugin_library("ghost_polynomial")).unwrap();
    assert_eq!(p.name, "ghost-polynomial");
    let names: Vec<&str> = p.params.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["degree", "terms", "samples", "seed", "bands"]);

    let sys = load_lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![SceneLight {
            theta_deg: 10.0,
            phi_deg: 30.0,
            intensity: 1.0,
            spectrum: LightSpectrum::D65,
        }],
        frame: Frame::across_film(160, 90, sys.film_width_mm),
        aperture: Aperture::Circular,
    };
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&sys).unwrap();
    let out = inst
        .render(&scene, &parse_values(&p.params, "").unwrap())
        .unwrap();
    assert!(out.items_drawn > 0 && out.mesh_triangles > 0);
    // Finite; a band's colour weights may be negative in a channel (the ends of the
    // spectrum), so only the luminance is positive.
    assert!(out.image.pixels.iter().flatten().all(|c| c.is_finite()));
    assert!(out.image.luminance_sum() > 0.0);

    let reference = {
        let r = host::load(&plugin_library("ghost_raytrace")).unwrap();
        let mut ri = r.instantiate().unwrap();
        ri.prepare(&sys).unwrap();
        let v = parse_values(&r.params, "dim_budget=0,bands=7").unwrap();
        ri.render(&scene, &v).unwrap().image
    };
    let (e, c) = energy_and_centroid(&out.image);
    let (e0, c0) = energy_and_centroid(&reference);
    let rel = e / e0 - 1.0;
    let shift = (c[0] - c0[0]).hypot(c[1] - c0[1]);
    eprintln!("energy {rel:+.4}, centroid shift {shift:.3} px");
    assert!(rel.abs() <= ENERGY_TOLERANCE, "energy {rel:+.4}");
    assert!(shift <= CENTROID_TOLERANCE_PX, "centroid {shift} px");
    assert!(
        std::fs::read_dir(dir.path()).unwrap().count() >= 2,
        "the table and the fits are cached on disk"
    );

    // Out of range, bypassing the host's own check: the plugin side refuses it.
    for bad in [
        [0.0, 40.0, 4096.0, 1.0, 0.0],
        [5.0, 40.0, 4096.0, 1.0, 99.0],
    ] {
        let e = inst.render(&scene, &bad).unwrap_err();
        assert!(
            matches!(e, PluginCallError::InvalidArgument { .. }),
            "{e:?}"
        );
    }
    let e = inst.render(&scene, &[5.0]).unwrap_err();
    assert!(e.to_string().contains("1 parameter values for 5"), "{e}");
    // And the instance carries on.
    assert!(
        inst.render(&scene, &parse_values(&p.params, "").unwrap())
            .is_ok()
    );
    // A render before `prepare` is an error, not a panic.
    let mut fresh = p.instantiate().unwrap();
    let e = fresh.render(&scene, &parse_values(&p.params, "").unwrap());
    assert!(e.is_err(), "rendered without a lens");
}

//! The plugin's contract: finite pixels, the same image for a seed whatever the thread count,
//! bad parameters as errors (called directly and through the built library), and the loaded
//! library rendering what the direct call renders.

use super::common;

use common::{Values, heliar_scene, render};
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_test_support::plugin_library;

fn values(rays: f64, seed: f64) -> Values {
    Values {
        rays,
        kernel_px: 1.0,
        bands: 5.0,
        seed,
    }
}

#[test]
fn a_render_has_finite_non_negative_pixels_and_light() {
    let (sys, scene) = heliar_scene(96, 54);
    for kernel_px in [0.0, 1.0, 2.5, 8.0] {
        let img = render(
            &sys,
            &scene,
            &Values {
                kernel_px,
                ..values(8192.0, 3.0)
            },
        )
        .unwrap();
        assert!(
            img.pixels.iter().flatten().all(|c| c.is_finite()),
            "kernel {kernel_px}"
        );
        // A D65 light's colour weights are positive at every band but the blue and red ends'
        // red and blue; a ghost's pixel sums many bands, so its luminance is positive.
        assert!(img.luminance_sum() > 0.0, "kernel {kernel_px}");
    }
}

#[test]
fn a_seed_gives_the_same_image_on_one_two_or_three_threads() {
    let (sys, scene) = heliar_scene(96, 54);
    let on = |threads: usize, seed: f64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&sys, &scene, &values(8192.0, seed)).unwrap())
    };
    let one = on(1, 9.0);
    for threads in [2, 3] {
        assert!(
            one.pixels == on(threads, 9.0).pixels,
            "{threads} threads gave another image"
        );
    }
    assert!(
        one.pixels != on(2, 10.0).pixels,
        "another seed, the same image"
    );
}

#[test]
fn bad_parameters_are_errors_not_panics() {
    let (sys, scene) = heliar_scene(32, 18);
    let bad = [
        // Between the box and bilinear: in the host's range, refused by the plugin.
        Values {
            kernel_px: 0.5,
            ..values(4096.0, 1.0)
        },
        Values {
            kernel_px: f64::NAN,
            ..values(4096.0, 1.0)
        },
        Values {
            kernel_px: 9.0,
            ..values(4096.0, 1.0)
        },
        values(0.0, 1.0),
        values(-5.0, 1.0),
        values(4096.0, -1.0),
        Values {
            bands: 0.0,
            ..values(4096.0, 1.0)
        },
        Values {
            bands: 1e9,
            ..values(4096.0, 1.0)
        },
    ];
    for v in &bad {
        let e = render(&sys, &scene, v).expect_err("a bad parameter");
        assert!(!e.message.is_empty());
    }
}

#[test]
fn the_library_renders_what_the_direct_call_renders_and_reports_bad_parameters() {
    let (sys, scene) = heliar_scene(96, 54);
    let direct = render(&sys, &scene, &values(8192.0, 4.0)).unwrap();
    let p = host::load(&plugin_library("ghost_splat")).unwrap();
    assert_eq!(p.name, "ghost-splat");
    let names: Vec<&str> = p.params.iter().map(|q| q.name.as_str()).collect();
    assert_eq!(names, ["rays", "kernel_px", "bands", "seed"]);
    let mut inst = p.instantiate().unwrap();
    // Before `prepare`: an error.
    let defaults = parse_values(&p.params, "").unwrap();
    assert!(inst.render(&scene, &defaults).is_err());
    inst.prepare(&sys).unwrap();
    let v = parse_values(&p.params, "rays=8192,kernel_px=1,bands=5,seed=4").unwrap();
    let out = inst.render(&scene, &v).unwrap();
    assert!(out.items_drawn > 0);
    assert!(
        out.image.pixels == direct.pixels,
        "another image through the library"
    );
    // In range for the host, refused by the plugin; the instance carries on.
    let half = parse_values(&p.params, "kernel_px=0.5").unwrap();
    let e = inst.render(&scene, &half).expect_err("kernel_px 0.5");
    assert!(e.to_string().contains("kernel_px"), "{e}");
    assert!(inst.render(&scene, &v).is_ok());
}

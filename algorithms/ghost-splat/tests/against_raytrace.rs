//! The splat image against the ray-traced renderer (`ghost-raytrace` at its high preset with
//! every ghost kept, loaded from the library `cargo build --workspace` builds): the same
//! energy within the splat's statistical error, and an image error that falls as 1/√rays.

use super::common;

use common::{Values, heliar_scene, render};
use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::ghost::monte_carlo::McEstimate;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::plugin_library;

/// The ray-traced renderer's image of `scene`: high preset, no ghost left out, `bands`
/// wavelength bands.
fn raytraced(sys: &LensSystem, scene: &Scene, bands: usize) -> HdrImage {
    let p = host::load(&plugin_library("ghost_raytrace")).expect("the renderer's library");
    let mut inst = p.instantiate().unwrap();
    inst.prepare(sys).unwrap();
    let values = parse_values(
        &p.params,
        &format!("quality=high,dim_budget=0,bands={bands}"),
    )
    .unwrap();
    inst.render(scene, &values).unwrap().image
}

/// Standard errors the splat energy may lie from the renderer's (a 4σ miss has odds of 6e-5
/// for a normal estimate).
const SIGMAS: f64 = 4.0;

/// What the two may differ by beyond that, relative: the renderer's own error (its high
/// preset's image is 0.85% RMSE from the dense reference on the Heliar, docs/accuracy.md) and
/// the colour within each band (both integrate it in 5 nm steps with the throughput at normal
/// incidence, the renderer over its 31 bands, the splat over its 7). Measured (2026-12-04, 160 × 90,
/// 8 seeds of 16384 rays a ghost): −0.29% ± 0.13% (one standard error). Taking the light's
/// weight at each of 7 bands' centres instead put the energy 14% low: caught.
const BAND_AND_RENDERER_TOLERANCE: f64 = 3e-3;

/// Seeds the splat energy's error bar is measured from.
const SEEDS: usize = 8;

#[test]
fn the_splat_carries_the_ray_traced_renderer_s_energy_on_the_heliar_at_10_degrees() {
    let (sys, scene) = heliar_scene(160, 90);
    let want = raytraced(&sys, &scene, 31).luminance_sum();
    let energies: Vec<f64> = (0..SEEDS)
        .map(|seed| {
            let img = render(
                &sys,
                &scene,
                &Values {
                    rays: 16384.0,
                    kernel_px: 1.0,
                    bands: 7.0,
                    seed: seed as f64,
                },
            )
            .unwrap();
            img.luminance_sum()
        })
        .collect();
    let e = McEstimate::of(&energies);
    eprintln!(
        "splat {:.6e} ± {:.2}%, renderer {want:.6e}: {:+.3}%",
        e.mean,
        100.0 * e.relative_error(),
        100.0 * (e.mean / want - 1.0)
    );
    assert!(want > 0.0);
    let allowed = SIGMAS * e.std_error + BAND_AND_RENDERER_TOLERANCE * want;
    assert!(
        (e.mean - want).abs() <= allowed,
        "splat {e:?} against the renderer's {want}"
    );
    // The test would see a 2% error in the splat's energy.
    assert!((1.02 * e.mean - want).abs() > allowed);
}

/// The relative RMSE at 4× the rays over that at 1×: 2 for an error falling as 1/√rays; the
/// renderer's own error (under 1% against the 50–130% compared here) barely lowers it.
/// Measured (2026-12-04, 160 × 90, box kernel, 7 bands): 1.26 at 32768 rays, 0.53 at 131072,
/// a fall of 2.4 (the strata make it a little faster than 1/√rays). Below this bound the
/// error would not be falling as 1/√rays.
const MIN_FALL_AT_4X: f64 = 1.7;

#[test]
fn the_error_against_the_renderer_halves_at_four_times_the_rays() {
    let (sys, scene) = heliar_scene(160, 90);
    // Both at the same 7 bands (the same wavelengths: the images differ only by the colour
    // within each band), and the box kernel, an estimate of each pixel's integral, unbiased
    // against the renderer's exact-coverage image: what is measured is the noise.
    let reference = raytraced(&sys, &scene, 7);
    let rmse = |rays: f64| {
        let img = render(
            &sys,
            &scene,
            &Values {
                rays,
                kernel_px: 0.0,
                bands: 7.0,
                seed: 5.0,
            },
        )
        .unwrap();
        img.relative_rmse(&reference).unwrap()
    };
    // At least one ray per stratum of every ghost and band (up to 64² cells × 7 bands) at 1×,
    // so that 4× the rays doubles the strata a side.
    let (e1, e4) = (rmse(32768.0), rmse(131072.0));
    eprintln!("relative RMSE {e1:.4} at 32768 rays, {e4:.4} at 131072");
    assert!(e1 / e4 > MIN_FALL_AT_4X, "{e1} → {e4}");
}

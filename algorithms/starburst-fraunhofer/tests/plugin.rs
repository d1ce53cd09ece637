//! The starburst plugin: the built library (`libstarburst_fraunhofer.so`, from `cargo build
//! --workspace`) renders what the sdk's starburst functions render when called directly, the
//! cache keeps one transform per aperture between renders and lenses, and bad settings are
//! refused with their reason.

use std::path::PathBuf;

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{FlarePlugin, Output, Params, Scene, SceneLight};
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::{LightSpectrum, SpectralSampling};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds::direct_flux;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::{
    PowerSpectrum, StarburstPattern, StarburstSettings, add_starburst, chief_ray_landing,
};
use flarebench_sdk::trace::InterfaceTableSet;
use flarebench_test_support::load_lens;
use flarebench_test_support::plugin_library;
use starburst_fraunhofer::{FLUX_LAMBDA_NM, StarburstFraunhofer};

/// The cdylib beside this test's `deps/` directory.
fn library() -> PathBuf {
    plugin_library("starburst_fraunhofer")
}

fn lens(name: &str) -> LensSystem {
    load_lens(name)
}

fn frame(sys: &LensSystem, width: usize, height: usize) -> Frame {
    Frame {
        width,
        height,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * height as f64 / width as f64,
    }
}

fn light(theta_deg: f64, phi_deg: f64, intensity: f64, spectrum: LightSpectrum) -> SceneLight {
    SceneLight {
        theta_deg,
        phi_deg,
        intensity,
        spectrum,
    }
}

/// Small settings so the debug tests stay quick: a 512² transform, 16 wavelengths.
const PARAMS: &str = "texels=128,padding=4,wavelengths=16";
fn small_settings() -> StarburstSettings {
    StarburstSettings {
        pupil_texels: 128,
        padding: 4,
        wavelengths: 16,
    }
}

/// The scene rendered by calling the sdk's functions one by one, without the plugin or a
/// cache: landing point at the d line (moved by `shift_mm` along x), flux at 550 nm, one
/// transform per light.
fn direct(
    sys: &LensSystem,
    scene: &Scene,
    settings: &StarburstSettings,
    shift_mm: f64,
) -> HdrImage {
    let f_number = analyse(sys, LAMBDA_D_NM).unwrap().f_number;
    let tables = InterfaceTableSet::for_system(sys, FLUX_LAMBDA_NM);
    let mut scratch = GridTrace::default();
    let mut img = HdrImage::new(scene.frame.width, scene.frame.height);
    for l in &scene.lights {
        let (theta, phi) = (l.theta_deg.to_radians(), l.phi_deg.to_radians());
        let [x, y] = chief_ray_landing(sys, LAMBDA_D_NM, theta, phi).unwrap();
        let centre = [x + shift_mm, y];
        let flux = l.intensity * direct_flux(sys, &tables, theta, &mut scratch);
        let spectrum = PowerSpectrum::compute(&scene.aperture, None, settings).unwrap();
        let sampling = SpectralSampling::new(settings.wavelengths, l.spectrum).unwrap();
        let pattern = StarburstPattern::new(&spectrum, &sampling);
        add_starburst(&mut img, &scene.frame, &pattern, centre, f_number, flux).unwrap();
    }
    img
}

/// Both paths run the same f32/f64 arithmetic in the same order, so they agree to rounding;
/// measured: identical images (relative RMSE 0). 1e-6 leaves room for a change of summation
/// order, not for a different landing point, flux or pattern: a landing point a tenth of a
/// pixel off measured a relative RMSE of 1.0% on these few-pixel patterns (checked below).
const SAME_IMAGE_TOL: f64 = 1e-6;

#[test]
fn the_plugin_library_renders_what_the_sdk_functions_render() {
    let sys = lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![
            light(5.0, 30.0, 1.0, LightSpectrum::D65),
            light(
                4.0,
                -120.0,
                2.5,
                LightSpectrum::Blackbody { kelvin: 3200.0 },
            ),
        ],
        frame: frame(&sys, 320, 180),
        aperture: Aperture::Iris {
            blades: 6,
            rotation_rad: 0.2,
            roundness: 0.3,
        },
    };
    let expected = direct(&sys, &scene, &small_settings(), 0.0);
    assert!(expected.luminance_sum() > 0.0);

    let p = host::load(&library()).unwrap();
    assert_eq!(p.name, "starburst-fraunhofer");
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&sys).unwrap();
    let values = parse_values(&p.params, PARAMS).unwrap();
    let out = inst.render(&scene, &values).unwrap();
    assert_eq!(out.items_drawn, 2);
    assert_eq!(out.mesh_triangles, 0);
    let c = out.image.compare(&expected).unwrap();
    assert!(
        c.relative_rmse < SAME_IMAGE_TOL && c.energy_error.abs() < SAME_IMAGE_TOL,
        "{c:?}"
    );
    // The comparison catches a landing point a tenth of a pixel off.
    let px_mm = scene.frame.film_width_mm / scene.frame.width as f64;
    let shifted = direct(&sys, &scene, &small_settings(), 0.1 * px_mm);
    let c = out.image.compare(&shifted).unwrap();
    assert!(c.relative_rmse > 1e3 * SAME_IMAGE_TOL, "{c:?}");
    // A second render from the instance's cache is the same image.
    let again = inst.render(&scene, &values).unwrap();
    assert_eq!(again.image.pixels, out.image.pixels);
}

/// Renders `scene` with the plugin called directly (its rlib).
fn render(plugin: &mut StarburstFraunhofer, scene: &Scene, params: &str) -> (HdrImage, u32) {
    let specs = StarburstFraunhofer::info().params;
    let mut values: Vec<f64> = specs.iter().map(|s| s.default).collect();
    for kv in params.split(',') {
        let (k, v) = kv.split_once('=').unwrap();
        let i = specs.iter().position(|s| s.name == k).unwrap();
        values[i] = v.parse().unwrap();
    }
    let f = scene.frame;
    let mut pixels = vec![[0.0f32; 3]; f.width * f.height];
    let mut out = Output {
        width: f.width,
        height: f.height,
        pixels: &mut pixels,
        mesh: Default::default(),
        items_drawn: 0,
    };
    plugin
        .render(scene, &Params::new(&specs, &values), &mut out)
        .unwrap();
    let drawn = out.items_drawn;
    (
        HdrImage::from_pixels(f.width, f.height, pixels).unwrap(),
        drawn,
    )
}

#[test]
fn the_instance_keeps_one_transform_per_aperture_across_renders_and_lenses() {
    let sys = lens("heliar-tronnier");
    let mut scene = Scene {
        lights: vec![
            light(5.0, 30.0, 1.0, LightSpectrum::D65),
            light(3.0, 200.0, 1.0, LightSpectrum::Blackbody { kelvin: 2700.0 }),
        ],
        frame: frame(&sys, 160, 90),
        aperture: Aperture::Iris {
            blades: 5,
            rotation_rad: 0.0,
            roundness: 0.0,
        },
    };
    let mut plugin = StarburstFraunhofer::create().unwrap();
    plugin.prepare(&sys).unwrap();
    let (first, drawn) = render(&mut plugin, &scene, PARAMS);
    assert_eq!(drawn, 2);
    assert_eq!(plugin.transforms(), 1, "two spectra share one transform");
    let (second, _) = render(&mut plugin, &scene, PARAMS);
    assert_eq!(plugin.transforms(), 1);
    assert_eq!(first.pixels, second.pixels);

    // Another lens: new f-number and flux, the same transform.
    let other = lens("heliar-tronnier-lff");
    plugin.prepare(&other).unwrap();
    let (third, _) = render(&mut plugin, &scene, PARAMS);
    assert_eq!(plugin.transforms(), 1);
    assert_ne!(third.pixels, first.pixels);
    let expected = direct(&other, &scene, &small_settings(), 0.0);
    let c = third.compare(&expected).unwrap();
    assert!(c.relative_rmse < SAME_IMAGE_TOL, "{c:?}");

    // Another aperture or another texel count: one more transform each.
    scene.aperture = Aperture::Circular;
    render(&mut plugin, &scene, PARAMS);
    assert_eq!(plugin.transforms(), 2);
    render(&mut plugin, &scene, "texels=64,wavelengths=16");
    assert_eq!(plugin.transforms(), 3);
}

#[test]
fn a_render_before_prepare_is_an_error() {
    let sys = lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![light(5.0, 0.0, 1.0, LightSpectrum::D65)],
        frame: frame(&sys, 32, 18),
        aperture: Aperture::Circular,
    };
    let mut plugin = StarburstFraunhofer::create().unwrap();
    let specs = StarburstFraunhofer::info().params;
    let values: Vec<f64> = specs.iter().map(|s| s.default).collect();
    let mut pixels = vec![[0.0f32; 3]; 32 * 18];
    let mut out = Output {
        width: 32,
        height: 18,
        pixels: &mut pixels,
        mesh: Default::default(),
        items_drawn: 0,
    };
    let e = plugin
        .render(&scene, &Params::new(&specs, &values), &mut out)
        .unwrap_err();
    assert_eq!(e.message, "no lens prepared");
}

#[test]
fn a_light_whose_pattern_cannot_reach_the_frame_draws_nothing() {
    let sys = lens("heliar-tronnier");
    // Its image lies far outside a frame showing only the sensor's centre.
    let scene = Scene {
        lights: vec![light(15.0, 0.0, 1.0, LightSpectrum::D65)],
        frame: Frame {
            width: 40,
            height: 40,
            film_width_mm: 2.0,
            film_height_mm: 2.0,
        },
        aperture: Aperture::Circular,
    };
    let mut plugin = StarburstFraunhofer::create().unwrap();
    plugin.prepare(&sys).unwrap();
    let (img, drawn) = render(&mut plugin, &scene, PARAMS);
    assert_eq!(drawn, 0);
    assert_eq!(img.luminance_sum(), 0.0);
    assert_eq!(plugin.transforms(), 0, "nothing computed for it");
}

#[test]
fn a_transform_too_large_is_refused_with_the_reason() {
    let p = host::load(&library()).unwrap();
    let sys = lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![light(5.0, 0.0, 1.0, LightSpectrum::D65)],
        frame: frame(&sys, 32, 18),
        aperture: Aperture::Circular,
    };
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&sys).unwrap();
    // 4096 texels × padding 4 = 16384 > 8192: each value is in its range, the pair is not.
    let values = parse_values(&p.params, "texels=4096,padding=4").unwrap();
    let e = inst.render(&scene, &values).unwrap_err().to_string();
    assert!(e.contains("transform size"), "{e}");
    assert!(e.contains("16384"), "{e}");
}

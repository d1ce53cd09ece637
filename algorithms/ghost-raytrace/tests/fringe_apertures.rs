//! Fringed band groups through an iris and a mask (`flarebench_sdk::ghost::fringe`, stop flag
//! `APERTURE_FLAG`): a frame drawn with them against the same frame drawn band by band (the
//! reference of the fringe model), within the circle's bounds, and at about the circle's
//! triangle count.

use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::context::GhostStats;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::{lenses_dir, load_lens};
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Colour sums of a frame drawn fringed against band by band (relative), as the command
/// line's test of the circle (`workbench/tests/render.rs`,
/// `band_by_band_and_fringed_bands_give_the_same_light`).
const COLOUR_SUM_TOL: f64 = 1e-3;
/// Relative RMSE of a frame drawn fringed against band by band, the same bound for every
/// aperture. Measured (960 × 540, 2026-12-07): Heliar at 5°, 0° circle 0.16%, iris 0.18%,
/// mask 0.30%; at 10°, 30° circle 0.13%, iris 0.13%, mask 0.43%.
const FRINGED_RMSE: f64 = 0.01;
/// An iris's or a mask's triangles over the circle's, both fringed.
const TRIANGLES_OVER_CIRCLE: f64 = 1.3;

/// A six-blade iris with rounded blades, turned.
fn iris() -> Aperture {
    Aperture::Iris {
        blades: 6,
        rotation_rad: 0.3,
        roundness: 0.2,
    }
}

/// OpenLensFlare's aperture mask (`lenses/masks/aperture.bmp`), as `bench --aperture mask`.
fn olf_mask() -> Aperture {
    let img = image::open(lenses_dir().join("masks/aperture.bmp"))
        .expect("the bundled mask")
        .to_luma8();
    let (w, h) = img.dimensions();
    Aperture::Mask(ApertureMask::from_luma(w as usize, h as usize, img.as_raw()).expect("a mask"))
}

/// The frame of `lens` with `light` at 960 × 540, default quality, through `aperture`: its
/// image and triangle count.
fn frame(lens: &str, light: &str, aperture: &Aperture, band_by_band: bool) -> (HdrImage, usize) {
    let sys = load_lens(lens);
    let frame = Frame::across_film(960, 540, sys.film_width_mm);
    let lights = [LightSpec::parse(light).unwrap()];
    let opts = PlanOptions::for_quality(Quality::Default, None);
    let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let options = RenderOptions {
        band_by_band,
        ..RenderOptions::default()
    };
    let (img, stats) = ghosts::render_with(&sys, aperture, frame, &plans, options).unwrap();
    let triangles = stats
        .iter()
        .flatten()
        .map(|s: &GhostStats| s.triangles)
        .sum();
    (img, triangles)
}

fn check(lens: &str, light: &str) {
    let (_, circle) = frame(lens, light, &Aperture::Circular, false);
    for (name, aperture) in [
        ("circle", Aperture::Circular),
        ("iris", iris()),
        ("mask", olf_mask()),
    ] {
        let (fringed, triangles) = frame(lens, light, &aperture, false);
        let (bands, band_triangles) = frame(lens, light, &aperture, true);
        assert!(!fringed.has_non_finite(), "{lens} {name}");
        let c = fringed.compare(&bands).unwrap();
        let (a, b) = (fringed.sum(), bands.sum());
        eprintln!(
            "{lens} {light} {name}: {triangles} triangles fringed, {band_triangles} band by band \
             (circle fringed {circle}); fringed against band by band: rel RMSE {:.3e}, \
             energy {:.2e}, sums {a:?} against {b:?}",
            c.relative_rmse, c.energy_error
        );
        assert!(
            triangles as f64 <= TRIANGLES_OVER_CIRCLE * circle as f64,
            "{lens} {name}: {triangles} triangles against the circle's {circle}"
        );
        assert!(
            (triangles as f64) < 0.5 * band_triangles as f64,
            "{lens} {name}: fringed groups drawn: {triangles} against {band_triangles}"
        );
        for ch in 0..3 {
            assert!(
                (a[ch] / b[ch] - 1.0).abs() < COLOUR_SUM_TOL,
                "{lens} {name}: channel {ch}: {} against {}",
                a[ch],
                b[ch]
            );
        }
        assert!(
            c.relative_rmse < FRINGED_RMSE,
            "{lens} {name}: rel RMSE {:.3e}",
            c.relative_rmse
        );
    }
}

/// The scene: the Heliar at 5°, where the iris and the mask drew about 5× the
/// circle's triangles band by band.
#[test]
fn heliar_iris_and_mask_fringed_like_the_circle() {
    check("heliar-tronnier", "5,0");
    check("heliar-tronnier", "10,30");
}

//! The sprite baseline puts each sprite's energy where its layout says: on the line through
//! the light's image and the centre.

use flarebench_sdk::abi::author::{Scene, SceneLight};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use ghost_sprite::{SPRITES, draw, light_image_px};

fn scene(aperture: Aperture) -> Scene {
    Scene {
        lights: vec![SceneLight {
            theta_deg: 4.0,
            phi_deg: 60.0,
            intensity: 3.0,
            spectrum: LightSpectrum::D65,
        }],
        frame: Frame {
            width: 400,
            height: 300,
            film_width_mm: 36.0,
            film_height_mm: 27.0,
        },
        aperture,
    }
}

/// The rasterizer conserves energy to f32 rounding of the pixel sums (measured < 1e-6).
const ENERGY_TOL: f64 = 1e-4;
/// Centroid of a convex polygon drawn with exact coverage: its centre, to f32 rounding.
const CENTROID_TOL_PX: f64 = 1e-2;
/// The light's image against EFL tan θ converted to pixels: f64 rounding of a closed form over
/// a few operations.
const LIGHT_IMAGE_TOL_PX: f64 = 1e-3;

#[test]
fn one_sprite_carries_gain_times_intensity_at_its_place_on_the_line() {
    let efl = 50.0;
    for aperture in [
        Aperture::Circular,
        Aperture::Iris {
            blades: 6,
            rotation_rad: 0.3,
            roundness: 0.0,
        },
    ] {
        let s = scene(aperture);
        let mut img = HdrImage::new(400, 300);
        // The first sprite only: t = -1.2, weight 1, tint (0.55, 0.75, 1).
        let n = draw(efl, &s, 0.05, 2.0, 1, &mut img);
        assert_eq!(n, 1);
        let sum = img.sum();
        let expect = 2.0 * 3.0 * SPRITES[0].weight;
        for (c, tint) in sum.iter().zip(SPRITES[0].tint) {
            assert!(
                (c / (expect * tint as f64) - 1.0).abs() < ENERGY_TOL,
                "{sum:?}"
            );
        }
        let (mut e, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for (k, p) in img.pixels.iter().enumerate() {
            let v = p[2] as f64;
            e += v;
            sx += v * ((k % 400) as f64 + 0.5);
            sy += v * ((k / 400) as f64 + 0.5);
        }
        let l = light_image_px(efl, &s.frame, 4.0, 60.0);
        let t = SPRITES[0].t;
        let expect = [200.0 + t * (l[0] - 200.0), 150.0 + t * (l[1] - 150.0)];
        assert!(
            (sx / e - expect[0]).abs() < CENTROID_TOL_PX,
            "{} vs {expect:?}",
            sx / e
        );
        assert!(
            (sy / e - expect[1]).abs() < CENTROID_TOL_PX,
            "{} vs {expect:?}",
            sy / e
        );
    }
}

#[test]
fn the_light_image_is_opposite_the_light_at_efl_tan_theta() {
    let s = scene(Aperture::Circular);
    // φ = 0: rays tilt toward +y, the image falls at sensor y = −EFL tan θ, which is above
    // the centre in the photograph (`Frame::to_pixel`: y down in pixels is +y on the sensor).
    let [x, y] = light_image_px(50.0, &s.frame, 4.0, 0.0);
    let px_mm = 36.0 / 400.0;
    assert!((x - 200.0).abs() < LIGHT_IMAGE_TOL_PX);
    assert!(
        (y - (150.0 - 50.0 * 4f64.to_radians().tan() / px_mm)).abs() < LIGHT_IMAGE_TOL_PX,
        "{y}"
    );
}

//! Composing a flare: the starburst of every light added to the ghosts' linear HDR image, and
//! the flare added onto a background image.
//!
//! **Starbursts** ([`add_starbursts`]): per light, the chief ray's landing point
//! (`starburst::chief_ray_landing` at the d line, azimuth turned as the ghosts' meshes are),
//! the light's flux through the lens — its intensity × the direct image's flux at its angle
//! (`ghost::bounds::direct_flux` at 550 nm, the same figure the ghosts' energy shares are
//! relative to) — and the aperture's spectral pattern for the light's spectrum (cached per
//! aperture and spectrum), added at the working f-number's scale (`docs/starburst.md`). A
//! light whose pattern cannot reach the frame is left out and reported.
//!
//! **Background** ([`add_onto`]): the flare is added to the background in linear light,
//! pixel by pixel; where the flare is zero the background's value is kept bit for bit.

use anyhow::{Context, Result, ensure};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds::direct_flux;
use flarebench_sdk::ghost::render::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::{
    StarburstCache, StarburstSettings, add_starburst, chief_ray_landing,
};
use flarebench_sdk::trace::InterfaceTableSet;
use ghost_raytrace::scene::LightSpec;
use serde::Serialize;

/// Wavelength of the direct-flux figure (nm): the ghost planner's (`plan::BOUNDS_LAMBDA_NM`).
const FLUX_LAMBDA_NM: f64 = 550.0;

/// What happened to one light's starburst.
#[derive(Clone, Debug, Serialize)]
pub struct StarburstLine {
    /// Index of the light (order given).
    pub light: usize,
    /// Where the chief ray lands (pixels of the output, x right, y down), if it does.
    pub position_px: Option<[f64; 2]>,
    /// Flux of the light through the lens (image units): the starburst's whole energy.
    pub flux: f64,
    /// Luminance added to the image, and the part of the pattern outside the frame.
    pub added: f64,
    pub outside: f64,
    /// How far the pattern reaches from its centre (pixels).
    pub reach_px: f64,
    /// Why it was left out (`"chief ray lost"`, `"off frame"`), or null.
    pub left_out: Option<String>,
}

/// The aperture and settings starbursts are made with.
#[derive(Clone, Copy, Debug)]
pub struct StarburstSetup<'a> {
    pub aperture: &'a Aperture,
    /// Optional dust/scratch overlay on the aperture.
    pub dust: Option<&'a ApertureMask>,
    pub settings: StarburstSettings,
}

/// Adds the starburst of every light to `img` (the frame's size).
pub fn add_starbursts(
    img: &mut HdrImage,
    system: &LensSystem,
    frame: &Frame,
    lights: &[LightSpec],
    setup: &StarburstSetup<'_>,
    cache: &mut StarburstCache,
) -> Result<Vec<StarburstLine>> {
    let para = analyse(system, LAMBDA_D_NM).context("paraxial analysis")?;
    let tables = InterfaceTableSet::for_system(system, FLUX_LAMBDA_NM);
    let mut scratch = GridTrace::default();
    let mut lines = Vec::with_capacity(lights.len());
    for (k, light) in lights.iter().enumerate() {
        let theta = light.theta_deg.to_radians();
        let phi = light.phi_deg.to_radians();
        let flux = light.intensity * direct_flux(system, &tables, theta, &mut scratch);
        let mut line = StarburstLine {
            light: k,
            position_px: None,
            flux,
            added: 0.0,
            outside: 0.0,
            reach_px: 0.0,
            left_out: None,
        };
        let centre = match chief_ray_landing(system, LAMBDA_D_NM, theta, phi) {
            Ok(c) => c,
            Err(_) => {
                line.left_out = Some("chief ray lost".into());
                lines.push(line);
                continue;
            }
        };
        let [px, py] = frame.to_pixel(centre[0], centre[1]).map(f64::from);
        line.position_px = Some([px, py]);
        // The pattern reaches ±pupil_texels·λ·N/2 (at most 780 nm): skip it when that
        // cannot touch the frame.
        let reach_mm = setup.settings.pupil_texels as f64 * 780e-6 * para.f_number / 2.0;
        let (hw, hh) = (0.5 * frame.film_width_mm, 0.5 * frame.film_height_mm);
        if centre[0].abs() > hw + reach_mm || centre[1].abs() > hh + reach_mm {
            line.left_out = Some("off frame".into());
            line.outside = flux;
            lines.push(line);
            continue;
        }
        let pattern = cache
            .pattern(setup.aperture, setup.dust, &setup.settings, light.spectrum)
            .context("starburst")?;
        let st = add_starburst(img, frame, &pattern, centre, para.f_number, flux)
            .context("starburst")?;
        line.added = st.added;
        line.outside = st.outside;
        line.reach_px = st.reach_px;
        lines.push(line);
    }
    Ok(lines)
}

/// Adds `flare` onto `background` (same size) in linear light.
pub fn add_onto(background: &HdrImage, flare: &HdrImage) -> Result<HdrImage> {
    ensure!(
        (background.width, background.height) == (flare.width, flare.height),
        "the background is {}×{} but the flare {}×{}",
        background.width,
        background.height,
        flare.width,
        flare.height
    );
    let mut out = background.clone();
    for (o, f) in out.pixels.iter_mut().zip(&flare.pixels) {
        for c in 0..3 {
            // x + 0 = x exactly, so untouched pixels keep their bits.
            if f[c] != 0.0 {
                o[c] += f[c];
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_background_is_kept_where_the_flare_is_zero() {
        let bg = HdrImage::from_pixels(
            3,
            1,
            vec![[0.25, -0.0, 7.5], [1e-30, 3.0, 0.5], [f32::MAX, 0.1, 0.2]],
        )
        .unwrap();
        let flare =
            HdrImage::from_pixels(3, 1, vec![[0.0; 3], [0.5, 0.0, 0.25], [0.0; 3]]).unwrap();
        let out = add_onto(&bg, &flare).unwrap();
        assert_eq!(
            out.pixels[0].map(f32::to_bits),
            bg.pixels[0].map(f32::to_bits)
        );
        assert_eq!(
            out.pixels[2].map(f32::to_bits),
            bg.pixels[2].map(f32::to_bits)
        );
        assert_eq!(out.pixels[1], [0.5 + 1e-30, 3.0, 0.75]);
        assert!(add_onto(&bg, &HdrImage::new(2, 1)).is_err());
    }
}

//! Composing a flare: the starburst of every light added to the ghosts' linear HDR image, and
//! the flare added onto a background image.
//!
//! **Starbursts** ([`add_starbursts`]): per light, `flarebench_sdk::starburst::StarburstLens`
//! (the chief ray's landing point, the light's flux through the lens, the aperture's spectral
//! pattern at the working f-number's scale — `docs/starburst.md`), the same code the
//! `starburst-fraunhofer` plugin runs; a light whose pattern cannot reach the frame, or whose
//! chief ray is lost, is left out and reported.
//!
//! **Background** ([`add_onto`]): the flare is added to the background in linear light,
//! pixel by pixel; where the flare is zero the background's value is kept bit for bit.

use anyhow::{Context, Result, ensure};
use flarebench_sdk::LensSystem;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::{
    StarburstCache, StarburstLens, StarburstLight, StarburstOutcome, StarburstSource,
    StarburstSplat, StarburstTarget, splat_stats,
};
use ghost_raytrace::scene::LightSpec;
use serde::Serialize;

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
pub type StarburstSetup<'a> = StarburstSource<'a>;

/// Adds the starburst of every light to `img` (the frame's size) —
/// [`StarburstLens::add`] per light — and reports each.
pub fn add_starbursts(
    img: &mut HdrImage,
    system: &LensSystem,
    frame: &Frame,
    lights: &[LightSpec],
    setup: &StarburstSetup<'_>,
    cache: &mut StarburstCache,
) -> Result<Vec<StarburstLine>> {
    let lens = StarburstLens::new(system).context("paraxial analysis")?;
    let mut scratch = GridTrace::default();
    let mut lines = Vec::with_capacity(lights.len());
    let mut target = StarburstTarget { img, frame };
    for (k, light) in lights.iter().enumerate() {
        let o = lens
            .add(
                system,
                &mut target,
                &starburst_light(light),
                setup,
                cache,
                &mut scratch,
            )
            .context("starburst")?;
        lines.push(line(k, frame, &o));
    }
    Ok(lines)
}

/// The starburst of every light placed on `frame` but not drawn (a backend that composites
/// the patterns itself, the GPU's): each light's report line — what would be added, from
/// `flarebench_sdk::starburst::splat_stats` — and the splats to draw.
pub fn place_starbursts(
    system: &LensSystem,
    frame: &Frame,
    lights: &[LightSpec],
    setup: &StarburstSetup<'_>,
    cache: &mut StarburstCache,
) -> Result<(Vec<StarburstLine>, Vec<StarburstSplat>)> {
    let lens = StarburstLens::new(system).context("paraxial analysis")?;
    let mut scratch = GridTrace::default();
    let mut lines = Vec::with_capacity(lights.len());
    let mut splats = Vec::with_capacity(lights.len());
    for (k, light) in lights.iter().enumerate() {
        let sl = starburst_light(light);
        let (mut o, splat) = lens
            .place(system, frame, &sl, setup, cache, &mut scratch)
            .context("starburst")?;
        if let Some(sp) = splat {
            o.drawn = Some(
                splat_stats(frame, &sp.pattern, sp.centre_mm, sp.f_number, sp.flux)
                    .context("starburst")?,
            );
            splats.push(sp);
        }
        lines.push(line(k, frame, &o));
    }
    Ok((lines, splats))
}

fn starburst_light(light: &LightSpec) -> StarburstLight {
    StarburstLight {
        theta_deg: light.theta_deg,
        phi_deg: light.phi_deg,
        intensity: light.intensity,
        spectrum: light.spectrum,
    }
}

/// The report line of light `k`'s starburst.
fn line(k: usize, frame: &Frame, o: &StarburstOutcome) -> StarburstLine {
    let position_px = o
        .centre_mm
        .map(|c| frame.to_pixel(c[0], c[1]).map(f64::from));
    let (added, outside, reach_px, left_out) = match (o.drawn, o.centre_mm) {
        (Some(st), _) => (st.added, st.outside, st.reach_px, None),
        (None, Some(_)) => (0.0, o.flux, 0.0, Some("off frame".to_string())),
        (None, None) => (0.0, 0.0, 0.0, Some("chief ray lost".to_string())),
    };
    StarburstLine {
        light: k,
        position_px,
        flux: o.flux,
        added,
        outside,
        reach_px,
        left_out,
    }
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

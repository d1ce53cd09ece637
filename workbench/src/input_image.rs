//! Reading images to put a flare on (`render --background`, `apply`): OpenEXR (linear, any
//! channel type) or PNG/BMP (8- or 16-bit sRGB, decoded to linear with the IEC 61966-2-1
//! transfer function; alpha ignored).

use std::path::Path;

use anyhow::{Context, Result, bail};
use flarebench_sdk::color::srgb;
use flarebench_sdk::image::HdrImage;

use crate::output::read_exr;

/// An image read for composition.
#[derive(Clone, Debug)]
pub struct InputImage {
    /// Linear RGB.
    pub image: HdrImage,
    /// True for OpenEXR (scene-referred, values above 1 are real); false for PNG/BMP
    /// (display-referred, 1 is clipped white).
    pub hdr: bool,
}

/// Reads `path` by its extension: `.exr`, `.png` or `.bmp` (any case).
pub fn read_input_image(path: &Path) -> Result<InputImage> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("exr") => Ok(InputImage {
            image: read_exr(path)?,
            hdr: true,
        }),
        Some("png") | Some("bmp") => Ok(InputImage {
            image: read_ldr(path)
                .with_context(|| format!("could not read image `{}`", path.display()))?,
            hdr: false,
        }),
        _ => bail!(
            "`{}`: unknown image extension; use .exr (linear HDR), .png or .bmp (sRGB)",
            path.display()
        ),
    }
}

fn read_ldr(path: &Path) -> Result<HdrImage> {
    let img = image::ImageReader::open(path)?
        .with_guessed_format()?
        .decode()?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let pixels = if img.color().bytes_per_pixel() / img.color().channel_count() > 1 {
        img.to_rgb16()
            .pixels()
            .map(|p| p.0.map(|c| srgb::decode(f32::from(c) / 65535.0)))
            .collect()
    } else {
        img.to_rgb8()
            .pixels()
            .map(|p| p.0.map(|c| srgb::decode(f32::from(c) / 255.0)))
            .collect()
    };
    Ok(HdrImage::from_pixels(w, h, pixels)?)
}

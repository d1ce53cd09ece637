//! Aperture mask images: BMP and PNG files decoded with the `image` crate into the sdk's
//! [`ApertureMask`] (the sdk itself has no image dependencies), and where a lens file's
//! `<mask>` name points.
//!
//! Two kinds of grey image are in use (docs/formats.md §9):
//! - **transmission**: white open, black closed (`lenses/masks/aperture.bmp`);
//! - **OpenLensFlare distance map**: dark at the centre, rising toward the edge of the opening
//!   and white outside (`lenses/masks/apertureDist.bmp`, the mask the Heliar-Tronnier's stop
//!   names). OpenLensFlare opens the aperture where the map is below 0.95
//!   ([`OLF_DISTANCE_CLIP`]).
//!
//! Colour images are reduced to luma (the `image` crate's Rec. 709 weights on the stored
//! values); alpha is ignored. The image's top row is v = +1 (`ApertureMask` layout).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use flarebench_sdk::aperture::{ApertureMask, OLF_DISTANCE_CLIP};

/// How a mask image's grey levels are read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaskEncoding {
    /// Grey level = transmission (white open).
    Transmission,
    /// An OpenLensFlare distance map: open where the grey level (0..=1) is below `clip`.
    OlfDistanceMap { clip: f32 },
    /// Decided from the image: a dark centre (below 1/2) inside a bright border (mean above
    /// 1/2) can only be a distance map — a transmission mask is open at its centre or closed
    /// at its border — and is read with [`OLF_DISTANCE_CLIP`]; anything else is a
    /// transmission.
    Auto,
}

/// A decoded mask and the encoding it was read with (never `Auto`).
#[derive(Clone, Debug)]
pub struct LoadedMask {
    pub mask: ApertureMask,
    pub encoding: MaskEncoding,
}

/// Reads a BMP or PNG aperture mask. Errors name the file.
pub fn load_aperture_mask(path: &Path, encoding: MaskEncoding) -> Result<LoadedMask> {
    decode(path, encoding).with_context(|| {
        format!(
            "could not read aperture mask `{}` (BMP or PNG, grey levels)",
            path.display()
        )
    })
}

fn decode(path: &Path, encoding: MaskEncoding) -> Result<LoadedMask> {
    let image = image::ImageReader::open(path)?
        .with_guessed_format()?
        .decode()?;
    let (width, height) = (image.width() as usize, image.height() as usize);
    let luma = image.to_luma32f().into_raw();
    let encoding = match encoding {
        MaskEncoding::Auto if looks_like_distance_map(width, height, &luma) => {
            MaskEncoding::OlfDistanceMap {
                clip: OLF_DISTANCE_CLIP,
            }
        }
        MaskEncoding::Auto => MaskEncoding::Transmission,
        chosen => chosen,
    };
    // `to_luma32f` scales integer samples into 0..=1; clamp float images' stray values.
    let luma: Vec<f32> = luma.into_iter().map(|v| v.clamp(0.0, 1.0)).collect();
    let mask = match encoding {
        MaskEncoding::OlfDistanceMap { clip } => {
            ApertureMask::from_olf_distance_map(width, height, &luma, clip)?
        }
        _ => ApertureMask::from_luma_f32(width, height, &luma)?,
    };
    Ok(LoadedMask { mask, encoding })
}

/// A dark centre inside a bright border (see [`MaskEncoding::Auto`]).
fn looks_like_distance_map(width: usize, height: usize, luma: &[f32]) -> bool {
    if width < 3 || height < 3 {
        return false;
    }
    let at = |row: usize, col: usize| luma[row * width + col];
    // The centre: the mean of the (up to four) texels around the image's middle.
    let (r0, r1) = ((height - 1) / 2, height / 2);
    let (c0, c1) = ((width - 1) / 2, width / 2);
    let centre = (at(r0, c0) + at(r0, c1) + at(r1, c0) + at(r1, c1)) / 4.0;
    let border: Vec<f32> = (0..width)
        .flat_map(|c| [at(0, c), at(height - 1, c)])
        .chain((1..height - 1).flat_map(|r| [at(r, 0), at(r, width - 1)]))
        .collect();
    let border_mean = border.iter().sum::<f32>() / border.len() as f32;
    centre < 0.5 && border_mean > 0.5
}

/// Where the mask named `name` in the lens file `lens_file` is: beside the lens file, or in a
/// `masks/` folder beside it (the library keeps its masks in `lenses/masks/`). `None` when
/// neither exists.
pub fn resolve_mask_path(lens_file: &Path, name: &str) -> Option<PathBuf> {
    let dir = lens_file.parent().unwrap_or(Path::new(""));
    [dir.join(name), dir.join("masks").join(name)]
        .into_iter()
        .find(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lenses() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses")
    }

    /// Both OpenLensFlare masks are regular octagons of apothem about 0.95: `aperture.bmp` has
    /// 195 584 of its 512² texels open (the file, counted), so its area is exactly
    /// 195584 / 512² × 4.
    const OCTAGON_AREA: f64 = 195_584.0 / 262_144.0 * 4.0;

    #[test]
    fn olf_aperture_bmp_loads_as_a_transmission_octagon() {
        let path = lenses().join("masks/aperture.bmp");
        let loaded = load_aperture_mask(&path, MaskEncoding::Auto).unwrap();
        assert_eq!(loaded.encoding, MaskEncoding::Transmission);
        let m = &loaded.mask;
        assert_eq!((m.width(), m.height()), (512, 512));
        assert!(
            (m.open_area() - OCTAGON_AREA).abs() < 1e-12,
            "{}",
            m.open_area()
        );
        // Flat edges face ±u and ±v at 243 texels from the centre (0.949); corners closed.
        assert_eq!(m.transmission(0.0, 0.0), 1.0);
        assert_eq!(m.transmission(0.0, 0.93), 1.0);
        assert_eq!(m.transmission(0.96, 0.0), 0.0);
        assert_eq!(m.transmission(0.9, 0.9), 0.0);
        assert!((m.signed_distance(0.0, 0.0) + 0.949).abs() < 0.01);
    }

    #[test]
    fn olf_distance_map_is_recognised_and_opens_the_same_octagon() {
        let path = lenses().join("masks/apertureDist.bmp");
        let auto = load_aperture_mask(&path, MaskEncoding::Auto).unwrap();
        assert_eq!(
            auto.encoding,
            MaskEncoding::OlfDistanceMap {
                clip: OLF_DISTANCE_CLIP
            }
        );
        // Thresholded at 0.95 it is the octagon of aperture.bmp to within a texel's width
        // along the edge (counted: 195 032 open texels against 195 584, 0.28 % smaller).
        let area = auto.mask.open_area();
        assert!((area / OCTAGON_AREA - 1.0).abs() < 0.01, "{area}");
        // Read as a transmission it would be nearly closed at the centre: the reason for
        // telling the two apart.
        let raw = load_aperture_mask(&path, MaskEncoding::Transmission).unwrap();
        assert!(raw.mask.transmission(0.0, 0.0) < 0.05);
    }

    #[test]
    fn png_masks_load_with_the_top_row_at_v_plus_one() {
        let dir = tempfile::Builder::new()
            .prefix("flarebench-mask-")
            .tempdir()
            .unwrap();
        let path = dir.path().join("half.png");
        // 4 × 2: the top row open, the bottom closed.
        image::GrayImage::from_raw(4, 2, vec![255, 255, 255, 255, 0, 0, 0, 0])
            .unwrap()
            .save(&path)
            .unwrap();
        let m = load_aperture_mask(&path, MaskEncoding::Transmission)
            .unwrap()
            .mask;
        dir.close().unwrap();
        assert_eq!((m.width(), m.height()), (4, 2));
        assert_eq!(m.transmission(0.0, 0.9), 1.0);
        assert_eq!(m.transmission(0.0, -0.9), 0.0);
        assert!((m.open_area() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn unreadable_masks_are_errors_naming_the_file() {
        let missing = lenses().join("masks/no-such-mask.bmp");
        let e = format!(
            "{:#}",
            load_aperture_mask(&missing, MaskEncoding::Auto).unwrap_err()
        );
        assert!(e.contains("no-such-mask.bmp"), "{e}");
        let not_image = lenses().join("heliar-tronnier.xml");
        let e = format!(
            "{:#}",
            load_aperture_mask(&not_image, MaskEncoding::Auto).unwrap_err()
        );
        assert!(
            e.starts_with("could not read aperture mask `") && e.contains("heliar-tronnier.xml"),
            "{e}"
        );
    }

    #[test]
    fn library_masks_resolve_from_the_lens_file() {
        let lens = lenses().join("heliar-tronnier.xml");
        let found = resolve_mask_path(&lens, "apertureDist.bmp").unwrap();
        assert!(
            found.ends_with("masks/apertureDist.bmp"),
            "{}",
            found.display()
        );
        assert_eq!(resolve_mask_path(&lens, "nothing.bmp"), None);
    }
}

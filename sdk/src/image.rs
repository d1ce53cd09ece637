//! [`HdrImage`]: a linear-RGB floating-point image (row-major, `f32` per channel), with the
//! sums and comparison metrics the error reports use.
//!
//! Pixel `(x, y)` covers `[x, x + 1) × [y, y + 1)` in pixel coordinates, x to the right and y
//! down, and is stored at `pixels[y * width + x]`.

mod upsample;

use rayon::prelude::*;
use serde::Serialize;

pub use upsample::{
    Blend, CoarseGrid, RowSpans, SpannedLevel, add_upsampled, add_upsampled_into,
    add_upsampled_levels_into, row_spans, upsample_levels_into, upsample_spans_into,
};

use crate::color::srgb::LUMINANCE_WEIGHTS;

/// Makes every pixel of a row-major buffer black, in chunks spread over the cores
/// ([`HdrImage::fill_black`]; also a replacing upsampling pass with no level).
pub(crate) fn fill_black(pixels: &mut [[f32; 3]]) {
    /// Pixels a chunk (384 KB): large enough that handing chunks out costs nothing.
    const CHUNK: usize = 1 << 15;
    pixels
        .par_chunks_mut(CHUNK)
        .for_each(|chunk| chunk.fill([0.0; 3]));
}

/// A linear-RGB HDR image. Invariant: `pixels.len() == width * height` (the constructors
/// ensure it; code that edits the public fields must keep it).
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major linear RGB, `pixels[y * width + x]`.
    pub pixels: Vec<[f32; 3]>,
}

/// Two images (or an image and its pixel buffer) do not have the same size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "image size mismatch: {got_width}×{got_height} (or {got_len} pixels) against {width}×{height}"
)]
pub struct ImageSizeError {
    /// Expected width.
    pub width: usize,
    /// Expected height.
    pub height: usize,
    /// Width of the other image.
    pub got_width: usize,
    /// Height of the other image.
    pub got_height: usize,
    /// Number of pixels of the other image.
    pub got_len: usize,
}

/// How far an image is from a reference (see [`HdrImage::compare`]). Each is 0 for equal
/// images; a zero reference gives 0 when the image is zero too and +∞ otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImageComparison {
    /// `sqrt(Σ (a − b)²) / sqrt(Σ b²)` over every pixel and channel.
    pub relative_rmse: f64,
    /// `Σ |a − b| / Σ |b|` over every pixel and channel.
    pub relative_l1: f64,
    /// `(Σ a − Σ b) / Σ b`, sums over every pixel and channel: the share of energy gained (> 0)
    /// or lost (< 0).
    pub energy_error: f64,
}

impl HdrImage {
    /// A black image.
    ///
    /// # Panics
    /// If `width * height` overflows `usize`.
    pub fn new(width: usize, height: usize) -> HdrImage {
        let len = width
            .checked_mul(height)
            .expect("image width × height fits in usize");
        HdrImage {
            width,
            height,
            pixels: vec![[0.0; 3]; len],
        }
    }

    /// An image over existing row-major pixels; an error unless `pixels.len() == width * height`.
    pub fn from_pixels(
        width: usize,
        height: usize,
        pixels: Vec<[f32; 3]>,
    ) -> Result<HdrImage, ImageSizeError> {
        if width.checked_mul(height) != Some(pixels.len()) {
            return Err(ImageSizeError {
                width,
                height,
                got_width: width,
                got_height: height,
                got_len: pixels.len(),
            });
        }
        Ok(HdrImage {
            width,
            height,
            pixels,
        })
    }

    /// Makes every pixel black, in chunks spread over the cores: how a frame buffer kept from
    /// frame to frame is cleared (1920 × 1080 on the 2-core machine of docs/performance.md:
    /// 2.0 ms on one core, 1.6 ms on two — the memory's bandwidth, not the cores, bounds it).
    pub fn fill_black(&mut self) {
        fill_black(&mut self.pixels);
    }

    /// Makes black the columns `spans[y].0..spans[y].1` of each row `y` (clamped to the
    /// image; rows in parallel): the whole image when it is black outside them, as after an
    /// upsampling pass that found them ([`row_spans`]).
    ///
    /// # Panics
    /// If there is not one span a row.
    pub fn clear_spans(&mut self, spans: &[(usize, usize)]) {
        assert_eq!(spans.len(), self.height, "one span a row");
        if self.width == 0 {
            return;
        }
        let width = self.width;
        self.pixels
            .par_chunks_mut(width)
            .zip(spans)
            .for_each(|(row, &(a, b))| {
                let b = b.min(width);
                if a < b {
                    row[a..b].fill([0.0; 3]);
                }
            });
    }

    /// The pixel at `(x, y)`, or `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        (x < self.width && y < self.height).then(|| self.pixels[y * self.width + x])
    }

    /// The pixel at `(x, y)` for writing, or `None` outside the image.
    pub fn get_mut(&mut self, x: usize, y: usize) -> Option<&mut [f32; 3]> {
        if x < self.width && y < self.height {
            Some(&mut self.pixels[y * self.width + x])
        } else {
            None
        }
    }

    /// Adds `other` pixel by pixel; an error (and no change) if the sizes differ.
    pub fn add_image(&mut self, other: &HdrImage) -> Result<(), ImageSizeError> {
        self.add_scaled(other, 1.0)
    }

    /// Adds `scale × other` pixel by pixel; an error (and no change) if the sizes differ.
    pub fn add_scaled(&mut self, other: &HdrImage, scale: f32) -> Result<(), ImageSizeError> {
        self.check_same_size(other)?;
        for (p, q) in self.pixels.iter_mut().zip(&other.pixels) {
            for c in 0..3 {
                p[c] += scale * q[c];
            }
        }
        Ok(())
    }

    /// Multiplies every channel by `s`.
    pub fn scale(&mut self, s: f32) {
        for p in &mut self.pixels {
            for v in p {
                *v *= s;
            }
        }
    }

    /// Per-channel sums `[Σ R, Σ G, Σ B]`, accumulated in f64.
    pub fn sum(&self) -> [f64; 3] {
        let mut s = [0.0_f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                s[c] += f64::from(p[c]);
            }
        }
        s
    }

    /// `Σ Y` with `Y = 0.2126 R + 0.7152 G + 0.0722 B` (linear sRGB luminance), in f64.
    pub fn luminance_sum(&self) -> f64 {
        let s = self.sum();
        LUMINANCE_WEIGHTS[0] * s[0] + LUMINANCE_WEIGHTS[1] * s[1] + LUMINANCE_WEIGHTS[2] * s[2]
    }

    /// The largest channel value (NaN is ignored); `-∞` for an image without pixels.
    pub fn max(&self) -> f32 {
        self.pixels
            .iter()
            .flatten()
            .fold(f32::NEG_INFINITY, |m, &v| m.max(v))
    }

    /// Whether any channel is NaN or infinite.
    pub fn has_non_finite(&self) -> bool {
        self.pixels.iter().flatten().any(|v| !v.is_finite())
    }

    /// Relative RMSE against `reference`: `sqrt(Σ |a − b|²) / sqrt(Σ |b|²)` over every pixel
    /// and channel.
    pub fn relative_rmse(&self, reference: &HdrImage) -> Result<f64, ImageSizeError> {
        Ok(self.compare(reference)?.relative_rmse)
    }

    /// Relative L1 error against `reference`: `Σ |a − b| / Σ |b|`.
    pub fn relative_l1(&self, reference: &HdrImage) -> Result<f64, ImageSizeError> {
        Ok(self.compare(reference)?.relative_l1)
    }

    /// Total-energy error against `reference`: `(Σ a − Σ b) / Σ b` over every pixel and channel.
    pub fn energy_error(&self, reference: &HdrImage) -> Result<f64, ImageSizeError> {
        Ok(self.compare(reference)?.energy_error)
    }

    /// All three metrics in one pass (f64 accumulation); `self` is `a`, `reference` is `b`.
    pub fn compare(&self, reference: &HdrImage) -> Result<ImageComparison, ImageSizeError> {
        self.check_same_size(reference)?;
        let (mut d2, mut b2, mut d1, mut b1, mut sa, mut sb) = (0.0_f64, 0.0, 0.0, 0.0, 0.0, 0.0);
        for (p, q) in self.pixels.iter().zip(&reference.pixels) {
            for c in 0..3 {
                let (a, b) = (f64::from(p[c]), f64::from(q[c]));
                let d = a - b;
                d2 += d * d;
                b2 += b * b;
                d1 += d.abs();
                b1 += b.abs();
                sa += a;
                sb += b;
            }
        }
        Ok(ImageComparison {
            relative_rmse: ratio(d2.sqrt(), b2.sqrt()),
            relative_l1: ratio(d1, b1),
            energy_error: ratio(sa - sb, sb),
        })
    }

    fn check_same_size(&self, other: &HdrImage) -> Result<(), ImageSizeError> {
        if other.width == self.width
            && other.height == self.height
            && other.pixels.len() == self.pixels.len()
        {
            Ok(())
        } else {
            Err(ImageSizeError {
                width: self.width,
                height: self.height,
                got_width: other.width,
                got_height: other.height,
                got_len: other.pixels.len(),
            })
        }
    }
}

/// `num / den`, with 0 / 0 = 0 and x / 0 = ±∞.
fn ratio(num: f64, den: f64) -> f64 {
    if den == 0.0 {
        if num == 0.0 {
            0.0
        } else {
            f64::INFINITY.copysign(num)
        }
    } else {
        num / den
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(pixels: &[[f32; 3]]) -> HdrImage {
        HdrImage::from_pixels(pixels.len(), 1, pixels.to_vec()).unwrap()
    }

    #[test]
    fn clearing_an_image_s_lit_spans_makes_it_black() {
        let (w, h) = (37, 9);
        let mut a = HdrImage::new(w, h);
        for (k, p) in a.pixels.iter_mut().enumerate() {
            // Sparse rows of scattered pixels, some rows black.
            if (k * 7919) % 11 < 2 && (k / w) % 3 != 1 {
                *p = [k as f32, 0.0, 0.5];
            }
        }
        let spans = row_spans(&a);
        assert_eq!(spans.len(), h);
        for (y, &(first, end)) in spans.iter().enumerate() {
            let row = &a.pixels[y * w..(y + 1) * w];
            let lit: Vec<usize> = (0..w).filter(|&x| row[x] != [0.0; 3]).collect();
            match (lit.first(), lit.last()) {
                (Some(&f), Some(&l)) => assert_eq!((first, end), (f, l + 1), "row {y}"),
                _ => assert_eq!((first, end), (0, 0), "row {y}"),
            }
        }
        assert!(a.pixels.iter().any(|p| *p != [0.0; 3]));
        a.clear_spans(&spans);
        assert!(a.pixels.iter().all(|p| *p == [0.0; 3]));
        // Spans past the width are clamped.
        let mut b = HdrImage::new(4, 2);
        b.pixels.fill([1.0; 3]);
        b.clear_spans(&[(1, 99), (0, 0)]);
        assert_eq!(b.pixels[0], [1.0; 3]);
        assert!(b.pixels[1..4].iter().all(|p| *p == [0.0; 3]));
        assert!(b.pixels[4..].iter().all(|p| *p == [1.0; 3]));
    }

    /// Every pixel black, over several chunks and a partial last one.
    #[test]
    fn fill_black_clears_every_pixel() {
        let mut im = HdrImage::new(300, 250);
        for (k, p) in im.pixels.iter_mut().enumerate() {
            *p = [k as f32, 1.0, -2.0];
        }
        im.fill_black();
        assert!(im.pixels.iter().all(|p| *p == [0.0; 3]));
        assert_eq!(im.pixels.len(), 300 * 250);
    }

    #[test]
    fn new_is_black_and_indexing_is_row_major() {
        let mut a = HdrImage::new(3, 2);
        assert_eq!(a.pixels.len(), 6);
        assert_eq!(a.sum(), [0.0; 3]);
        *a.get_mut(2, 1).unwrap() = [1.0, 2.0, 3.0];
        assert_eq!(a.pixels[5], [1.0, 2.0, 3.0]);
        assert_eq!(a.get(2, 1), Some([1.0, 2.0, 3.0]));
        assert_eq!(a.get(3, 0), None);
        assert_eq!(a.get(0, 2), None);
        assert!(a.get_mut(3, 1).is_none());
    }

    #[test]
    fn from_pixels_checks_the_length() {
        assert!(HdrImage::from_pixels(2, 2, vec![[0.0; 3]; 3]).is_err());
        assert!(HdrImage::from_pixels(usize::MAX, 2, vec![]).is_err());
        assert!(HdrImage::from_pixels(0, 5, vec![]).is_ok());
    }

    #[test]
    fn add_scale_sum_luminance_and_max() {
        let mut a = img(&[[1.0, 2.0, 3.0], [0.5, -1.0, 0.0]]);
        let b = img(&[[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]);
        a.add_image(&b).unwrap();
        assert_eq!(a.pixels, vec![[2.0, 3.0, 4.0], [2.5, 1.0, 2.0]]);
        a.scale(2.0);
        assert_eq!(a.sum(), [9.0, 8.0, 12.0]);
        // 0.2126·9 + 0.7152·8 + 0.0722·12 = 1.9134 + 5.7216 + 0.8664 = 8.5014
        assert!((a.luminance_sum() - 8.5014).abs() < 1e-12);
        assert_eq!(a.max(), 8.0);
        a.add_scaled(&b, -0.5).unwrap();
        assert_eq!(a.pixels, vec![[3.5, 5.5, 7.5], [4.0, 1.0, 3.0]]);
        let wrong = HdrImage::new(1, 2);
        assert!(a.add_image(&wrong).is_err());
        assert_eq!(a.pixels, vec![[3.5, 5.5, 7.5], [4.0, 1.0, 3.0]]);
        assert_eq!(HdrImage::new(0, 0).max(), f32::NEG_INFINITY);
    }

    #[test]
    fn non_finite_values_are_found() {
        let mut a = HdrImage::new(2, 2);
        assert!(!a.has_non_finite());
        a.pixels[3][1] = f32::NAN;
        assert!(a.has_non_finite());
        a.pixels[3][1] = f32::NEG_INFINITY;
        assert!(a.has_non_finite());
        // max ignores NaN.
        a.pixels[3][1] = f32::NAN;
        a.pixels[0][0] = 0.25;
        assert_eq!(a.max(), 0.25);
    }

    /// a = (1, 2, 3 | 0, 0, 0), b = (1, 1, 1 | 1, 1, 1): differences (0, 1, 2 | −1, −1, −1),
    /// Σd² = 0 + 1 + 4 + 3 = 8, Σb² = 6 → RMSE = sqrt(8/6); Σ|d| = 6, Σ|b| = 6 → L1 = 1;
    /// Σa = 6, Σb = 6 → energy error 0.
    #[test]
    fn metrics_match_hand_computed_values() {
        let a = img(&[[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]);
        let b = img(&[[1.0; 3], [1.0; 3]]);
        let m = a.compare(&b).unwrap();
        assert!((m.relative_rmse - (8.0_f64 / 6.0).sqrt()).abs() < 1e-15);
        assert!((m.relative_l1 - 1.0).abs() < 1e-15);
        assert!(m.energy_error.abs() < 1e-15);
        // Half the energy: a = b / 2 → RMSE 0.5, L1 0.5, energy −0.5.
        let mut h = b.clone();
        h.scale(0.5);
        let m = h.compare(&b).unwrap();
        assert!((m.relative_rmse - 0.5).abs() < 1e-15);
        assert!((m.relative_l1 - 0.5).abs() < 1e-15);
        assert!((m.energy_error + 0.5).abs() < 1e-15);
        assert_eq!(h.relative_rmse(&b).unwrap(), m.relative_rmse);
        assert_eq!(h.relative_l1(&b).unwrap(), m.relative_l1);
        assert_eq!(h.energy_error(&b).unwrap(), m.energy_error);
        assert_eq!(b.compare(&b).unwrap().relative_rmse, 0.0);
    }

    #[test]
    fn metrics_against_a_black_reference_are_zero_or_infinite() {
        let zero = HdrImage::new(2, 1);
        let m = zero.compare(&zero).unwrap();
        assert_eq!(
            (m.relative_rmse, m.relative_l1, m.energy_error),
            (0.0, 0.0, 0.0)
        );
        let m = img(&[[1.0, 0.0, 0.0], [0.0; 3]]).compare(&zero).unwrap();
        assert_eq!(m.relative_rmse, f64::INFINITY);
        assert_eq!(m.energy_error, f64::INFINITY);
        assert!(zero.compare(&HdrImage::new(1, 2)).is_err());
    }
}

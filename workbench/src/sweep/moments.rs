//! An image's energy, centroid and spread: what a ghost drawn by a renderer is compared by
//! against the same ghost of the reference.

use flarebench_sdk::image::HdrImage;
use serde::{Deserialize, Serialize};

/// Energy (sum of the three channels over the frame), centroid and second central moments of
/// an image, in pixels (x right, y down; a pixel's centre at `i + ½`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    pub energy: f64,
    pub cx: f64,
    pub cy: f64,
    /// Second central moments: ⟨(x − cx)²⟩, ⟨(y − cy)²⟩, ⟨(x − cx)(y − cy)⟩ (px²).
    pub xx: f64,
    pub yy: f64,
    pub xy: f64,
}

impl Moments {
    /// The moments of `img`, each pixel weighted by the sum of its channels (negative and
    /// non-finite pixels weigh nothing).
    pub fn of(img: &HdrImage) -> Moments {
        let (mut e, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0);
        for (y, row) in img.pixels.chunks(img.width.max(1)).enumerate() {
            let py = y as f64 + 0.5;
            // Per row first: the sums stay exact enough in f64 for frames of any size.
            let (mut re, mut rx, mut rxx) = (0.0f64, 0.0f64, 0.0f64);
            for (x, p) in row.iter().enumerate() {
                let w = f64::from(p[0] + p[1] + p[2]);
                if !(w > 0.0 && w.is_finite()) {
                    continue;
                }
                let px = x as f64 + 0.5;
                re += w;
                rx += w * px;
                rxx += w * px * px;
            }
            e += re;
            sx += rx;
            sy += re * py;
            sxx += rxx;
            syy += re * py * py;
            sxy += rx * py;
        }
        if e <= 0.0 {
            return Moments::default();
        }
        let (cx, cy) = (sx / e, sy / e);
        Moments {
            energy: e,
            cx,
            cy,
            xx: (sxx / e - cx * cx).max(0.0),
            yy: (syy / e - cy * cy).max(0.0),
            xy: sxy / e - cx * cy,
        }
    }

    /// The RMS radius about the centroid, √(xx + yy) (px).
    pub fn rms_radius(&self) -> f64 {
        (self.xx + self.yy).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_rectangle_has_its_centre_and_the_uniform_variance() {
        let mut img = HdrImage::new(40, 30);
        // x in 10..20, y in 5..25, value 1 in one channel.
        for y in 5..25 {
            for x in 10..20 {
                img.pixels[y * 40 + x] = [1.0, 0.0, 0.0];
            }
        }
        let m = Moments::of(&img);
        assert_eq!(m.energy, 200.0);
        assert!((m.cx - 15.0).abs() < 1e-12 && (m.cy - 15.0).abs() < 1e-12);
        // A run of n unit pixels has variance (n² − 1)/12.
        assert!((m.xx - 99.0 / 12.0).abs() < 1e-9, "{}", m.xx);
        assert!((m.yy - 399.0 / 12.0).abs() < 1e-9, "{}", m.yy);
        assert!(m.xy.abs() < 1e-9);
    }

    #[test]
    fn a_black_image_has_no_energy_and_ignores_bad_pixels() {
        let mut img = HdrImage::new(4, 4);
        img.pixels[3] = [f32::NAN, 0.0, 0.0];
        img.pixels[5] = [-1.0, 0.0, 0.0];
        assert_eq!(Moments::of(&img), Moments::default());
    }
}

//! Finding the bright light sources in an image and the direction each comes from
//! (`flarebench apply`).
//!
//! **Detection.** A pixel is part of a source when its largest channel (linear) is at least
//! the threshold: a scene-referred EXR's lights are far above diffuse white (default 1), an
//! sRGB image's are clipped to white (default 0.95 linear, encoded 0.98). Sources are the
//! 8-connected components of such pixels; each has its energy `Σ Y` (luminance) and its
//! centroid weighted by luminance, pixel centres at `(x + ½, y + ½)`. The brightest
//! `max_sources` are kept.
//!
//! **Direction.** A centroid at pixel `(px, py)` is the sensor point
//! `x = (½ − px/w)·W`, `y = (py/h − ½)·H` (the inverse of `Frame::to_pixel`, photograph
//! orientation). Its azimuth is `φ = atan2(−x, y)` (the chief ray of a light at azimuth φ
//! lands at `r·(−sin φ, cos φ)`), and its angle θ starts from the paraxial `atan(r/f)` and is
//! refined by the secant method until the real chief ray lands at `r` (within 1e-6 mm), so
//! distortion is undone and the flare is centred on the source.

use anyhow::{Result, bail};
use flarebench_sdk::LensSystem;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::chief_ray_landing;
use serde::Serialize;

/// A bright region of an image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Source {
    /// Luminance-weighted centroid (pixels, x right, y down; pixel centres at +½).
    pub centroid_px: [f64; 2],
    /// Pixels in the region.
    pub pixels: usize,
    /// `Σ` luminance over the region (image units).
    pub energy: f64,
    /// Mean linear colour of the region, normalised to luminance 1.
    pub colour: [f64; 3],
}

/// The 8-connected regions whose largest channel is at least `threshold`, brightest first,
/// at most `max_sources` of them.
pub fn find_sources(img: &HdrImage, threshold: f32, max_sources: usize) -> Vec<Source> {
    let (w, h) = (img.width, img.height);
    let bright: Vec<bool> = img
        .pixels
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]) >= threshold)
        .collect();
    let mut seen = vec![false; w * h];
    let mut stack = Vec::new();
    let mut found = Vec::new();
    for start in 0..w * h {
        if !bright[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let (mut n, mut e, mut sx, mut sy) = (0usize, 0f64, 0f64, 0f64);
        let mut rgb = [0f64; 3];
        while let Some(k) = stack.pop() {
            let p = img.pixels[k];
            let y = 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
            let (x0, y0) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
            n += 1;
            e += y;
            sx += y * x0;
            sy += y * y0;
            for c in 0..3 {
                rgb[c] += f64::from(p[c]);
            }
            let (cx, cy) = ((k % w) as isize, (k / w) as isize);
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    let (nx, ny) = (cx + dx, cy + dy);
                    if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if bright[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        // A region without luminance (nothing but negative or zero values) is no light.
        if e.is_nan() || e <= 0.0 {
            continue;
        }
        let centroid_px = [sx / e, sy / e];
        let ysum = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
        let colour = if ysum > 0.0 {
            rgb.map(|c| c / ysum)
        } else {
            [1.0; 3]
        };
        found.push(Source {
            centroid_px,
            pixels: n,
            energy: e,
            colour,
        });
    }
    found.sort_by(|a, b| b.energy.total_cmp(&a.energy));
    found.truncate(max_sources);
    found
}

/// The direction `(θ, φ)` in degrees of a light whose image is at pixel `(px, py)`.
pub fn direction_of(system: &LensSystem, frame: &Frame, px: f64, py: f64) -> Result<(f64, f64)> {
    let x = (0.5 - px / frame.width as f64) * frame.film_width_mm;
    let y = (py / frame.height as f64 - 0.5) * frame.film_height_mm;
    let r = x.hypot(y);
    if r == 0.0 {
        return Ok((0.0, 0.0));
    }
    let phi = (-x).atan2(y);
    let f = analyse(system, LAMBDA_D_NM)?.efl_mm;
    if f.is_nan() || f <= 0.0 {
        bail!("the lens has a negative focal length ({f} mm): it forms no real image");
    }
    // Image height of the chief ray at θ, along its azimuth.
    let height = |theta: f64| -> Result<f64> {
        let [lx, ly] = chief_ray_landing(system, LAMBDA_D_NM, theta, 0.0)?;
        Ok(lx.hypot(ly) * ly.signum())
    };
    let mut t0 = (r / f).atan();
    let mut h0 = height(t0)? - r;
    let mut t1 = t0 * 1.01;
    for _ in 0..40 {
        if h0.abs() < 1e-6 {
            return Ok((t0.to_degrees(), phi.to_degrees()));
        }
        let h1 = height(t1)? - r;
        let slope = (h1 - h0) / (t1 - t0);
        if slope == 0.0 || !slope.is_finite() {
            break;
        }
        let t2 = (t1 - h1 / slope).clamp(0.0, 89f64.to_radians());
        (t0, h0, t1) = (t1, h1, t2);
    }
    bail!(
        "no light direction images at pixel ({px:.1}, {py:.1}) ({r:.3} mm from the centre): \
         the lens's chief ray does not reach that height"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_centroids_and_energies() {
        let mut img = HdrImage::new(20, 10);
        // A 2×2 block at columns 3–4, rows 5–6, values 4: centroid (4, 6), energy 16.
        for (x, y) in [(3, 5), (4, 5), (3, 6), (4, 6)] {
            img.pixels[y * 20 + x] = [4.0; 3];
        }
        // A diagonal pair (8-connected) with uneven weights at (10, 1) and (11, 2).
        img.pixels[20 + 10] = [2.0; 3];
        img.pixels[2 * 20 + 11] = [6.0; 3];
        // Below the threshold: ignored.
        img.pixels[9 * 20 + 19] = [0.9; 3];
        let s = find_sources(&img, 1.0, 10);
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].pixels, 4);
        assert!((s[0].energy - 16.0).abs() < 1e-9);
        assert!((s[0].centroid_px[0] - 4.0).abs() < 1e-12);
        assert!((s[0].centroid_px[1] - 6.0).abs() < 1e-12);
        assert_eq!(s[1].pixels, 2);
        // (2 × 10.5 + 6 × 11.5) / 8 = 11.25; (2 × 1.5 + 6 × 2.5) / 8 = 2.25.
        assert!((s[1].centroid_px[0] - 11.25).abs() < 1e-12);
        assert!((s[1].centroid_px[1] - 2.25).abs() < 1e-12);
        assert_eq!(find_sources(&img, 1.0, 1).len(), 1);
        assert!(find_sources(&img, 100.0, 10).is_empty());
    }
}

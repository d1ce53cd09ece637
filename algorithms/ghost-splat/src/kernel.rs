//! The splat kernel: how one ray's energy is shared among the pixels around where it lands.
//!
//! - **Box** (`kernel_px = 0`): all of it to the pixel the ray lands in. The image then
//!   estimates each pixel's integral of the irradiance, which is what an exact-coverage
//!   rasterizer draws (the ray-traced renderer and its reference): unbiased against them, the
//!   noisiest.
//! - **Tent** of half-width `r ≥ 1` pixels: separable, `w(d) = max(0, 1 − |d|/r)` along each
//!   axis, `d` the distance from the landing point to a pixel centre, normalised so that the
//!   weights sum to 1 (exactly the energy, whatever `r`). `r = 1` is bilinear splatting. A wider
//!   tent averages more rays into each pixel (less noise) and blurs the image by its width.
//!
//! Weights are computed on the stack ([`MAX_TAPS`] per axis): nothing is allocated per ray.
//! What falls outside the frame is dropped, as an exact-coverage rasterizer crops.

use crate::error::SplatError;

/// The widest tent (half-width, pixels).
pub const MAX_KERNEL_PX: f64 = 8.0;
/// Pixels a tent of half-width [`MAX_KERNEL_PX`] can touch along one axis.
pub const MAX_TAPS: usize = 2 * MAX_KERNEL_PX as usize + 1;

/// A splat kernel (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// 0 for the box, else the tent's half-width (pixels, in `[1, MAX_KERNEL_PX]`).
    half_width_px: f64,
}

/// The pixels along one axis a ray touches: the first one's index and the weights.
#[derive(Clone, Copy, Debug)]
pub struct Taps {
    pub first: i64,
    pub len: usize,
    pub weights: [f64; MAX_TAPS],
}

impl Kernel {
    /// The box for 0, a tent of half-width `half_width_px` for values in `[1, 8]`; anything
    /// else (between 0 and 1, above 8, negative, NaN) is an error.
    pub fn new(half_width_px: f64) -> Result<Kernel, SplatError> {
        let ok = half_width_px == 0.0 || (1.0..=MAX_KERNEL_PX).contains(&half_width_px);
        if ok {
            Ok(Kernel { half_width_px })
        } else {
            Err(SplatError::KernelWidth(half_width_px))
        }
    }

    /// The box kernel.
    pub fn box_filter() -> Kernel {
        Kernel { half_width_px: 0.0 }
    }

    /// 0 for the box, else the tent's half-width (pixels).
    pub fn half_width_px(&self) -> f64 {
        self.half_width_px
    }

    /// The taps along an axis for a ray landing at `p` (pixels, pixel centres at
    /// half-integers); none for a point that is not finite.
    pub fn taps(&self, p: f64) -> Taps {
        let mut t = Taps {
            first: 0,
            len: 0,
            weights: [0.0; MAX_TAPS],
        };
        if !p.is_finite() {
            return t;
        }
        let r = self.half_width_px;
        if r == 0.0 {
            t.first = p.floor() as i64;
            t.len = 1;
            t.weights[0] = 1.0;
            return t;
        }
        // Pixels k with |k + ½ − p| < r; the nearest centre is at most ½ away, so with r ≥ 1
        // at least one weight is positive.
        let first = (p - 0.5 - r).ceil();
        let last = (p - 0.5 + r).floor();
        let len = ((last - first) as usize + 1).min(MAX_TAPS);
        let mut sum = 0.0;
        for (k, w) in t.weights.iter_mut().take(len).enumerate() {
            let d = (first + k as f64 + 0.5 - p).abs();
            *w = (1.0 - d / r).max(0.0);
            sum += *w;
        }
        for w in t.weights.iter_mut().take(len) {
            *w /= sum;
        }
        t.first = first as i64;
        t.len = len;
        t
    }

    /// Adds the part in rows `rows.0..rows.1` of the splat of `energy` (linear RGB) landing
    /// at `px` (pixels) to `strip`, those rows of a frame `width` pixels wide.
    pub fn splat_rows(
        &self,
        strip: &mut [[f64; 3]],
        width: usize,
        rows: (usize, usize),
        px: [f64; 2],
        energy: [f64; 3],
    ) {
        // A cheap bound on the rows first (it holds every tap, the box's pixel included).
        let r = self.half_width_px.max(0.5);
        let (lo, hi) = ((px[1] - 0.5 - r).floor(), (px[1] - 0.5 + r).ceil());
        if hi < rows.0 as f64 || lo >= rows.1 as f64 {
            return;
        }
        let ty = self.taps(px[1]);
        let (y0, y1) = (rows.0 as i64, rows.1 as i64);
        if ty.len == 0 || ty.first >= y1 || ty.first + ty.len as i64 <= y0 {
            return;
        }
        let tx = self.taps(px[0]);
        for (j, wy) in ty.weights.iter().take(ty.len).enumerate() {
            let y = ty.first + j as i64;
            if y < y0 || y >= y1 {
                continue;
            }
            let row = &mut strip[(y - y0) as usize * width..][..width];
            for (i, wx) in tx.weights.iter().take(tx.len).enumerate() {
                let x = tx.first + i as i64;
                if x < 0 || x >= width as i64 {
                    continue;
                }
                let w = wx * wy;
                let p = &mut row[x as usize];
                for c in 0..3 {
                    p[c] += energy[c] * w;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normalised weights sum to 1 up to f64 rounding of a few terms.
    const SUM_TOL: f64 = 1e-12;

    #[test]
    fn every_kernel_shares_the_whole_energy() {
        for r in [0.0, 1.0, 1.5, 2.0, 3.7, 8.0] {
            let k = Kernel::new(r).unwrap();
            for p in [0.0, 0.25, 0.5, 0.999, 3.3, 10.5] {
                let t = k.taps(p);
                let s: f64 = t.weights[..t.len].iter().sum();
                assert!((s - 1.0).abs() < SUM_TOL, "r {r} p {p}: {s}");
                assert!(t.len <= (2.0 * r) as usize + 1);
            }
        }
    }

    #[test]
    fn the_unit_tent_is_bilinear() {
        let t = Kernel::new(1.0).unwrap().taps(3.8);
        // Pixels 3 and 4 (centres 0.3 and 0.7 away): weights 0.7 and 0.3, as bilinear.
        assert_eq!(t.first, 3);
        assert_eq!(t.len, 2);
        assert!((t.weights[0] - 0.7).abs() < SUM_TOL && (t.weights[1] - 0.3).abs() < SUM_TOL);
    }

    #[test]
    fn the_box_gives_everything_to_the_pixel_landed_in() {
        let t = Kernel::box_filter().taps(3.99);
        assert_eq!((t.first, t.len, t.weights[0]), (3, 1, 1.0));
        assert_eq!(Kernel::box_filter().taps(f64::NAN).len, 0);
    }

    #[test]
    fn widths_between_the_box_and_bilinear_and_beyond_the_widest_are_refused() {
        for r in [0.5, -1.0, 8.5, f64::NAN, f64::INFINITY] {
            assert!(Kernel::new(r).is_err(), "{r}");
        }
    }
}

//! [`add_starburst`]: a [`StarburstPattern`] added into an HDR image at a point of the sensor,
//! scaled by the light's flux, by exact area resampling.
//!
//! **Geometry.** Bin `(i, j)` of the pattern covers the sensor square centred on
//! `centre + ((i − P/2)·b, (j − P/2)·b)` mm with side `b` = [`StarburstPattern::bin_mm`]. The
//! frame maps the sensor to the photograph ([`Frame::to_pixel`]: x to the left, y downward),
//! so both axes map separately and each bin's square becomes an axis-aligned pixel-space
//! rectangle. Each bin's value is shared among the pixels its rectangle overlaps in
//! proportion to the overlap (separable: along x, then along y) — what lies in the frame is
//! added exactly, what lies outside is counted in [`SplatStats::outside`].
//!
//! **Units.** Image pixels hold flux (as the ghost renderer's do): a pattern of luminance sum
//! 1 times `flux` adds `flux` to the image's luminance sum when it lies wholly in the frame.

use crate::frame::Frame;
use crate::image::HdrImage;

use super::{StarburstError, StarburstPattern};

/// What adding a starburst did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplatStats {
    /// Luminance (Rec. 709 weights) added to the image.
    pub added: f64,
    /// Luminance of the pattern × flux that fell outside the frame.
    pub outside: f64,
    /// Radius the pattern reaches from its centre (pixels, along the frame's wider pixel
    /// side): half the grid.
    pub reach_px: f64,
}

/// Adds `pattern × flux` to `img` centred at sensor point `centre_mm` (lens frame, mm) for a
/// working f-number `f_number` (module docs). `img` must have the frame's size.
pub fn add_starburst(
    img: &mut HdrImage,
    frame: &Frame,
    pattern: &StarburstPattern,
    centre_mm: [f64; 2],
    f_number: f64,
    flux: f64,
) -> Result<SplatStats, StarburstError> {
    let g = SplatGeometry::new(frame, pattern, centre_mm, f_number)?;
    let p = g.size;
    let x_edges = Axis::new(g.first[0], g.step[0], p, frame.width);
    let y_edges = Axis::new(g.first[1], g.step[1], p, frame.height);
    let lum = |v: [f64; 3]| 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
    let total = lum(pattern.sum()) * flux;
    let mut stats = SplatStats {
        reach_px: g.reach_px,
        ..SplatStats::default()
    };
    if x_edges.span.is_none() || y_edges.span.is_none() {
        stats.outside = total;
        return Ok(stats);
    }
    let (x0, x1) = x_edges.span.expect("checked above");
    let nx = x1 - x0;
    let mut row_px = vec![[0f64; 3]; nx];
    let w = img.width;
    let mut added = [0f64; 3];
    for j in 0..p {
        let ys = &y_edges.weights[y_edges.start[j]..y_edges.start[j + 1]];
        if ys.is_empty() {
            continue;
        }
        row_px.fill([0.0; 3]);
        let src = &pattern.rgb()[j * p..][..p];
        for (i, v) in src.iter().enumerate() {
            if v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0 {
                continue;
            }
            for &(px, wx) in &x_edges.weights[x_edges.start[i]..x_edges.start[i + 1]] {
                let o = &mut row_px[px as usize - x0];
                for c in 0..3 {
                    o[c] += wx * f64::from(v[c]);
                }
            }
        }
        for &(py, wy) in ys {
            let row = &mut img.pixels[py as usize * w..][..w];
            for (k, v) in row_px.iter().enumerate() {
                let o = &mut row[x0 + k];
                for c in 0..3 {
                    let add = wy * v[c] * flux;
                    o[c] += add as f32;
                    added[c] += add;
                }
            }
        }
    }
    stats.added = lum(added);
    stats.outside = (total - stats.added).max(0.0);
    Ok(stats)
}

/// Where a pattern's bins land on a frame's pixels: bin `(i, j)` covers pixel coordinates
/// `first[0] + i·step[0]` to `first[0] + (i + 1)·step[0]` along x (a negative step: x maps
/// to the left), and likewise along y (module docs). The CPU splat and the GPU backend's
/// starburst pass share it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatGeometry {
    /// Bins per side.
    pub size: usize,
    /// Pixel coordinate of bin 0's first edge, per axis.
    pub first: [f64; 2],
    /// Signed pixels per bin, per axis.
    pub step: [f64; 2],
    /// How far the pattern reaches from its centre (pixels, along the wider pixel side).
    pub reach_px: f64,
}

impl SplatGeometry {
    /// The geometry of `pattern` centred at sensor point `centre_mm` at f-number `f_number`.
    pub fn new(
        frame: &Frame,
        pattern: &StarburstPattern,
        centre_mm: [f64; 2],
        f_number: f64,
    ) -> Result<SplatGeometry, StarburstError> {
        if !(f_number > 0.0 && f_number.is_finite()) {
            return Err(StarburstError::FNumber(f_number));
        }
        let p = pattern.size();
        let b = pattern.bin_mm(f_number);
        let half = (p / 2) as f64;
        let px_w = frame.film_width_mm / frame.width as f64;
        let px_h = frame.film_height_mm / frame.height as f64;
        let [cx, cy] = frame.to_pixel(centre_mm[0], centre_mm[1]).map(f64::from);
        Ok(SplatGeometry {
            size: p,
            first: [cx - (-half - 0.5) * b / px_w, cy + (-half - 0.5) * b / px_h],
            step: [-b / px_w, b / px_h],
            reach_px: half * b / px_w.min(px_h),
        })
    }
}

/// What [`add_starburst`] would add, without drawing: the luminance that lands in the frame
/// and the part outside it (for a backend that draws the pattern itself).
pub fn splat_stats(
    frame: &Frame,
    pattern: &StarburstPattern,
    centre_mm: [f64; 2],
    f_number: f64,
    flux: f64,
) -> Result<SplatStats, StarburstError> {
    let g = SplatGeometry::new(frame, pattern, centre_mm, f_number)?;
    let p = g.size;
    let share = |axis: &Axis| -> Vec<f64> {
        (0..p)
            .map(|i| {
                axis.weights[axis.start[i]..axis.start[i + 1]]
                    .iter()
                    .map(|w| w.1)
                    .sum()
            })
            .collect()
    };
    let fx = share(&Axis::new(g.first[0], g.step[0], p, frame.width));
    let fy = share(&Axis::new(g.first[1], g.step[1], p, frame.height));
    let lum = |v: [f32; 3]| {
        0.2126 * f64::from(v[0]) + 0.7152 * f64::from(v[1]) + 0.0722 * f64::from(v[2])
    };
    let total = {
        let s = pattern.sum();
        (0.2126 * s[0] + 0.7152 * s[1] + 0.0722 * s[2]) * flux
    };
    let mut added = 0.0;
    for (j, row) in pattern.rgb().chunks_exact(p).enumerate() {
        if fy[j] == 0.0 {
            continue;
        }
        let r: f64 = row.iter().zip(&fx).map(|(v, f)| f * lum(*v)).sum();
        added += fy[j] * r;
    }
    added *= flux;
    Ok(SplatStats {
        added,
        outside: (total - added).max(0.0),
        reach_px: g.reach_px,
    })
}

/// The overlap weights of one axis: bin `i` spreads over pixels
/// `weights[start[i]..start[i + 1]]` as `(pixel, fraction of the bin)`.
struct Axis {
    start: Vec<usize>,
    weights: Vec<(u32, f64)>,
    /// The pixels touched, `[first, last + 1)`, if any.
    span: Option<(usize, usize)>,
}

impl Axis {
    /// Bin `i` covers pixel coordinates between `first + i·step` and `first + (i + 1)·step`.
    fn new(first: f64, step: f64, bins: usize, pixels: usize) -> Axis {
        let mut start = Vec::with_capacity(bins + 1);
        let mut weights = Vec::new();
        let mut span: Option<(usize, usize)> = None;
        let len = step.abs();
        let limit = pixels as f64;
        for i in 0..bins {
            start.push(weights.len());
            let a = first + i as f64 * step;
            let (lo, hi) = if step >= 0.0 {
                (a, a + step)
            } else {
                (a + step, a)
            };
            let (lo_c, hi_c) = (lo.max(0.0), hi.min(limit));
            #[allow(
                clippy::neg_cmp_op_on_partial_ord,
                reason = "NaN edges (from a NaN centre) add nothing"
            )]
            if !(hi_c > lo_c) || !(len > 0.0) {
                continue;
            }
            // `lo_c` and `hi_c` lie in [0, pixels]: the casts are in range.
            let first_px = lo_c.floor() as usize;
            let last_px = ((hi_c.ceil() as usize).max(first_px + 1)).min(pixels);
            for px in first_px..last_px {
                let ov = hi_c.min((px + 1) as f64) - lo_c.max(px as f64);
                if ov > 0.0 {
                    weights.push((px as u32, ov / len));
                    span = Some(match span {
                        None => (px, px + 1),
                        Some((s0, s1)) => (s0.min(px), s1.max(px + 1)),
                    });
                }
            }
        }
        start.push(weights.len());
        Axis {
            start,
            weights,
            span,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_weights_share_each_bin_exactly() {
        // Bins of 0.3 px from pixel coordinate 2.9 going left (negative step), 5 pixels.
        let a = Axis::new(2.9, -0.3, 20, 5);
        let per_bin: Vec<f64> = (0..20)
            .map(|i| {
                a.weights[a.start[i]..a.start[i + 1]]
                    .iter()
                    .map(|w| w.1)
                    .sum()
            })
            .collect();
        // Bins wholly inside [0, 5] keep all of their value; bins 0..9 span 2.9 → 0.2.
        for (i, s) in per_bin.iter().enumerate() {
            let lo = 2.9 - 0.3 * (i as f64 + 1.0);
            let hi = 2.9 - 0.3 * i as f64;
            let inside = (hi.min(5.0) - lo.max(0.0)).max(0.0) / 0.3;
            assert!((s - inside).abs() < 1e-12, "bin {i}: {s} vs {inside}");
        }
        assert_eq!(a.span, Some((0, 3)));
        // Bins wider than a pixel spread over several.
        let b = Axis::new(0.5, 2.5, 2, 10);
        assert_eq!(
            b.weights,
            vec![(0, 0.2), (1, 0.4), (2, 0.4), (3, 0.4), (4, 0.4), (5, 0.2)]
        );
    }
}

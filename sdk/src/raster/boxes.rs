//! Box splats: axis-aligned rectangles of constant irradiance added to the pixels they
//! overlap, each pixel gaining the exact overlap area times the irradiance. A rectangle's
//! overlap with the pixel grid is separable (its overlap with each column times that with
//! each row), so a splat of about a pixel costs a handful of multiply-adds where the
//! triangle rasterizer's exact coverage clips polygons: the ghost renderer draws a ghost
//! whose triangles land smaller than a few pixels as boxes (`crate::ghost::splat`).
//!
//! **Energy.** A box adds `irradiance × (its area inside the image)`, exactly; the same box
//! drawn as two triangles with exact coverage adds the same to every pixel (up to f32
//! rounding), which is how the GPU backend draws boxes.
//!
//! **Parallelism.** Boxes are binned into bands of [`BAND_ROWS`] rows (chunks of boxes in
//! parallel, each band's boxes kept in input order); bands are drawn in parallel, each writing
//! only its own rows, so the image does not depend on the number of threads.

use rayon::prelude::*;

/// Rows of a band drawn by one task.
pub const BAND_ROWS: usize = 32;

/// Boxes to splat: `rects[i] = [x0, y0, x1, y1]` (pixels, x right, y down; pixel `(i, j)`
/// covers `[i, i + 1) × [j, j + 1)`) with irradiance `irradiance[i]` (image units per pixel²).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Boxes {
    pub rects: Vec<[f32; 4]>,
    pub irradiance: Vec<[f32; 3]>,
}

impl Boxes {
    /// Number of boxes.
    pub fn len(&self) -> usize {
        self.rects.len()
    }

    /// True without boxes.
    pub fn is_empty(&self) -> bool {
        self.rects.is_empty()
    }

    /// Removes every box, keeping the buffers.
    pub fn clear(&mut self) {
        self.rects.clear();
        self.irradiance.clear();
    }

    /// Makes room for `n` more boxes.
    pub fn reserve(&mut self, n: usize) {
        self.rects.reserve(n);
        self.irradiance.reserve(n);
    }

    /// Adds a box.
    #[inline]
    pub fn push(&mut self, rect: [f32; 4], irradiance: [f32; 3]) {
        self.rects.push(rect);
        self.irradiance.push(irradiance);
    }

    /// Adds every box of `other` after this one's.
    pub fn append(&mut self, other: &Boxes) {
        self.rects.extend_from_slice(&other.rects);
        self.irradiance.extend_from_slice(&other.irradiance);
    }

    /// The energy the boxes carry (the sum of irradiance × area), wherever they lie.
    pub fn energy(&self) -> [f64; 3] {
        let mut e = [0.0; 3];
        for (r, c) in self.rects.iter().zip(&self.irradiance) {
            let area = f64::from(r[2] - r[0]) * f64::from(r[3] - r[1]);
            for k in 0..3 {
                e[k] += area * f64::from(c[k]);
            }
        }
        e
    }
}

/// True when a box is drawn: finite, non-empty, finite irradiance.
#[inline]
fn usable(r: &[f32; 4], c: &[f32; 3]) -> bool {
    r.iter().all(|v| v.is_finite()) && r[2] > r[0] && r[3] > r[1] && c.iter().all(|v| v.is_finite())
}

/// Adds `boxes` to `pixels`, a row-major buffer `width` pixels wide (whole rows): each pixel
/// gains the area of it each box covers times the box's irradiance. Boxes with a non-finite
/// value or no area are skipped; parts outside the image are dropped.
pub fn splat_boxes_into(pixels: &mut [[f32; 3]], width: usize, boxes: &Boxes) {
    let height = pixels.len().checked_div(width).unwrap_or(0);
    if width == 0 || height == 0 || boxes.is_empty() {
        return;
    }
    let bands = height.div_ceil(BAND_ROWS);
    // The bands each box's rows meet (inclusive), or none.
    let span = |r: &[f32; 4]| -> Option<(usize, usize)> {
        let (y0, y1) = (r[1].max(0.0), r[3].min(height as f32));
        if y1 <= y0 || r[2] <= 0.0 || r[0] >= width as f32 {
            return None;
        }
        let j0 = y0 as usize;
        let j1 = ((y1.ceil() as usize).max(j0 + 1) - 1).min(height - 1);
        Some((j0 / BAND_ROWS, j1 / BAND_ROWS))
    };
    // Binned in parallel, chunk by chunk: each chunk's boxes of each band, in input order.
    let chunks: Vec<Vec<Vec<u32>>> = boxes
        .rects
        .par_chunks(BIN_CHUNK)
        .zip(boxes.irradiance.par_chunks(BIN_CHUNK))
        .enumerate()
        .map(|(k, (rects, irradiance))| {
            let mut bins = vec![Vec::new(); bands];
            for (i, (r, c)) in rects.iter().zip(irradiance).enumerate() {
                if let Some((b0, b1)) = usable(r, c).then(|| span(r)).flatten() {
                    for bin in &mut bins[b0..=b1] {
                        bin.push((k * BIN_CHUNK + i) as u32);
                    }
                }
            }
            bins
        })
        .collect();
    pixels
        .par_chunks_mut(BAND_ROWS * width)
        .enumerate()
        .for_each(|(b, rows)| {
            let first_row = b * BAND_ROWS;
            let band_rows = rows.len() / width;
            for chunk in &chunks {
                for &i in &chunk[b] {
                    let r = boxes.rects[i as usize];
                    let c = boxes.irradiance[i as usize];
                    splat_one(rows, width, first_row, band_rows, r, c);
                }
            }
        });
}

/// Boxes binned by one task.
const BIN_CHUNK: usize = 1 << 15;

/// Adds one box to the rows `first_row..first_row + band_rows` held in `rows`.
#[inline]
fn splat_one(
    rows: &mut [[f32; 3]],
    width: usize,
    first_row: usize,
    band_rows: usize,
    [x0, y0, x1, y1]: [f32; 4],
    c: [f32; 3],
) {
    let (x0, x1) = (x0.max(0.0), x1.min(width as f32));
    let (lo, hi) = (first_row as f32, (first_row + band_rows) as f32);
    let (y0, y1) = (y0.max(lo), y1.min(hi));
    if x1 <= x0 || y1 <= y0 {
        return;
    }
    let (i0, i1) = (x0 as usize, (x1.ceil() as usize).min(width));
    let (j0, j1) = (y0 as usize, (y1.ceil() as usize).min(first_row + band_rows));
    for j in j0..j1.max(j0 + 1) {
        let oy = y1.min((j + 1) as f32) - y0.max(j as f32);
        if oy <= 0.0 {
            continue;
        }
        let row = &mut rows[(j - first_row) * width..(j - first_row + 1) * width];
        for (i, px) in row.iter_mut().enumerate().take(i1.max(i0 + 1)).skip(i0) {
            let ox = x1.min((i + 1) as f32) - x0.max(i as f32);
            if ox <= 0.0 {
                continue;
            }
            let a = ox * oy;
            px[0] += a * c[0];
            px[1] += a * c[1];
            px[2] += a * c[2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(pixels: &[[f32; 3]]) -> [f64; 3] {
        let mut s = [0.0; 3];
        for p in pixels {
            for k in 0..3 {
                s[k] += f64::from(p[k]);
            }
        }
        s
    }

    #[test]
    fn a_box_adds_its_overlap_with_each_pixel() {
        let mut px = vec![[0.0_f32; 3]; 4 * 3];
        let mut b = Boxes::default();
        // [0.5, 2.25) × [0.75, 1.5): columns 0..3, rows 0..2.
        b.push([0.5, 0.75, 2.25, 1.5], [2.0, 1.0, 0.0]);
        splat_boxes_into(&mut px, 4, &b);
        let at = |i: usize, j: usize| px[j * 4 + i][0];
        let expect = |ox: f32, oy: f32| 2.0 * ox * oy;
        assert!((at(0, 0) - expect(0.5, 0.25)).abs() < 1e-6);
        assert!((at(1, 0) - expect(1.0, 0.25)).abs() < 1e-6);
        assert!((at(2, 0) - expect(0.25, 0.25)).abs() < 1e-6);
        assert!((at(0, 1) - expect(0.5, 0.5)).abs() < 1e-6);
        assert!((at(1, 1) - expect(1.0, 0.5)).abs() < 1e-6);
        assert!((at(2, 1) - expect(0.25, 0.5)).abs() < 1e-6);
        assert_eq!(at(3, 0), 0.0);
        assert_eq!(at(0, 2), 0.0);
        let total = sum(&px);
        assert!((total[0] - 2.0 * 1.75 * 0.75).abs() < 1e-6, "{total:?}");
        assert!((total[1] - 1.75 * 0.75).abs() < 1e-6);
    }

    #[test]
    fn energy_is_kept_across_bands_and_clipped_at_the_image() {
        let (w, h) = (50, 3 * BAND_ROWS + 5);
        let mut px = vec![[0.0_f32; 3]; w * h];
        let mut b = Boxes::default();
        // Boxes across every band border, and one half outside the image.
        for k in 0..200 {
            let x = 1.0 + (k as f32 * 0.37) % 45.0;
            let y = (k as f32 * 0.731) % (h as f32 - 3.0);
            b.push([x, y, x + 1.3, y + 2.1], [1.0, 0.5, 0.25]);
        }
        b.push([-1.0, 10.0, 1.0, 11.0], [1.0, 1.0, 1.0]);
        let inside = b.energy()[0] - 1.0;
        splat_boxes_into(&mut px, w, &b);
        let s = sum(&px);
        assert!(
            (s[0] - inside).abs() < 1e-4 * inside,
            "{} vs {inside}",
            s[0]
        );
        // Thread count and band split do not change the image: one band at a time agrees.
        let mut one = vec![[0.0_f32; 3]; w * h];
        for k in 0..b.len() {
            let single = Boxes {
                rects: vec![b.rects[k]],
                irradiance: vec![b.irradiance[k]],
            };
            splat_boxes_into(&mut one, w, &single);
        }
        assert_eq!(one, px);
    }

    #[test]
    fn bad_boxes_add_nothing() {
        let mut px = vec![[0.0_f32; 3]; 16];
        let mut b = Boxes::default();
        b.push([f32::NAN, 0.0, 1.0, 1.0], [1.0; 3]);
        b.push([0.0, 0.0, 1.0, 1.0], [f32::INFINITY, 0.0, 0.0]);
        b.push([2.0, 2.0, 2.0, 3.0], [1.0; 3]);
        b.push([5.0, 0.0, 9.0, 1.0], [1.0; 3]);
        b.push([0.0, -3.0, 1.0, -1.0], [1.0; 3]);
        splat_boxes_into(&mut px, 4, &b);
        assert!(px.iter().all(|p| *p == [0.0; 3]));
    }
}

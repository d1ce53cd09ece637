//! [`StarburstPattern`]: the spectral starburst, `T(x) = Σ_k w_k s_k² I(c + (x − c)·s_k)` with
//! `s_k = λs/λ_k`, on the grid of the power spectrum `I` at the shortest wavelength λs.
//!
//! A wavelength's Fraunhofer pattern is the same function of `x/λ`, so the pattern at λ is the
//! one at λs magnified by `λ/λs ≥ 1`: sampling `I` at the scaled position `c + (x − c)·s_k`
//! (bilinear) gives its shape, and the factor `s_k²` keeps its energy (the magnified pattern
//! spreads over `1/s_k²` more area). `w_k` are the light's linear-sRGB weights
//! ([`crate::color::SpectralSampling`], luminance sum 1), so the pattern's luminance sum is 1
//! less the part of the longer wavelengths' patterns that falls outside the grid.
//!
//! **Edge.** The sum is cut at the grid's edge, where the patterns of the longer wavelengths
//! (sampled only out to `s_k` of the grid) and the far tail of the shortest are not yet zero:
//! drawn at a high exposure, that cut shows as a square. The pattern is therefore multiplied by
//! a radial window ([`edge_window`]): 1 out to [`TAPER_START`] of the inscribed circle's
//! radius, a raised cosine from there to 0 at that circle, 0 beyond. The pattern ends in a
//! circle, smoothly, with no step.
//!
//! **Speed.** The sum is centrally symmetric, as every power spectrum of a real aperture is
//! (`I(−f) = I(f)`): rows above the centre are computed (rayon over rows) and the rows below
//! are their point reflections. Per row and wavelength, the two source rows are blended once
//! over the span the row reads, then sampled along the row with precomputed positions.

use rayon::prelude::*;

use crate::color::SpectralSampling;

use super::PowerSpectrum;

/// A spectral starburst in linear sRGB on a `P × P` grid (row `j` along +y of the sensor,
/// column `i` along +x, the centre at `(P/2, P/2)`); a bin is [`Self::bin_mm`] on the sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct StarburstPattern {
    size: usize,
    padding: f64,
    reference_nm: f64,
    rgb: Vec<[f32; 3]>,
}

impl StarburstPattern {
    /// The pattern for a light sampled by `sampling` (its wavelengths and weights).
    pub fn new(spectrum: &PowerSpectrum, sampling: &SpectralSampling) -> StarburstPattern {
        let lines: Vec<(f64, [f32; 3])> = sampling
            .wavelengths_nm()
            .iter()
            .copied()
            .zip(sampling.weights().iter().copied())
            .collect();
        Self::from_lines(spectrum, &lines)
    }

    /// The pattern for explicit spectral lines `(λ nm, linear-sRGB weight)`; the shortest
    /// wavelength is the reference λs. An empty list gives a black pattern at 550 nm.
    pub fn from_lines(spectrum: &PowerSpectrum, lines: &[(f64, [f32; 3])]) -> StarburstPattern {
        let p = spectrum.size();
        let reference_nm = lines
            .iter()
            .map(|l| l.0)
            .filter(|l| *l > 0.0)
            .fold(f64::INFINITY, f64::min);
        let reference_nm = if reference_nm.is_finite() {
            reference_nm
        } else {
            550.0
        };
        let c = (p / 2) as f64;
        // Per line: scale, weight × s², and for every column the source column and fraction.
        let scaled: Vec<Line> = lines
            .iter()
            .filter(|l| l.0 > 0.0 && l.0.is_finite())
            .map(|&(lambda, w)| {
                let s = reference_nm / lambda;
                let s2 = (s * s) as f32;
                let columns = (0..p).map(|i| source(c + (i as f64 - c) * s, p)).collect();
                Line {
                    s,
                    weight: w.map(|x| x * s2),
                    columns,
                }
            })
            .collect();
        let mut rgb = vec![[0f32; 3]; p * p];
        let half = p / 2;
        let data = spectrum.data();
        // Rows half..p directly, and row 0 (it has no reflection inside the grid).
        {
            let (top, upper) = rgb.split_at_mut(half * p);
            rows_iter(top, upper, p, half)
                .into_par_iter()
                .for_each_init(
                    || RowScratch::new(p),
                    |scratch, (j, out)| sum_row(data, p, c, j, &scaled, scratch, out),
                );
        }
        // Rows 1..half are the point reflections of rows p−1..half+1; column 0 of those rows
        // has no reflection in the grid and is computed.
        let (low, high) = rgb.split_at_mut(half * p);
        for j in 1..half {
            let src = &high[(p - j - half) * p..][..p];
            let dst = &mut low[j * p..][..p];
            for i in 1..p {
                dst[i] = src[p - i];
            }
        }
        let mut scratch = RowScratch::new(p);
        for j in 1..half {
            let mut row = vec![[0f32; 3]; p];
            sum_row(data, p, c, j, &scaled, &mut scratch, &mut row);
            low[j * p] = row[0];
        }
        apply_edge_window(&mut rgb, p);
        StarburstPattern {
            size: p,
            padding: spectrum.padding(),
            reference_nm,
            rgb,
        }
    }

    /// Side of the grid.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The reference (shortest) wavelength λs (nm).
    pub fn reference_nm(&self) -> f64 {
        self.reference_nm
    }

    /// Zero padding factor of the transform.
    pub fn padding(&self) -> f64 {
        self.padding
    }

    /// Size of one bin on the sensor (mm) for a working f-number `f_number`:
    /// `λs · N / padding` (λs in mm).
    pub fn bin_mm(&self, f_number: f64) -> f64 {
        self.reference_nm * 1e-6 * f_number / self.padding
    }

    /// The linear-sRGB values, row-major (row `j` along +y).
    pub fn rgb(&self) -> &[[f32; 3]] {
        &self.rgb
    }

    /// The value at column `i`, row `j`.
    pub fn at(&self, i: usize, j: usize) -> [f32; 3] {
        self.rgb[j * self.size + i]
    }

    /// `Σ` over the grid, per channel (f64).
    pub fn sum(&self) -> [f64; 3] {
        let mut s = [0f64; 3];
        for v in &self.rgb {
            for c in 0..3 {
                s[c] += f64::from(v[c]);
            }
        }
        s
    }
}

/// Where the edge window starts falling, as a fraction of the inscribed circle's radius.
pub const TAPER_START: f64 = 0.75;

/// The edge window at `r` bins from the centre of a `p × p` grid: 1 within
/// `TAPER_START · R`, `½(1 + cos(π t))` over the taper (`t` from 0 to 1), 0 from `R = p/2 − 1`
/// (the inscribed circle of the grid's sample positions) outward.
pub fn edge_window(r: f64, p: usize) -> f64 {
    let outer = (p / 2) as f64 - 1.0;
    let inner = TAPER_START * outer;
    if r <= inner {
        1.0
    } else if r >= outer {
        0.0
    } else {
        0.5 * (1.0 + (std::f64::consts::PI * (r - inner) / (outer - inner)).cos())
    }
}

/// Multiplies the pattern by [`edge_window`] (rows in parallel; rows entirely inside the
/// taper's start are left alone).
fn apply_edge_window(rgb: &mut [[f32; 3]], p: usize) {
    let c = (p / 2) as f64;
    let inner = TAPER_START * (c - 1.0);
    rgb.par_chunks_mut(p).enumerate().for_each(|(j, row)| {
        let dy = j as f64 - c;
        for (i, v) in row.iter_mut().enumerate() {
            let dx = i as f64 - c;
            let r2 = dx * dx + dy * dy;
            if r2 > inner * inner {
                let w = edge_window(r2.sqrt(), p) as f32;
                *v = v.map(|x| x * w);
            }
        }
    });
}

/// One spectral line, prepared.
struct Line {
    s: f64,
    weight: [f32; 3],
    /// Per output column: source column and the weight of the next one.
    columns: Vec<(u32, f32)>,
}

/// Source index and fraction for a position `x` on an axis of `p` samples (clamped).
fn source(x: f64, p: usize) -> (u32, f32) {
    let last = (p - 1) as f64;
    let x = x.clamp(0.0, last);
    let i0 = (x as usize).min(p - 2);
    (i0 as u32, (x - i0 as f64) as f32)
}

/// The rows computed directly: row 0 and rows `half..p`.
fn rows_iter<'a>(
    top: &'a mut [[f32; 3]],
    upper: &'a mut [[f32; 3]],
    p: usize,
    half: usize,
) -> Vec<(usize, &'a mut [[f32; 3]])> {
    std::iter::once((0usize, &mut top[..p]))
        .chain(upper.chunks_mut(p).enumerate().map(|(k, r)| (half + k, r)))
        .collect()
}

/// Per-thread buffers of [`sum_row`]: the blended source row, one line's samples along the
/// output row, and the three channel sums (separate, so the sums vectorise).
struct RowScratch {
    blend: Vec<f32>,
    samples: Vec<f32>,
    acc: [Vec<f32>; 3],
}

impl RowScratch {
    fn new(p: usize) -> Self {
        RowScratch {
            blend: vec![0.0; p],
            samples: vec![0.0; p],
            acc: [vec![0.0; p], vec![0.0; p], vec![0.0; p]],
        }
    }
}

/// Row `j` of the spectral sum into `out` (overwritten).
fn sum_row(
    data: &[f32],
    p: usize,
    c: f64,
    j: usize,
    lines: &[Line],
    scratch: &mut RowScratch,
    out: &mut [[f32; 3]],
) {
    let RowScratch {
        blend,
        samples,
        acc,
    } = scratch;
    for a in acc.iter_mut() {
        a.fill(0.0);
    }
    for line in lines {
        let (j0, fy) = source(c + (j as f64 - c) * line.s, p);
        let r0 = &data[j0 as usize * p..][..p];
        let r1 = &data[(j0 as usize + 1) * p..][..p];
        // Columns this row reads: from the first to one past the last output column's source.
        let lo = line.columns[0].0 as usize;
        let hi = (line.columns[p - 1].0 as usize + 2).min(p);
        for ((b, &a0), &a1) in blend[lo..hi].iter_mut().zip(&r0[lo..hi]).zip(&r1[lo..hi]) {
            *b = a0 + fy * (a1 - a0);
        }
        for (v, &(i0, fx)) in samples.iter_mut().zip(&line.columns) {
            let a = blend[i0 as usize];
            let b = blend[i0 as usize + 1];
            *v = a + fx * (b - a);
        }
        for (a, &w) in acc.iter_mut().zip(&line.weight) {
            for (o, &v) in a.iter_mut().zip(samples.iter()) {
                *o += w * v;
            }
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = [acc[0][i], acc[1][i], acc[2][i]];
    }
}

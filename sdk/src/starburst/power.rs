//! [`PowerSpectrum`]: `|F|²` of the zero-padded aperture, centred and normalised.
//!
//! **Layout.** `P × P` values, row-major; index `(j, i)` holds the spatial frequency
//! `(i − P/2, j − P/2)` cycles per padded width, `i` along +u (the stop's x) and `j` along +v
//! (its y) — rows go *up*, unlike the aperture mask's rows. The aperture sits in the corner of
//! the padded square; where it sits only changes the phase of `F`, not `|F|²`.
//!
//! **Method.** The mask's columns (texels along v) are the first `pupil_texels` rows of a
//! `P × P` complex buffer; those rows are transformed (the other rows are zero and stay zero),
//! the buffer is transposed in 64 × 64 blocks, and every row is transformed along u. Rows run
//! in parallel (rayon).

use rayon::prelude::*;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex32;

use crate::aperture::{Aperture, ApertureMask};

use super::{StarburstError, StarburstSettings};

/// The normalised power spectrum of an aperture (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct PowerSpectrum {
    size: usize,
    pupil_texels: usize,
    /// `|F|² / (P² Σ a²)`: sums to 1.
    data: Vec<f32>,
    /// `Σ|F|²` (before normalising) and `Σ a²` over the rasterised aperture.
    total_power: f64,
    aperture_energy: f64,
    /// `Σ a` (texels): the aperture's transmitted area in texel units.
    aperture_sum: f64,
}

impl PowerSpectrum {
    /// Rasterises `aperture` (times the optional dust/scratch `overlay`) with
    /// `settings.pupil_texels` across and transforms it, zero-padded by `settings.padding`.
    pub fn compute(
        aperture: &Aperture,
        overlay: Option<&ApertureMask>,
        settings: &StarburstSettings,
    ) -> Result<PowerSpectrum, StarburstError> {
        settings.validate()?;
        aperture.validate()?;
        let n = settings.pupil_texels;
        let mask = aperture.rasterize_with_overlay(n, n, overlay)?;
        Self::from_mask(&mask, settings.padding)
    }

    /// Transforms a rasterised aperture (any `n × m` mask; it is padded to `max(n, m) ×
    /// padding` per side, which must be even).
    pub fn from_mask(mask: &ApertureMask, padding: usize) -> Result<PowerSpectrum, StarburstError> {
        let n = mask.width().max(mask.height());
        let p = n.saturating_mul(padding);
        if padding < 2 {
            return Err(StarburstError::Padding(padding));
        }
        if p > super::MAX_FFT_SIZE || !p.is_multiple_of(2) {
            return Err(StarburstError::FftSize(p));
        }
        let (w, h) = (mask.width(), mask.height());
        let a = mask.data();
        let aperture_sum: f64 = a.iter().map(|&t| f64::from(t)).sum();
        let aperture_energy: f64 = a.iter().map(|&t| f64::from(t) * f64::from(t)).sum();
        // Texels lie in 0..=1, so the sum is finite and never NaN.
        if aperture_energy <= 0.0 {
            return Err(StarburstError::Closed);
        }
        let fft = FftPlanner::<f32>::new().plan_fft_forward(p);
        let zero = Complex32::new(0.0, 0.0);
        // Row c of `buf` is mask column c, texels along +v (mask rows run downward).
        let mut buf = vec![zero; p * p];
        for (c, row) in buf.chunks_mut(p).take(w).enumerate() {
            for (r, x) in row.iter_mut().take(h).enumerate() {
                *x = Complex32::new(a[(h - 1 - r) * w + c], 0.0);
            }
        }
        let scratch_len = fft.get_inplace_scratch_len();
        buf[..w * p].par_chunks_mut(p).for_each_init(
            || vec![zero; scratch_len],
            |scratch, row| fft.process_with_scratch(row, scratch),
        );
        let mut t = vec![zero; p * p];
        transpose(&buf, &mut t, p);
        drop(buf);
        t.par_chunks_mut(p).for_each_init(
            || vec![zero; scratch_len],
            |scratch, row| fft.process_with_scratch(row, scratch),
        );
        // t[kv·P + ku] = F(ku, kv): row kv is frequency kv along v. Centre both axes.
        let half = p / 2;
        let mut data = vec![0f32; p * p];
        let total_power: f64 = data
            .par_chunks_mut(p)
            .enumerate()
            .map(|(j, out)| {
                let src = &t[((j + half) % p) * p..][..p];
                let mut sum = 0.0f64;
                for (i, o) in out.iter_mut().enumerate() {
                    let f = src[(i + half) % p];
                    let v = f.norm_sqr();
                    sum += f64::from(v);
                    *o = v;
                }
                sum
            })
            .sum();
        let norm = (1.0 / (p as f64 * p as f64 * aperture_energy)) as f32;
        data.par_iter_mut().for_each(|v| *v *= norm);
        Ok(PowerSpectrum {
            size: p,
            pupil_texels: n,
            data,
            total_power,
            aperture_energy,
            aperture_sum,
        })
    }

    /// Side of the transform, `P`.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Texels across the aperture's square.
    pub fn pupil_texels(&self) -> usize {
        self.pupil_texels
    }

    /// Zero padding factor `P / pupil_texels` (a bin is `λ·N/padding` on the sensor).
    pub fn padding(&self) -> f64 {
        self.size as f64 / self.pupil_texels as f64
    }

    /// The normalised values, row-major (module docs); they sum to 1.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// `Σ|F|²` before normalising.
    pub fn total_power(&self) -> f64 {
        self.total_power
    }

    /// `Σ a²` over the rasterised aperture's texels.
    pub fn aperture_energy(&self) -> f64 {
        self.aperture_energy
    }

    /// `Σ a` over the rasterised aperture's texels (its open area in texels).
    pub fn aperture_sum(&self) -> f64 {
        self.aperture_sum
    }

    /// Value at `(i, j)` (column along u, row along v), 0 outside.
    pub fn at(&self, i: usize, j: usize) -> f32 {
        if i < self.size && j < self.size {
            self.data[j * self.size + i]
        } else {
            0.0
        }
    }
}

/// `dst = srcᵀ` for `p × p` row-major buffers, in 64 × 64 blocks, block rows in parallel.
fn transpose(src: &[Complex32], dst: &mut [Complex32], p: usize) {
    const B: usize = 64;
    dst.par_chunks_mut(B * p)
        .enumerate()
        .for_each(|(bi, rows)| {
            let r0 = bi * B;
            let nr = rows.len() / p;
            for c0 in (0..p).step_by(B) {
                let nc = B.min(p - c0);
                for dr in 0..nr {
                    let out = &mut rows[dr * p + c0..][..nc];
                    for (dc, o) in out.iter_mut().enumerate() {
                        *o = src[(c0 + dc) * p + r0 + dr];
                    }
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transpose_is_a_transpose() {
        let p = 130;
        let src: Vec<Complex32> = (0..p * p)
            .map(|k| Complex32::new(k as f32, -(k as f32)))
            .collect();
        let mut dst = vec![Complex32::new(0.0, 0.0); p * p];
        transpose(&src, &mut dst, p);
        for r in 0..p {
            for c in 0..p {
                assert_eq!(dst[r * p + c], src[c * p + r]);
            }
        }
    }

    #[test]
    fn a_single_texel_has_a_flat_spectrum() {
        // One open texel: F = 1 at every frequency, so every bin holds 1/P².
        let mut v = vec![0f32; 16 * 16];
        v[5 * 16 + 9] = 1.0;
        let mask = ApertureMask::from_luma_f32(16, 16, &v).unwrap();
        let s = PowerSpectrum::from_mask(&mask, 2).unwrap();
        let p = s.size();
        assert_eq!(p, 32);
        for &x in s.data() {
            assert!((x - 1.0 / (p * p) as f32).abs() < 1e-9);
        }
    }

    #[test]
    fn a_closed_aperture_is_an_error() {
        let mask = ApertureMask::from_luma_f32(16, 16, &[0.0; 256]).unwrap();
        assert_eq!(
            PowerSpectrum::from_mask(&mask, 4),
            Err(StarburstError::Closed)
        );
    }
}

//! Aperture masks: a transmission image over [-1, 1]², sampled bilinearly, with a signed
//! distance field worked out once when the mask is built.
//!
//! **Layout.** Row-major, row 0 at the top of the image (v = +1), column 0 at u = −1. Texel
//! `(row, col)` has its centre at `u = −1 + (col + 1/2)·2/width`, `v = 1 − (row + 1/2)·2/height`.
//! Between the outermost texel centres and the square's edge the value is held
//! (clamp to edge); outside the square the transmission is 0. With that reconstruction the
//! integral of the transmission is exactly `Σ T × texel area`.
//!
//! **Distance field.** The opening is where the transmission is at least 1/2. A Euclidean
//! distance transform (Felzenszwalb & Huttenlocher 2012, exact on the texel grid, anisotropic
//! texels allowed) gives each texel centre's distance to the nearest texel centre on the
//! other side; half a texel is taken off, putting the edge midway between the two, and the
//! square's edge closes the opening. The field is sampled bilinearly between texel centres,
//! so it is good to about a texel (`2/width`); beyond the outermost centres the distance to
//! them is added. Grey levels only move the edge by where they cross 1/2.

use super::ApertureError;

/// Masks larger than this many texels are refused (two f32 fields of 2²⁶ texels: 512 MiB).
pub const MAX_MASK_TEXELS: usize = 1 << 26;

/// Distances are clamped to ±this: larger than anything inside the square (its diagonal is
/// 2√2), so only a mask with no open texel reaches it.
const DISTANCE_LIMIT: f32 = 4.0;

/// What the distance transform uses for "no feature here" (squared distance; finite so the
/// lower-envelope arithmetic has no ∞ − ∞).
const FAR: f64 = 1e20;

/// OpenLensFlare's clip value for its distance-map masks: the aperture is open where the map
/// is below it (`fIrisClip` / `m_distanceClip`, 0.95 by default; its precomputation uses
/// 0.95001).
pub const OLF_DISTANCE_CLIP: f32 = 0.95;

/// A transmission image over [-1, 1]² (module docs for layout and sampling).
#[derive(Clone, Debug, PartialEq)]
pub struct ApertureMask {
    width: usize,
    height: usize,
    /// Transmission 0..=1, row-major, row 0 at v = +1.
    data: Vec<f32>,
    /// Signed distance to the edge at each texel centre (normalised units, negative inside).
    distance: Vec<f32>,
    /// Every texel is 0 or 1 and the texels are at most twice as wide as tall (or tall as
    /// wide): then [`ApertureMask::uniform_around`] may decide where the bilinear
    /// transmission is 0 or 1 from the distance field.
    binary: bool,
    /// A bound on the slope of the distance field's bilinear interpolation (per normalised
    /// unit), from its largest differences between neighbouring texels along each axis.
    lipschitz: f32,
}

/// Checks a mask size: both sides positive, at most [`MAX_MASK_TEXELS`] texels; the texel
/// count.
pub fn check_mask_size(width: usize, height: usize) -> Result<usize, ApertureError> {
    if width == 0 || height == 0 {
        return Err(ApertureError::EmptyMask { width, height });
    }
    match width.checked_mul(height) {
        Some(n) if n <= MAX_MASK_TEXELS => Ok(n),
        _ => Err(ApertureError::MaskTooLarge {
            width,
            height,
            max: MAX_MASK_TEXELS,
        }),
    }
}

fn check_len(width: usize, height: usize, got: usize) -> Result<(), ApertureError> {
    let expected = check_mask_size(width, height)?;
    if got != expected {
        return Err(ApertureError::MaskLength {
            width,
            height,
            expected,
            got,
        });
    }
    Ok(())
}

impl ApertureMask {
    /// A mask from 8-bit grey values, 255 fully open (`T = value / 255`).
    pub fn from_luma(width: usize, height: usize, luma: &[u8]) -> Result<Self, ApertureError> {
        check_len(width, height, luma.len())?;
        let data = luma.iter().map(|&b| f32::from(b) / 255.0).collect();
        Ok(Self::build(width, height, data))
    }

    /// A mask from transmissions in 0..=1; anything else (NaN included) is an error naming
    /// the texel.
    pub fn from_luma_f32(
        width: usize,
        height: usize,
        values: &[f32],
    ) -> Result<Self, ApertureError> {
        check_len(width, height, values.len())?;
        check_unit_range(width, values)?;
        Ok(Self::build(width, height, values.to_vec()))
    }

    /// A mask from an OpenLensFlare distance map (`lenses/masks/apertureDist.bmp`): values in
    /// 0..=1, small at the centre, rising to the edge of the opening and 1 outside. As
    /// OpenLensFlare's shaders do, the aperture is open (1) where the value is below `clip`
    /// ([`OLF_DISTANCE_CLIP`]) and closed (0) elsewhere.
    pub fn from_olf_distance_map(
        width: usize,
        height: usize,
        values: &[f32],
        clip: f32,
    ) -> Result<Self, ApertureError> {
        check_len(width, height, values.len())?;
        check_unit_range(width, values)?;
        if !(0.0..=1.0).contains(&clip) {
            return Err(ApertureError::DistanceClip(clip));
        }
        let data = values
            .iter()
            .map(|&d| if d < clip { 1.0 } else { 0.0 })
            .collect();
        Ok(Self::build(width, height, data))
    }

    fn build(width: usize, height: usize, data: Vec<f32>) -> Self {
        let distance = distance_field(width, height, &data);
        let (tu, tv) = (2.0 / width as f64, 2.0 / height as f64);
        let binary = tu.max(tv) <= 2.0 * tu.min(tv) && data.iter().all(|&t| t == 0.0 || t == 1.0);
        let lipschitz = field_slope(width, height, &distance, tu, tv);
        ApertureMask {
            width,
            height,
            data,
            distance,
            binary,
            lipschitz,
        }
    }

    /// Texels per row.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Transmissions, row-major, row 0 at v = +1.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// The signed distance to the edge at each texel centre (normalised units, negative
    /// inside), row-major like [`Self::data`]: the field [`Self::signed_distance`] interpolates.
    pub fn distance_field(&self) -> &[f32] {
        &self.distance
    }

    /// Every texel is 0 or 1 (and the texels are at most twice as wide as tall, or tall as
    /// wide): what [`Self::uniform_around`] needs to decide for a feather of a texel or less.
    pub fn is_binary(&self) -> bool {
        self.binary
    }

    /// A bound on the slope of [`Self::signed_distance`]'s bilinear interpolation (per
    /// normalised unit); [`Self::uniform_around`] adds 1 for the distance beyond the
    /// outermost texel centres.
    pub fn field_slope(&self) -> f32 {
        self.lipschitz
    }

    /// A texel's width and height in normalised units (`2/width`, `2/height`).
    pub fn texel_size(&self) -> (f32, f32) {
        (2.0 / self.width as f32, 2.0 / self.height as f32)
    }

    /// Bilinear transmission at `(u, v)`; 0 outside [-1, 1]² (and for NaN).
    pub fn transmission(&self, u: f32, v: f32) -> f32 {
        if !(u.abs() <= 1.0 && v.abs() <= 1.0) {
            return 0.0;
        }
        self.bilinear(&self.data, u, v)
    }

    /// Signed distance to the edge of the opening, to about a texel (module docs).
    pub fn signed_distance(&self, u: f32, v: f32) -> f32 {
        // The field is known at texel centres; beyond the outermost ones, add the distance
        // to them (the triangle inequality keeps this an upper bound out there).
        let (tu, tv) = self.texel_size();
        let (eu, ev) = (1.0 - 0.5 * tu, 1.0 - 0.5 * tv);
        let (uc, vc) = (u.clamp(-eu, eu), v.clamp(-ev, ev));
        let (du, dv) = (u - uc, v - vc);
        let beyond = (du * du + dv * dv).sqrt();
        self.bilinear(&self.distance, uc, vc) + beyond
    }

    /// Where [`crate::aperture::ApertureSampler::transmission_soft`] of this mask is the same
    /// at every point within `radius` of `(u, v)`: `Some(1.0)` wholly open, `Some(0.0)` wholly
    /// closed, `None` where it may vary (or this cannot tell). Conservative, from the distance
    /// field at `(u, v)` alone:
    ///
    /// - a feather of at most a texel gives the bilinear transmission, which is 1 (or 0)
    ///   where every texel centre it blends is open (closed) and the mask is binary; the
    ///   field at `(u, v)` is within a texel diagonal of the distance to the nearest texel
    ///   centre on the other side, so `|d| ≥ 2 radius + 4 texels` leaves every centre within
    ///   `radius` plus a diagonal on one side;
    /// - a wider feather ramps on the field, whose slope is at most `lipschitz` within the
    ///   square of the outermost texel centres and `lipschitz + 1` beyond (the distance to
    ///   them added): wholly open where `d + slope · radius ≤ −feather/2`, closed where
    ///   `d − slope · radius ≥ feather/2`.
    pub fn uniform_around(&self, u: f32, v: f32, radius: f32, feather: f32) -> Option<f32> {
        let d = f64::from(self.signed_distance(u, v));
        let (tu, tv) = self.texel_size();
        let (r, f) = (f64::from(radius), f64::from(feather));
        let margin = if feather <= tu.max(tv) {
            if !self.binary {
                return None;
            }
            2.0 * r + 4.0 * f64::from(tu.max(tv))
        } else {
            self.slope_within(u, v, r) * r + 0.5 * f
        };
        // A little more for the roundings of f32 positions and distances.
        let margin = margin + UNIFORM_SLACK;
        if d <= -margin {
            Some(1.0)
        } else if d >= margin {
            Some(0.0)
        } else {
            None
        }
    }

    /// The soft transmission at `(u, v)` (as `ApertureSampler::transmission_soft`, `feather`
    /// positive) and a distance within which it is the same: [`Self::uniform_around`]'s
    /// margins solved for the radius (0 where they leave none), for a wide feather with the
    /// field's slope among the texel centres (`lipschitz`, without the distance added beyond
    /// them) as far as they reach.
    pub fn transmission_reach(&self, u: f32, v: f32, feather: f32) -> (f32, f32) {
        let (tu, tv) = self.texel_size();
        let d = f64::from(self.signed_distance(u, v));
        let (t, reach) = if feather <= tu.max(tv) {
            let t = self.transmission(u, v);
            // Over max(2, slope): within it of (u, v), the field keeps the margin
            // `uniform_around` asks there.
            let reach = if self.binary {
                (d.abs() - 4.0 * f64::from(tu.max(tv)) - UNIFORM_SLACK)
                    / (f64::from(self.lipschitz) + 1.0).max(2.0)
            } else {
                0.0
            };
            (t, reach)
        } else {
            let f = f64::from(feather);
            let t = super::smooth_edge(d, f) as f32;
            let room = d.abs() - 0.5 * f - UNIFORM_SLACK;
            let slope = f64::from(self.lipschitz);
            // Within the texel centres' square, the field's slope is `lipschitz`
            // (`slope_within`).
            let reach = (room / (slope + 1.0)).max((room / slope).min(self.to_centres_edge(u, v)));
            (t, reach)
        };
        (t, if reach > 0.0 { reach as f32 } else { 0.0 })
    }

    /// A bound on the distance field's slope within `radius` of `(u, v)`: `lipschitz` where
    /// that disc lies within the square of the outermost texel centres (the bilinear field's
    /// own slope), `lipschitz + 1` elsewhere (the distance beyond them added).
    fn slope_within(&self, u: f32, v: f32, radius: f64) -> f64 {
        let inside = radius <= self.to_centres_edge(u, v);
        f64::from(self.lipschitz) + if inside { 0.0 } else { 1.0 }
    }

    /// The distance from `(u, v)` to the edge of the square of the outermost texel centres
    /// (negative outside it).
    fn to_centres_edge(&self, u: f32, v: f32) -> f64 {
        let (tu, tv) = self.texel_size();
        let (eu, ev) = (1.0 - 0.5 * f64::from(tu), 1.0 - 0.5 * f64::from(tv));
        (eu - f64::from(u).abs()).min(ev - f64::from(v).abs())
    }

    /// `Σ T × texel area`: the exact integral of the bilinear transmission (module docs).
    pub fn open_area(&self) -> f64 {
        let sum: f64 = self.data.iter().map(|&t| f64::from(t)).sum();
        sum * 4.0 / (self.width as f64 * self.height as f64)
    }

    /// Bilinear interpolation of a texel field at a point of the square, clamped to edge.
    fn bilinear(&self, field: &[f32], u: f32, v: f32) -> f32 {
        let (i0, i1, fx) = axis(f64::from(u) + 1.0, self.width);
        let (j0, j1, fy) = axis(1.0 - f64::from(v), self.height);
        let at = |j: usize, i: usize| f64::from(field[j * self.width + i]);
        let top = at(j0, i0) + fx * (at(j0, i1) - at(j0, i0));
        let bottom = at(j1, i0) + fx * (at(j1, i1) - at(j1, i0));
        (top + fy * (bottom - top)) as f32
    }
}

/// Normalised units added to [`ApertureMask::uniform_around`]'s margins for roundings.
const UNIFORM_SLACK: f64 = 1e-5;

/// A bound on the slope of the bilinear interpolation of `field` (texels `tu` × `tv`): the
/// hypotenuse of its largest differences between neighbours along each axis over the
/// spacing (within a cell each partial derivative is a blend of two such differences).
fn field_slope(width: usize, height: usize, field: &[f32], tu: f64, tv: f64) -> f32 {
    let (mut gu, mut gv) = (0.0_f64, 0.0_f64);
    for row in 0..height {
        for col in 0..width {
            let d = f64::from(field[row * width + col]);
            if col + 1 < width {
                gu = gu.max((f64::from(field[row * width + col + 1]) - d).abs() / tu);
            }
            if row + 1 < height {
                gv = gv.max((f64::from(field[(row + 1) * width + col]) - d).abs() / tv);
            }
        }
    }
    gu.hypot(gv) as f32
}

/// For a position `p` in 0..=2 along an axis of `n` texels: the two texels to blend and the
/// weight of the second, clamped to edge. NaN lands on texel 0.
fn axis(p: f64, n: usize) -> (usize, usize, f64) {
    let last = (n - 1) as f64;
    let x = p * 0.5 * n as f64 - 0.5;
    let x = if x >= last {
        last
    } else if x > 0.0 {
        x
    } else {
        0.0
    };
    // `x` is in 0..=n−1, so the cast is exact and in range.
    let i0 = x as usize;
    let i1 = (i0 + 1).min(n - 1);
    (i0, i1, x - i0 as f64)
}

fn check_unit_range(width: usize, values: &[f32]) -> Result<(), ApertureError> {
    match values.iter().position(|t| !(0.0..=1.0).contains(t)) {
        None => Ok(()),
        Some(i) => Err(ApertureError::MaskValue {
            row: i / width,
            column: i % width,
            value: values[i],
        }),
    }
}

/// The signed distance at every texel centre (module docs).
fn distance_field(width: usize, height: usize, data: &[f32]) -> Vec<f32> {
    let (sx, sy) = (2.0 / width as f64, 2.0 / height as f64);
    let half = 0.25 * (sx + sy);
    let open: Vec<bool> = data.iter().map(|&t| t >= 0.5).collect();
    let to_open = squared_edt(width, height, sx, sy, &open, true);
    let to_closed = squared_edt(width, height, sx, sy, &open, false);
    let mut out = Vec::with_capacity(data.len());
    for row in 0..height {
        let v = 1.0 - (row as f64 + 0.5) * sy;
        for col in 0..width {
            let u = -1.0 + (col as f64 + 0.5) * sx;
            let i = row * width + col;
            let d = if open[i] {
                let to_square_edge = (1.0 - u.abs()).min(1.0 - v.abs());
                -(to_closed[i].sqrt() - half).min(to_square_edge)
            } else {
                to_open[i].sqrt() - half
            };
            out.push((d as f32).clamp(-DISTANCE_LIMIT, DISTANCE_LIMIT));
        }
    }
    out
}

/// Squared Euclidean distance from every texel centre to the nearest centre whose `open`
/// flag equals `feature` (≥ [`FAR`]/2 when there is none); texels are `sx` × `sy`.
fn squared_edt(
    width: usize,
    height: usize,
    sx: f64,
    sy: f64,
    open: &[bool],
    feature: bool,
) -> Vec<f64> {
    let mut grid: Vec<f64> = open
        .iter()
        .map(|&o| if o == feature { 0.0 } else { FAR })
        .collect();
    let n = width.max(height);
    let mut f = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0.0; n + 1];
    for row in 0..height {
        let line = &mut grid[row * width..(row + 1) * width];
        f[..width].copy_from_slice(line);
        edt_1d(&f[..width], sx, &mut d[..width], &mut v, &mut z);
        line.copy_from_slice(&d[..width]);
    }
    for col in 0..width {
        for row in 0..height {
            f[row] = grid[row * width + col];
        }
        edt_1d(&f[..height], sy, &mut d[..height], &mut v, &mut z);
        for row in 0..height {
            grid[row * width + col] = d[row];
        }
    }
    grid
}

/// One dimension of the distance transform: `d[p] = min_q (f[q] + ((p − q)·step)²)` by the
/// lower envelope of parabolas. `v` and `z` are scratch of at least `f.len()` and
/// `f.len() + 1`.
fn edt_1d(f: &[f64], step: f64, d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    let x = |q: usize| q as f64 * step;
    let meet =
        |q: usize, p: usize| ((f[q] + x(q) * x(q)) - (f[p] + x(p) * x(p))) / (2.0 * (x(q) - x(p)));
    let mut k = 0;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let mut s = meet(q, v[k]);
        while s <= z[k] && k > 0 {
            k -= 1;
            s = meet(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, out) in d.iter_mut().enumerate().take(n) {
        while z[k + 1] < x(q) {
            k += 1;
        }
        let dx = x(q) - x(v[k]);
        *out = dx * dx + f[v[k]];
    }
}

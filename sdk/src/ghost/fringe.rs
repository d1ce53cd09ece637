//! One mesh for all of a ghost's wavelength bands, its colour fringes shaded per pixel.
//!
//! Drawn band by band, a dispersive ghost costs its whole area once per band, although the
//! bands' images differ only near the ghost's edges (where the clip radius and the aperture's
//! outline fall at slightly different places for each wavelength) and by a small shift inside.
//! [`mesh_ghost_fringed`] traces every band, then makes each grid triangle once, at the bands'
//! mean position, carrying:
//!
//! - the sum over bands of its irradiance, each band's flux over *its own* triangle's area:
//!   what a band adds at a point of the sensor is its irradiance there, wherever the mean
//!   triangle puts it (over the mean area, a band whose image is larger than the mean would
//!   gain light; measured, +0.5% on the Heliar's frame);
//! - for the clip radius and the stop crossing, each band's value *at the mean triangle's
//!   corners* — band `b`'s triangle is an affine map of the grid cell, so the value it would
//!   have at any point of the sensor is its affine extension, exact within the triangle — fitted
//!   by a line in a dispersion coordinate `τ ∈ [0, 1]` (`1/λ²`, normalised over the ghost's
//!   bins, in which a glass's index, and so the ghost's geometry, is nearly linear).
//!
//! Per pixel the open bands form an interval of `τ` (the clip radius is linear in `τ`, the
//! circular stop's `|(u, v)|²` a parabola), each end feathered by a linear ramp as wide as the
//! feather's smoothstep spreads; the pixel takes its summed irradiance times, per channel, the
//! share of the ghost's colour that falls in the interval — a lookup in the ghost's cumulative
//! colour over `τ` ([`FringeTable`]). A single end whose ramp spans much of `τ`'s range (a
//! ghost drawn coarse, its dispersion under a feather) is integrated exactly instead: its
//! smoothstep of a linear function of `τ` is a cubic in `τ` against the colour's tabulated
//! partial moments (the stop's radius taken as linear along `τ` where it sags from its chord by
//! under [`MAX_SAG`] of a feather). Where ends' smoothsteps overlap, several ends are wide or the
//! stop is grazed, the exact smoothsteps are summed over [`CORNER_STEPS`] steps of `τ`. Inside
//! the ghost this is one shade instead of one per band.
//!
//! An iris or a mask has no parabola in `τ`: on its outline ([`APERTURE_FLAG`]) the pixel's
//! stop crossing `(u, v)(τ)` — a segment, as each band's crossing is where the circle's is — is
//! stepped over `τ` in [`CORNER_STEPS`] steps, each taking the clip's smoothstep times the
//! aperture's soft transmission there (the band-by-band edge shade, with the same feather)
//! times the step's share of the colour. Where the aperture's transmission is known to be 0
//! or 1 all along the segment ([`crate::aperture::ApertureSampler::uniform_around`]), the pixel
//! is dark or takes the clip's share alone; steps within a known transmission's reach are not
//! evaluated, and a row's pixels closed at its ends or open in its middle are found by tracing
//! the segments' middles along it ([`FringeShader::split_row`]). A triangle closed all over
//! its stop crossings is not drawn.
//!
//! A triangle is drawn band by band as before (`BandTriangles::push` in [`super::triangles`]) where
//! the model does not hold: a ray of some band stopped, the bands' triangles differ in
//! orientation or by more than [`MAX_AREA_RATIO`] in area (a fold, a caustic), or, on an edge,
//! a band's value departs from the line by more than a quarter of the feather — and the whole
//! ghost is, when more than [`MAX_FAILED_SHARE`] of its triangles do not hold.

use crate::aperture::{Aperture, ApertureSampler};
use crate::raster::{RowSplit, Shader};

use super::context::{BandRef, GhostContext, GhostGrid, GhostStats};
use super::fringe_table::FringeTable;
use super::grid::GridTrace;
use super::mesh::GhostMesh;
use super::row_split::{
    APERTURE_SPLIT_MARGIN, SPLIT_MARGIN, StepNorm, aperture_split, intersect, linear_split_with,
    parabola_below_with, smoothstep,
};
use super::triangles::{BandTriangles, grid_triangles, len, trace_band};

/// Attributes of a fringed triangle's corner: summed RGB irradiance, the clip radius at
/// `τ = 0` and its change over `τ ∈ [0, 1]`, likewise the stop crossing's `u` and `v`, the
/// feather width, the stop flag — 0 where the aperture is not evaluated, 1 where the circular
/// stop is (analytically), 2 where another aperture is ([`FringeShader::aperture`], stepped
/// over `τ`: [`APERTURE_FLAG`]) — and the index of the ghost's [`FringeTable`] in
/// [`GhostMesh::fringe_tables`].
pub type FringeAttrs = [f32; 12];

/// The stop flag (attribute 10) of a fringed triangle on the outline of an aperture other
/// than the circle: the shader takes the aperture's soft transmission at the stop crossing
/// `(u, v)(τ)` in [`CORNER_STEPS`] steps of `τ` (a stepped path of the crossing over the
/// group's wavelengths), where the circle's open interval is found analytically.
pub const APERTURE_FLAG: f32 = 2.0;

/// Largest ratio between the areas of a grid triangle's images in two bands for which the
/// triangle is drawn once: beyond it the cell folds or focuses (a caustic) and is drawn band
/// by band. Measured against the reference (light 10°, 30°): 1.3 rather than 1.1 takes about
/// 10% off the Nikon zoom's default render at 1920 × 1080 (fewer of its near-focus ghosts fall
/// back to band by band) for an error at 960 × 540 of 1.570% against 1.557% (with a table
/// 1.761% against 1.751%); the Heliar's does not move; 1.6 gains nothing more.
pub const MAX_AREA_RATIO: f64 = 1.3;

/// Largest share of a ghost's grid triangles that may be drawn band by band among fringed
/// ones; beyond it the whole ghost is. Measured on the Nikon zoom: mixing more raises its
/// error from 1.88% to 2.5–4% (the seams between fringed and band-by-band triangles differ per
/// band).
pub const MAX_FAILED_SHARE: f64 = 0.05;

/// Width of the linear ramp that stands for the feather's smoothstep, in feathers:
/// `√(12/20)`.
const RAMP_WIDTH: f32 = 0.774_596_7;

/// Width in `τ` beyond which one end's ramp is summed step by step.
const WIDE_RAMP: f32 = 0.25;

/// Largest sag (in feathers) of the stop's radius below its chord over `τ ∈ [0, 1]` for which
/// a wide end of the stop is integrated as linear in `τ`.
pub const MAX_SAG: f32 = 0.01;

/// Largest departure (in transmission, of the pixel's irradiance) of an aperture's
/// transmission at the middle of a pixel's segment of stop crossings from its ends' mean for
/// which it is integrated as linear along the segment ([`FringeShader::aperture_linear`]).
pub const LINEAR_SAG: f32 = 1e-3;

/// Steps over `τ` where the clip's and the stop's ends meet in the range, where the stop is
/// grazed, or where an end's ramp is wide; and over the whole range where another aperture's
/// outline is drawn ([`APERTURE_FLAG`]).
pub const CORNER_STEPS: usize = 16;

/// A linear ramp of the open share over `τ`: 0 at `closed`, 1 at `open`.
#[derive(Clone, Copy, Debug)]
struct Ramp {
    closed: f32,
    open: f32,
}

/// What a fringed triangle's rows share ([`FringeShader::split_row`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct FringeRows {
    /// The clip's outer and inner bounds on the relative radius, with [`SPLIT_MARGIN`].
    bounds: [f64; 2],
    /// `1 /` the step along x of the clip radius at either end of τ.
    inv_radius_step: [f64; 2],
    /// The circular stop's outline is drawn (flagged 1).
    stop: bool,
    /// Another aperture's outline is drawn ([`APERTURE_FLAG`]): no pixel is wholly open.
    aperture: bool,
    /// Half the longest segment of the stop crossing over τ, of the triangle's corners.
    reach: f64,
    /// The step along x of the segment's middle, and the norms of that step and of its
    /// ends'.
    middle_step: [f64; 2],
    stop_steps: [StepNorm; 3],
}

/// Shades [`FringeAttrs`] triangles: the summed irradiance times each channel's share of the
/// ghost's colour over the open interval of `τ`.
#[derive(Debug)]
pub struct FringeShader<'a> {
    pub tables: &'a [FringeTable],
    /// The aperture of triangles flagged [`APERTURE_FLAG`] (the frame's; for the circle,
    /// whose triangles are flagged 1, unused: [`crate::aperture::CIRCLE_SAMPLER`]).
    pub aperture: ApertureSampler<'a>,
}

impl FringeShader<'_> {
    /// The open share of a triangle flagged [`APERTURE_FLAG`]: where the aperture's soft
    /// transmission is 1 along the pixel's whole segment of stop crossings over `τ` (from
    /// its middle, [`ApertureSampler::uniform_around`] within half its length), the clip's
    /// share alone; 0 where it is 0 there. Otherwise, where the clip is open all along `τ`
    /// and the transmission is the feather's smoothstep of a signed distance that is linear
    /// along the segment (its sag under [`MAX_SAG`] of a feather), that smoothstep is shaded
    /// as the clip's would be ([`aperture_as_clip`]): three evaluations of the aperture; where
    /// the clip is open and the transmission itself is linear along the segment, it is
    /// integrated as such ([`FringeShader::aperture_linear`]). Elsewhere, the clip's
    /// smoothstep times the aperture's transmission summed over [`CORNER_STEPS`] steps of `τ`.
    fn aperture_share(&self, a: &FringeAttrs) -> [f32; 3] {
        let (mu, mv) = (a[5] + 0.5 * a[6], a[7] + 0.5 * a[8]);
        let half = 0.5 * (a[6] * a[6] + a[8] * a[8]).sqrt();
        match self.aperture.uniform_around(mu, mv, half, a[9]) {
            Some(0.0) => [0.0; 3],
            Some(_) => {
                let mut clip = *a;
                clip[10] = 0.0;
                self.open_share(&clip)
            }
            None => match aperture_as_clip(&self.aperture, a) {
                Some(clip) => self.open_share(&clip),
                None => self
                    .aperture_linear(a)
                    .unwrap_or_else(|| self.aperture_stepped(a, CORNER_STEPS)),
            },
        }
    }

    /// The open share of a triangle flagged [`APERTURE_FLAG`] where the clip is open all along
    /// `τ` and the aperture's soft transmission is linear along the pixel's segment of stop
    /// crossings (its value at the middle within [`LINEAR_SAG`] of its ends' mean; a mask
    /// sampled bilinearly under a feather of a texel, across a segment short against a
    /// texel): `∫ (t0 + τ (t1 − t0)) dF = t0 + (t1 − t0)(1 − H(1))` per channel, `H` the
    /// colour's integral ([`FringeTable::integral`]). `None` elsewhere.
    fn aperture_linear(&self, a: &FringeAttrs) -> Option<[f32; 3]> {
        let f = a[9];
        if !clip_open_along_tau(a) {
            return None;
        }
        let t = |s: f32| {
            self.aperture
                .transmission_soft(a[5] + s * a[6], a[7] + s * a[8], f)
        };
        let (t0, t_mid, t1) = (t(0.0), t(0.5), t(1.0));
        let sag = (t0 + t1 - 2.0 * t_mid).abs();
        if sag.is_nan() || sag > 2.0 * LINEAR_SAG {
            return None;
        }
        let h = self.tables[a[11] as usize].integral(1.0);
        Some(h.map(|h| t0 + (t1 - t0) * (1.0 - h)))
    }

    /// [`FringeShader::stepped_share`] of a triangle flagged [`APERTURE_FLAG`], the same sum
    /// with fewer evaluations of the aperture: a step whose clip is closed needs none, and
    /// where the aperture's transmission is known to be 0 or 1 within some distance
    /// ([`ApertureSampler::transmission_reach`]) the steps of the stop crossing inside it take
    /// that value (consecutive steps are `|(u1, v1)| / steps` apart).
    fn aperture_stepped(&self, a: &FringeAttrs, steps: usize) -> [f32; 3] {
        let f = a[9];
        let table = &self.tables[a[11] as usize];
        let width = 1.0 / steps as f32;
        let step_len = (a[6] * a[6] + a[8] * a[8]).sqrt() * width;
        let mut prev = table.share(0.0);
        let mut acc = [0.0_f32; 3];
        // Steps before `known_until` have transmission `known`.
        let (mut known_until, mut known) = (0_usize, 0.0_f32);
        for i in 0..steps {
            let next = table.share((i + 1) as f32 * width);
            let t = (i as f32 + 0.5) * width;
            let clip = smoothstep(1.0 + 0.5 * f, 1.0 - 0.5 * f, a[3] + t * a[4]);
            if clip > 0.0 {
                let transmission = if i < known_until {
                    known
                } else {
                    let (u, v) = (a[5] + t * a[6], a[7] + t * a[8]);
                    let (tr, reach) = self.aperture.transmission_reach(u, v, f);
                    if reach > 0.0 {
                        let ahead = if step_len > 0.0 {
                            (reach / step_len).min(steps as f32) as usize
                        } else {
                            steps
                        };
                        (known_until, known) = (i + 1 + ahead, tr);
                    }
                    tr
                };
                let w = clip * transmission;
                for c in 0..3 {
                    acc[c] += w * (next[c] - prev[c]);
                }
            }
            prev = next;
        }
        acc
    }

    /// The open share summed over `steps` even steps of `τ`: at each step's middle the
    /// feather's own smoothstep of the clip radius and (where flagged) of the stop's exact
    /// radius, times the step's share of the colour. With many steps, the tests' oracle.
    fn stepped_share(&self, a: &FringeAttrs, steps: usize) -> [f32; 3] {
        self.stepped_between(a, steps, 0.0, 1.0)
    }

    /// [`FringeShader::stepped_share`] with the steps over `[lo, hi]` (within `[0, 1]`)
    /// only: each part below and above it takes its colour share at one weight, that of its
    /// side's end. The clip's smoothstep is constant there exactly; the stop's only nearly
    /// (its span is its ramp's straight extension, while its radius is convex in `τ`: at a
    /// stop grazed by half a feather, about 1% of that part's colour).
    fn stepped_between(&self, a: &FringeAttrs, steps: usize, lo: f32, hi: f32) -> [f32; 3] {
        let f = a[9];
        let table = &self.tables[a[11] as usize];
        let weight = |t: f32| {
            let mut w = smoothstep(1.0 + 0.5 * f, 1.0 - 0.5 * f, a[3] + t * a[4]);
            if a[10] > 1.5 {
                let (u, v) = (a[5] + t * a[6], a[7] + t * a[8]);
                w *= self.aperture.transmission_soft(u, v, f);
            } else if a[10] > 0.5 {
                let (u, v) = (a[5] + t * a[6], a[7] + t * a[8]);
                w *= smoothstep(1.0 + 0.5 * f, 1.0 - 0.5 * f, (u * u + v * v).sqrt());
            }
            w
        };
        let mut prev = table.share(lo);
        let mut acc = if lo > 0.0 {
            let w = weight(0.5 * lo);
            prev.map(|p| w * p)
        } else {
            [0.0_f32; 3]
        };
        let width = (hi - lo) / steps as f32;
        for i in 0..steps {
            let next = table.share(lo + (i + 1) as f32 * width);
            let w = weight(lo + (i as f32 + 0.5) * width);
            for c in 0..3 {
                acc[c] += w * (next[c] - prev[c]);
            }
            prev = next;
        }
        if hi < 1.0 {
            let w = weight(0.5 * (hi + 1.0));
            for c in 0..3 {
                acc[c] += w * (1.0 - prev[c]);
            }
        }
        acc
    }

    /// The open share per channel at a pixel with attributes `a` (no aperture outline unless
    /// flagged).
    #[inline]
    fn open_share(&self, a: &FringeAttrs) -> [f32; 3] {
        if a[10] > 1.5 {
            return self.aperture_share(a);
        }
        let full = a[9];
        // Where a value does not move with τ, the feather's own smoothstep; where it does, a
        // linear ramp over τ as wide as the smoothstep's spread: the same mean and variance
        // (a uniform spread of width w has variance w²/12, the smoothstep's slope 6x(1 − x)
        // one of 1/20 over its width).
        let still = |x: f32| smoothstep(1.0 + 0.5 * full, 1.0 - 0.5 * full, x);
        let f = full * RAMP_WIDTH;
        let (inner, outer) = (1.0 - 0.5 * f, 1.0 + 0.5 * f);
        let mut factor = 1.0_f32;
        // Lower (open above) and upper (open below) ends of the open interval: the clip's and
        // the stop's, up to two each.
        let mut lower = [None::<Ramp>; 2];
        let mut upper = [None::<Ramp>; 2];
        // The clip radius r(τ) = r0 + τ r1, open below 1 (wholly, at every τ in [0, 1], when
        // within the feather at both ends).
        let (r0, r1) = (a[3], a[4]);
        let wholly = 1.0 - 0.5 * full;
        let clip_open = clip_open_along_tau(a);
        if !clip_open && r1.abs() < 1e-9 {
            factor *= still(r0);
        } else if !clip_open {
            let ramp = Ramp {
                closed: (outer - r0) / r1,
                open: (inner - r0) / r1,
            };
            if r1 > 0.0 {
                upper[0] = Some(ramp);
            } else {
                lower[0] = Some(ramp);
            }
        }
        // The circular stop: |(u0, v0) + τ (u1, v1)| open below 1 (wholly, the disc being
        // convex, when both ends are within the feather).
        let (u0, u1, v0, v1) = (a[5], a[6], a[7], a[8]);
        let inside = |u: f32, v: f32| u * u + v * v < wholly * wholly;
        if a[10] > 0.5 && !(inside(u0, v0) && inside(u0 + u1, v0 + v1)) {
            let dd = u1 * u1 + v1 * v1;
            if dd < 1e-14 {
                factor *= still((u0 * u0 + v0 * v0).sqrt());
            } else {
                let tc = -(u0 * u1 + v0 * v1) / dd;
                let (pu, pv) = (u0 + tc * u1, v0 + tc * v1);
                let q2 = pu * pu + pv * pv;
                if q2 >= outer * outer {
                    return [0.0; 3];
                }
                let reach = |q: f32| ((q * q - q2).max(0.0) / dd).sqrt();
                let (h_out, h_in) = (reach(outer), reach(inner));
                if q2 > inner * inner {
                    // Never wholly open: the line grazes the stop, its radius far from
                    // linear in τ over the feather.
                    return self.stepped_share(a, CORNER_STEPS);
                }
                lower[1] = Some(Ramp {
                    closed: tc - h_out,
                    open: tc - h_in,
                });
                upper[1] = Some(Ramp {
                    closed: tc + h_out,
                    open: tc + h_in,
                });
            }
        }
        if factor == 0.0 {
            return [0.0; 3];
        }
        // Ends wholly outside τ ∈ [0, 1] either close everything or nothing; those that reach
        // into it are the active ones.
        let mut active = [(
            Ramp {
                closed: 0.0,
                open: 0.0,
            },
            false,
            false,
        ); 4];
        let mut count = 0;
        // (ramp, an upper end, the clip's rather than the stop's)
        let ramps = |ends: [Option<Ramp>; 2], is_upper: bool| {
            ends.into_iter()
                .zip([true, false])
                .filter_map(move |(r, clip)| r.map(|r| (r, is_upper, clip)))
        };
        // Over the feather's whole smoothstep, of which the ramp is the narrower stand-in.
        let span = |r: &Ramp| {
            let (mid, half) = (
                0.5 * (r.open + r.closed),
                0.5 * (r.open - r.closed).abs() / RAMP_WIDTH,
            );
            (mid - half, mid + half)
        };
        for (r, is_upper, clip) in ramps(upper, true).chain(ramps(lower, false)) {
            // An end whose smoothstep reaches into the range is active.
            let (a0, a1) = span(&r);
            if a1 <= 0.0 || a0 >= 1.0 {
                // Wholly before or after the range: open or closed throughout.
                let open_throughout = (r.open <= r.closed) == (a0 >= 1.0);
                if !open_throughout {
                    return [0.0; 3];
                }
                continue;
            }
            active[count] = (r, is_upper, clip);
            count += 1;
        }
        let table = &self.tables[a[11] as usize];
        let ends = &active[..count];

        // A ramp over much of the range (where the colour's spread is uneven under it, the
        // ramp's shape matters, not only its mean and variance), or ends whose smoothsteps
        // overlap (a corner of the clip and the stop).
        let wide = ends
            .iter()
            .any(|(r, _, _)| (r.open - r.closed).abs() > WIDE_RAMP);
        let overlap = ends.iter().enumerate().any(|(i, (p, _, _))| {
            ends[i + 1..].iter().any(|(q, _, _)| {
                let (a, b) = (span(p), span(q));
                a.0 < b.1 && b.0 < a.1
            })
        });
        if overlap {
            // Steps over where the ends' smoothsteps are, not the whole range.
            let (lo, hi) = ends.iter().fold((1.0_f32, 0.0_f32), |(lo, hi), (r, _, _)| {
                let (a0, a1) = span(r);
                (lo.min(a0), hi.max(a1))
            });
            return self.stepped_between(a, CORNER_STEPS, lo.max(0.0), hi.min(1.0));
        }
        if wide {
            // One wide end whose value is linear in τ (the clip's; the stop's radius where
            // it is nearly so along τ's segment): its smoothstep integrated exactly against
            // the colour. Otherwise step by step.
            let linear = match ends {
                [(_, _, true)] => Some((r0, r1)),
                [(_, _, false)] => {
                    let d = |t: f32| ((u0 + t * u1).powi(2) + (v0 + t * v1).powi(2)).sqrt();
                    let (d0, d1) = (d(0.0), d(1.0));
                    // The radius is convex in τ, so its sag below the chord is concave and
                    // zero at both ends: at most twice the sag at the middle.
                    (d0 + d1 - 2.0 * d(0.5) <= MAX_SAG * full).then_some((d0, d1 - d0))
                }
                _ => None,
            };
            return match linear {
                Some((x0, x1)) => {
                    let (f, x0, x1) = (f64::from(full), f64::from(x0), f64::from(x1));
                    // smoothstep(1 + f/2, 1 − f/2, x0 + τ x1) = S((1 + f/2 − x0)/f − τ x1/f)
                    let s = table.smooth_share((1.0 + 0.5 * f - x0) / f, -x1 / f);
                    s.map(|v| factor * v)
                }
                None => self.stepped_share(a, CORNER_STEPS),
            };
        }
        // Apart, each end cuts on its own: the share below the lowest upper end (the mean of
        // F over its ramp) minus that below the highest lower end; nothing where a lower end
        // lies above an upper one.
        let mut below_hi = [1.0_f32; 3];
        let mut below_lo = [0.0_f32; 3];
        let (mut top, mut bottom) = (f32::INFINITY, f32::NEG_INFINITY);
        for (r, is_upper, _) in ends {
            if *is_upper {
                if r.open < top {
                    top = r.open;
                    below_hi = table.mean_share(r.open, r.closed);
                }
            } else if r.open > bottom {
                bottom = r.open;
                below_lo = table.mean_share(r.closed, r.open);
            }
        }
        if bottom > top {
            return [0.0; 3];
        }
        std::array::from_fn(|c| factor * (below_hi[c] - below_lo[c]))
    }
}

impl Shader<12> for FringeShader<'_> {
    type Rows = FringeRows;

    #[inline]
    fn shade(&self, a: &FringeAttrs) -> [f32; 3] {
        let s = self.open_share(a);
        [a[0] * s[0], a[1] * s[1], a[2] * s[2]]
    }

    fn rows(&self, step: &FringeAttrs, corners: &[FringeAttrs; 3]) -> FringeRows {
        // The feather and the flag are the same at every corner (and so at every pixel).
        let a = &corners[0];
        let f = f64::from(a[9]);
        let (d0, d1) = (f64::from(step[3]), f64::from(step[3] + step[4]));
        let half = |c: &FringeAttrs| {
            let (u1, v1) = (f64::from(c[6]), f64::from(c[8]));
            0.5 * (u1 * u1 + v1 * v1).sqrt()
        };
        let (dmu, dmv) = (
            f64::from(step[5]) + 0.5 * f64::from(step[6]),
            f64::from(step[7]) + 0.5 * f64::from(step[8]),
        );
        FringeRows {
            bounds: [1.0 + 0.5 * f + SPLIT_MARGIN, 1.0 - 0.5 * f - SPLIT_MARGIN],
            inv_radius_step: [1.0 / d0, 1.0 / d1],
            stop: a[10] > 0.5 && a[10] <= 1.5,
            aperture: a[10] > 1.5,
            reach: corners.iter().map(half).fold(0.0, f64::max),
            middle_step: [dmu, dmv],
            stop_steps: [
                StepNorm::new(dmu, dmv),
                StepNorm::new(f64::from(step[5]), f64::from(step[7])),
                StepNorm::new(f64::from(step[5] + step[6]), f64::from(step[7] + step[8])),
            ],
        }
    }

    /// The clip radius over `τ ∈ [0, 1]` lies between `r0` and `r0 + r1`, both affine along the
    /// row: the pixels where both are beyond the outer feather are dark — and, where the stop
    /// is flagged, those where the stop crossing's whole segment over τ is beyond the stop's
    /// outer feather — and those where both are within the inner one (and, where the stop is
    /// flagged, both ends of the segment inside the stop's inner feather) wholly open.
    fn split_row(
        &self,
        rows: &FringeRows,
        a: &FringeAttrs,
        step: &FringeAttrs,
        n: usize,
    ) -> RowSplit {
        let bounds = rows.bounds;
        let (r0, d0) = (f64::from(a[3]), f64::from(step[3]));
        let (r1, d1) = (f64::from(a[3] + a[4]), f64::from(step[3] + step[4]));
        let (lit0, core0) = linear_split_with(r0, d0, rows.inv_radius_step[0], bounds, n);
        let (lit1, core1) = linear_split_with(r1, d1, rows.inv_radius_step[1], bounds, n);
        // Lit where either end is inside (the hull of the two), open where both are.
        let lit = match (lit0.is_empty(), lit1.is_empty()) {
            (true, true) => 0..0,
            (true, false) => lit1,
            (false, true) => lit0,
            (false, false) => lit0.start.min(lit1.start)..lit0.end.max(lit1.end),
        };
        let mut lit = lit;
        if rows.stop && !lit.is_empty() {
            // Dark where τ's whole segment of the stop crossing is beyond the stop's outer
            // feather: its middle farther than that plus its half-length (at most the
            // largest of the triangle's corners', the length being convex over it).
            let (mu, mv) = (
                f64::from(a[5]) + 0.5 * f64::from(a[6]),
                f64::from(a[7]) + 0.5 * f64::from(a[8]),
            );
            let [dmu, dmv] = rows.middle_step;
            let outer = bounds[0] + rows.reach;
            let within =
                parabola_below_with(mu, mv, dmu, dmv, rows.stop_steps[0], n)(outer * outer);
            lit = intersect(lit, within);
        }
        let mut core = core0.start.max(core1.start)..core0.end.min(core1.end);
        if rows.aperture {
            (lit, core) = self.aperture_split(rows, a, lit, core);
        }
        if rows.stop && !core.is_empty() {
            // The stop, where both ends of τ's segment are inside it (the disc is convex):
            // each end's `u² + v²` is a parabola along the row.
            for ((u, v, du, dv), norm) in [
                (a[5], a[7], step[5], step[7]),
                (
                    a[5] + a[6],
                    a[7] + a[8],
                    step[5] + step[6],
                    step[7] + step[8],
                ),
            ]
            .into_iter()
            .zip(&rows.stop_steps[1..])
            {
                let inside = if bounds[1] > 0.0 {
                    let below = parabola_below_with(
                        f64::from(u),
                        f64::from(v),
                        f64::from(du),
                        f64::from(dv),
                        *norm,
                        n,
                    );
                    below(bounds[1] * bounds[1])
                } else {
                    0..0
                };
                core = intersect(core, inside);
            }
        }
        RowSplit { lit, core }
    }

    #[inline]
    fn shade_core(&self, a: &FringeAttrs) -> [f32; 3] {
        [a[0], a[1], a[2]]
    }
}

/// True when the clip radius `r0 + τ r1` (attributes 3 and 4) is within `1 − feather/2` at
/// both ends of `τ ∈ [0, 1]`, so wholly open at every `τ` (it is linear in `τ`).
#[inline]
fn clip_open_along_tau(a: &FringeAttrs) -> bool {
    let wholly = 1.0 - 0.5 * a[9];
    a[3] < wholly && a[3] + a[4] < wholly
}

/// A triangle's attributes `a` flagged [`APERTURE_FLAG`] with the aperture's outline put in
/// the clip's place, where that is exact: where the clip is open all along `τ` (its radius
/// within `1 − feather/2` at both ends) and the aperture's soft transmission is the
/// feather's smoothstep of its signed distance `d`
/// ([`ApertureSampler::soft_is_distance_ramp`]), linear along the pixel's segment of stop
/// crossings (`d` at its middle within [`MAX_SAG`] of a feather of the chord's), the
/// transmission over `τ` is the clip's smoothstep of the radius `1 + d(τ)`. `None` elsewhere.
fn aperture_as_clip(aperture: &ApertureSampler<'_>, a: &FringeAttrs) -> Option<FringeAttrs> {
    let f = a[9];
    if !(clip_open_along_tau(a) && aperture.soft_is_distance_ramp(f)) {
        return None;
    }
    let d = |t: f32| aperture.signed_distance(a[5] + t * a[6], a[7] + t * a[8]);
    let (d0, d_mid, d1) = (d(0.0), d(0.5), d(1.0));
    let sag = (d0 + d1 - 2.0 * d_mid).abs();
    // (A NaN distance is not linear either.)
    if sag.is_nan() || sag > 2.0 * MAX_SAG * f {
        return None;
    }
    let mut clip = *a;
    clip[3] = 1.0 + d0;
    clip[4] = d1 - d0;
    clip[10] = 0.0;
    Some(clip)
}

impl FringeShader<'_> {
    /// [`aperture_split`] of a row of a triangle flagged [`APERTURE_FLAG`]: traced along the
    /// row from the segments' middles, which step by `middle_step` a pixel; where the
    /// transmission is 0 (or 1) within `reach` of a middle, it is along the segments of the
    /// pixels whose middle lies within `reach` less the longest half segment
    /// ([`FringeRows::reach`]) of it.
    fn aperture_split(
        &self,
        rows: &FringeRows,
        a: &FringeAttrs,
        lit: std::ops::Range<usize>,
        core: std::ops::Range<usize>,
    ) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let middle = [
            f64::from(a[5]) + 0.5 * f64::from(a[6]),
            f64::from(a[7]) + 0.5 * f64::from(a[8]),
        ];
        aperture_split(
            &self.aperture,
            middle,
            rows.middle_step,
            a[9],
            rows.reach + APERTURE_SPLIT_MARGIN,
            lit,
            core,
        )
    }
}

/// Traces `ghost` at every band of `bands` (at least two, over the bins whose edges in
/// wavelength are `edges_nm`, one more than the bands) and appends one triangle per grid
/// triangle where the bands' images follow the fringe model, and one per band elsewhere
/// (`BandTriangles::push` in [`super::triangles`]) — for the whole ghost when that is more than
/// [`MAX_FAILED_SHARE`] of its triangles. Any aperture: the circle's outline is shaded
/// analytically (stop flag 1), an iris's or a mask's by its transmission stepped over `τ`
/// ([`APERTURE_FLAG`]). Fewer than two bands, or a colour whose channels cannot be split, is
/// meshed band by band.
pub fn mesh_ghost_fringed(
    ctx: &GhostContext<'_>,
    ghost: &GhostGrid<'_>,
    bands: &[BandRef<'_>],
    edges_nm: &[f64],
    grids: &mut Vec<GridTrace>,
    mesh: &mut GhostMesh,
) -> GhostStats {
    let GhostGrid {
        path,
        bounds,
        n,
        ref light,
    } = *ghost;
    let m = bands.len();
    let mut stats = GhostStats::default();
    if grids.len() < m {
        grids.resize_with(m, GridTrace::default);
    }
    for (band, grid) in bands.iter().zip(grids.iter_mut()) {
        if !trace_band(ctx, path, bounds, n, light, band, grid) {
            return stats;
        }
        stats.rays += n * n;
    }
    let sampler = ctx.aperture.sampler();
    let emits: Vec<BandTriangles<'_>> = bands
        .iter()
        .zip(grids.iter())
        .map(|(band, grid)| BandTriangles::new(ctx, n, light, band, &sampler, grid))
        .collect();
    let per_band = |tri: [usize; 3], mesh: &mut GhostMesh, stats: &mut GhostStats| {
        for emit in &emits {
            emit.push(tri, mesh, stats);
        }
    };
    let table = (edges_nm.len() == m + 1 && m >= 2)
        .then(|| ghost_table(bands, edges_nm, &emits, n))
        .flatten();
    let Some((table, centres)) = table else {
        for tri in grid_triangles(n) {
            per_band(tri, mesh, &mut stats);
        }
        return stats;
    };
    let id = mesh.fringe_tables.len() as f32;
    mesh.fringe_tables.push(table);
    let circle = matches!(ctx.aperture, Aperture::Circular);
    let mut fringer = Fringer::new(&emits, &centres, n, id, (circle, &sampler));
    let (o0, e0, f0) = (mesh.open.len(), mesh.edge.len(), mesh.fringe.len());
    let mut failed = 0_usize;
    for tri in grid_triangles(n) {
        match fringer.triangle(tri, mesh, &mut stats) {
            Fringed::Drawn | Fringed::Clipped => {}
            Fringed::Failed => {
                failed += 1;
                per_band(tri, mesh, &mut stats);
            }
        }
    }
    // Too many triangles off the model: the whole ghost band by band (where fringed and
    // band-by-band triangles meet, their seams differ per band).
    if failed as f64 > MAX_FAILED_SHARE * (2 * (n - 1) * (n - 1)) as f64 {
        mesh.open.truncate_to(o0);
        mesh.edge.truncate_to(e0);
        mesh.fringe.truncate_to(f0);
        mesh.fringe_tables.pop();
        stats = GhostStats {
            rays: stats.rays,
            ..GhostStats::default()
        };
        for tri in grid_triangles(n) {
            per_band(tri, mesh, &mut stats);
        }
    }
    stats
}

/// The ghost's [`FringeTable`] and its bands' centres in `τ`, or `None` when its colour
/// cannot be split into shares.
///
/// The dispersion coordinate τ (1/λ², in which the geometry is nearly linear) of the bands.
/// Each bin's colour is spread evenly over a span of τ as wide as its own but centred on its
/// band, so that its fringe sits where its band was traced (1/λ² is convex: a bin's centre
/// wavelength is not its span's middle); τ is then scaled so the spans cover [0, 1].
fn ghost_table(
    bands: &[BandRef<'_>],
    edges_nm: &[f64],
    emits: &[BandTriangles<'_>],
    n: usize,
) -> Option<(FringeTable, Vec<f64>)> {
    let inv = |l: f64| 1.0 / (l * l);
    let raw: Vec<[f64; 2]> = bands
        .iter()
        .enumerate()
        .map(|(b, band)| {
            let half = 0.5 * (inv(edges_nm[b]) - inv(edges_nm[b + 1])).abs();
            let c = inv(band.lambda_nm);
            [c - half, c + half]
        })
        .collect();
    let lo = raw.iter().fold(f64::INFINITY, |a, s| a.min(s[0]));
    let hi = raw.iter().fold(f64::NEG_INFINITY, |a, s| a.max(s[1]));
    let tau = |t: f64| (t - lo) / (hi - lo);
    let spans: Vec<[f64; 2]> = raw.iter().map(|s| s.map(tau)).collect();
    let colours: Vec<[f64; 3]> = emits
        .iter()
        .map(|e| {
            let passed: f64 = (0..n * n)
                .filter(|&k| e.grid.passes(k))
                .map(|k| f64::from(e.grid.weight[k]))
                .sum();
            e.rgb.map(|c| f64::from(c) * passed)
        })
        .collect();
    let centres: Vec<f64> = bands.iter().map(|b| tau(inv(b.lambda_nm))).collect();
    FringeTable::new(&spans, &colours).map(|t| (t, centres))
}

/// What [`Fringer::triangle`] did with a grid triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fringed {
    /// Drawn once for every band (open or fringed).
    Drawn,
    /// Wholly clipped in every band: nothing to draw.
    Clipped,
    /// Off the model: to be drawn band by band.
    Failed,
}

/// One fringed ghost's triangles: its bands' traced grids, read per vertex once, and the
/// buffers a triangle's test reuses (made once per ghost).
struct Fringer<'e, 'a> {
    emits: &'e [BandTriangles<'a>],
    /// The aperture is the circle (its outline flagged 1, else [`APERTURE_FLAG`]).
    circle: bool,
    /// A convex aperture's open part is decided at the stop crossings' ends (the circle's,
    /// the iris's), a mask's around them ([`ApertureSampler::uniform_around`]).
    convex: bool,
    sampler: &'e ApertureSampler<'e>,
    model: LineFit<'e>,
    /// Index of the ghost's table in [`GhostMesh::fringe_tables`].
    id: f32,
    /// The widest feather of the ghost's triangles ([`super::triangles::max_feather`]).
    max_feather: f32,
    /// The largest of the bands' smallest triangle areas (the Airy disc, mm²).
    min_area: f64,
    /// Grid vertices per band.
    vertices: usize,
    /// Each band's vertices as the triangles read them (every vertex is shared by up to six
    /// triangles): sensor position (mm, the lens's frame) and `[r, u, v]`.
    sensor: Vec<[f64; 2]>,
    radius_uv: Vec<[f64; 3]>,
    /// Per band: its triangle's area.
    areas: Vec<f64>,
    /// Per band `b` and corner `c` of the mean triangle: the clip radius and stop crossing
    /// `[r, u, v]` at `values[b][3 c..3 c + 3]`.
    values: Vec<[f64; 9]>,
}

impl<'e, 'a> Fringer<'e, 'a> {
    fn new(
        emits: &'e [BandTriangles<'a>],
        centres: &'e [f64],
        n: usize,
        id: f32,
        (circle, sampler): (bool, &'e ApertureSampler<'e>),
    ) -> Self {
        let m = emits.len();
        let vertices = n * n;
        let mut sensor = Vec::with_capacity(m * vertices);
        let mut radius_uv = Vec::with_capacity(m * vertices);
        for e in emits {
            for k in 0..vertices {
                sensor.push(e.sensor(k));
                let uv = e.stop_uv(k);
                radius_uv.push([
                    f64::from(e.grid.max_rel[k]),
                    f64::from(uv[0]),
                    f64::from(uv[1]),
                ]);
            }
        }
        Fringer {
            emits,
            circle,
            convex: sampler.is_convex(),
            sampler,
            model: LineFit::new(centres),
            id,
            max_feather: emits[0].max_feather,
            min_area: emits.iter().fold(0.0_f64, |a, e| a.max(e.min_area)),
            vertices,
            sensor,
            radius_uv,
            areas: vec![0.0_f64; m],
            values: vec![[0.0_f64; 9]; m],
        }
    }

    /// Band `b`'s triangle `tri` on the sensor (mm, the lens's frame).
    #[inline]
    fn corners(&self, b: usize, tri: [usize; 3]) -> [[f64; 2]; 3] {
        tri.map(|k| self.sensor[b * self.vertices + k])
    }

    /// Draws grid triangle `tri` once for every band into `mesh` (counting it in `stats`)
    /// where the bands follow the fringe model; [`Fringed::Failed`] where they do not.
    fn triangle(
        &mut self,
        tri: [usize; 3],
        mesh: &mut GhostMesh,
        stats: &mut GhostStats,
    ) -> Fringed {
        let emits = self.emits;
        let all_done = emits
            .iter()
            .all(|e| tri.iter().all(|&k| e.grid.completed[k]));
        if !all_done {
            return Fringed::Failed;
        }
        if emits.iter().all(|e| {
            tri.iter()
                .all(|&k| e.grid.max_rel[k] > 1.0 + self.max_feather)
        }) {
            return Fringed::Clipped;
        }
        let Some(mean) = self.mean_triangle(tri) else {
            // Beyond every band's clip by its own triangle's feather, as band by band.
            return if self.clipped_per_band(tri) {
                Fringed::Clipped
            } else {
                Fringed::Failed
            };
        };
        self.extend_to(tri, &mean);
        let (fits, residuals) = self.model.fit_all(&self.values);
        let mut lines = [[[0.0_f64; 2]; 3]; 3];
        let mut residual = [0.0_f64; 3];
        for (c, line) in lines.iter_mut().enumerate() {
            for (x, l) in line.iter_mut().enumerate() {
                *l = fits[3 * c + x];
                residual[x] = residual[x].max(residuals[3 * c + x]);
            }
        }
        let end = |line: [f64; 2], t: f64| line[0] + t * line[1];
        // The feathers from the mean triangle's values at the middle of τ.
        let feathers = emits[0].feathers(
            mean,
            lines.map(|l| end(l[0], 0.5)),
            lines.map(|l| [end(l[1], 0.5), end(l[2], 0.5)]),
        );
        if emits
            .iter()
            .all(|e| tri.iter().all(|&k| e.grid.max_rel[k] > 1.0 + feathers.clip))
        {
            return Fringed::Clipped;
        }
        let wide = feathers.widest();
        // Open when, at both ends of τ, every corner is within the clip and the (convex)
        // stop by half the wider feather: the radius is linear and the disc convex, so it is
        // between.
        let inner = 1.0 - 0.5 * f64::from(wide);
        let radius_open = lines
            .iter()
            .all(|l| end(l[0], 0.0) <= inner && end(l[0], 1.0) <= inner);
        let inside_at_ends = || {
            lines.iter().all(|l| {
                [0.0, 1.0].iter().all(|&t| {
                    let uv = [end(l[1], t) as f32, end(l[2], t) as f32];
                    emits[0].inside_aperture(uv, wide)
                })
            })
        };
        let (stop_open, stop_closed) = if self.circle {
            (inside_at_ends(), false)
        } else {
            // Every pixel's stop crossings over τ lie in the hull of the corners' ends (they
            // are affine in the pixel's position and in τ), taken here as the disc about
            // their centroid through the farthest: where the aperture is closed all over it,
            // nothing to draw; open all over it, no outline (a convex aperture is open over
            // the hull already where it is at its ends).
            let ends: [[f64; 2]; 6] = std::array::from_fn(|k| {
                let (l, t) = (&lines[k / 2], (k % 2) as f64);
                [end(l[1], t), end(l[2], t)]
            });
            let c = ends
                .iter()
                .fold([0.0; 2], |c, p| [c[0] + p[0] / 6.0, c[1] + p[1] / 6.0]);
            let radius = ends
                .iter()
                .map(|p| len(p[0] - c[0], p[1] - c[1]))
                .fold(0.0_f64, f64::max);
            let uniform =
                self.sampler
                    .uniform_around(c[0] as f32, c[1] as f32, radius as f32, wide);
            let open = if self.convex {
                inside_at_ends()
            } else {
                uniform == Some(1.0)
            };
            (open, uniform == Some(0.0))
        };
        // Where an edge crosses the triangle, the bands' values there must follow their lines
        // (the stop's only where its outline is drawn); inside, the mean triangle is all.
        // (within a quarter of the feather drawn: a quarter pixel on the image).
        let open = radius_open && stop_open;
        let feather = feathers.drawn(radius_open, stop_open);
        let tolerance = 0.25 * f64::from(feather);
        let follows = residual[0] <= tolerance
            && (stop_open || (residual[1] <= tolerance && residual[2] <= tolerance));
        if !open && !follows {
            return Fringed::Failed;
        }
        let (flux, colours) = self.colours(tri);
        stats.flux += flux;
        if stop_closed {
            // Behind the aperture at every pixel and band: its light counted (as band by
            // band), nothing drawn.
            return Fringed::Drawn;
        }
        stats.triangles += 1;
        let pixels = mean.map(|q| emits[0].to_pixel(q));
        if open {
            mesh.open.push(pixels, colours);
        } else {
            let flag = if stop_open {
                0.0
            } else if self.circle {
                1.0
            } else {
                APERTURE_FLAG
            };
            let id = self.id;
            let corner = |c: usize| -> FringeAttrs {
                let [r, u, v] = lines[c];
                let [red, green, blue] = colours[c];
                [
                    red,
                    green,
                    blue,
                    r[0] as f32,
                    r[1] as f32,
                    u[0] as f32,
                    u[1] as f32,
                    v[0] as f32,
                    v[1] as f32,
                    feather,
                    flag,
                    id,
                ]
            };
            mesh.fringe.push(pixels, [corner(0), corner(1), corner(2)]);
        }
        Fringed::Drawn
    }

    /// True when every band's triangle `tri` is beyond its clip radius by its own feather
    /// (where [`BandTriangles`] leaves it out).
    fn clipped_per_band(&self, tri: [usize; 3]) -> bool {
        self.emits.iter().enumerate().all(|(b, e)| {
            let at = tri.map(|k| self.radius_uv[b * self.vertices + k]);
            let r = at.map(|x| x[0]);
            let clip = e
                .feathers(self.corners(b, tri), r, at.map(|x| [x[1], x[2]]))
                .clip;
            r.iter().all(|&x| x > 1.0 + f64::from(clip))
        })
    }

    /// The mean of the bands' triangles `tri`, each band's area kept in `areas`; `None` when
    /// the bands' triangles differ in orientation or by more than [`MAX_AREA_RATIO`] in area,
    /// or the mean is smaller than the diffraction limit.
    #[inline]
    fn mean_triangle(&mut self, tri: [usize; 3]) -> Option<[[f64; 2]; 3]> {
        let m = self.emits.len();
        let mut mean = [[0.0_f64; 2]; 3];
        let (mut smallest, mut largest) = (f64::INFINITY, 0.0_f64);
        let mut sign = 0.0_f64;
        let mut consistent = true;
        for b in 0..m {
            let p = self.corners(b, tri);
            let a2 = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            self.areas[b] = 0.5 * a2.abs();
            if sign == 0.0 {
                sign = a2.signum();
            }
            consistent &= a2 * sign > 0.0;
            smallest = smallest.min(a2.abs());
            largest = largest.max(a2.abs());
            for (acc, q) in mean.iter_mut().zip(p) {
                acc[0] += q[0] / m as f64;
                acc[1] += q[1] / m as f64;
            }
        }
        let mean_a2 = cross(sub(mean[1], mean[0]), sub(mean[2], mean[0]));
        let fails = !consistent
            || mean_a2.is_nan()
            || mean_a2 * sign <= 0.0
            || largest > MAX_AREA_RATIO * smallest
            || 0.5 * mean_a2.abs() < self.min_area;
        (!fails).then_some(mean)
    }

    /// Each band's clip radius and stop crossing over its triangle `tri`, extended affinely
    /// to the corners of `mean`, into `values`.
    #[inline]
    fn extend_to(&mut self, tri: [usize; 3], mean: &[[f64; 2]; 3]) {
        for b in 0..self.emits.len() {
            let p = self.corners(b, tri);
            let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
            let inv = 1.0 / cross(e1, e2);
            let at = tri.map(|k| self.radius_uv[b * self.vertices + k]);
            let vals = &mut self.values[b];
            for (c, q) in mean.iter().enumerate() {
                let d = sub(*q, p[0]);
                let (w1, w2) = (cross(d, e2) * inv, cross(e1, d) * inv);
                for x in 0..3 {
                    vals[3 * c + x] =
                        at[0][x] + w1 * (at[1][x] - at[0][x]) + w2 * (at[2][x] - at[0][x]);
                }
            }
        }
    }

    /// The flux of triangle `tri` summed over the bands, and its corners' summed RGB
    /// irradiance. Each band's irradiance as in its own triangle: what band `b` adds at a
    /// point of the sensor is its flux over its own area there, wherever the mean triangle
    /// puts it (over the mean area, a band whose image is larger than the mean would gain
    /// light).
    #[inline]
    fn colours(&self, tri: [usize; 3]) -> (f64, [[f32; 3]; 3]) {
        let mut flux = 0.0;
        let mut colours = [[0.0_f32; 3]; 3];
        for (e, &area) in self.emits.iter().zip(&self.areas) {
            flux += e.flux(tri);
            let irr = e.irradiance_over(area) as f32;
            for (colour, &k) in colours.iter_mut().zip(&tri) {
                let w = irr * e.grid.weight[k];
                for (v, c) in colour.iter_mut().zip(e.rgb) {
                    *v += c * w;
                }
            }
        }
        (flux, colours)
    }
}

/// Least-squares lines over fixed abscissae.
struct LineFit<'a> {
    x: &'a [f64],
    mean: f64,
    sxx: f64,
}

impl<'a> LineFit<'a> {
    fn new(x: &'a [f64]) -> Self {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let sxx = x.iter().map(|v| (v - mean) * (v - mean)).sum();
        LineFit { x, mean, sxx }
    }

    /// For each of `K` series (`ys[b][i]` is series `i`'s value at abscissa `b`): the
    /// `[intercept, slope]` of its least-squares line and the largest distance of a value
    /// from it. One pass over the abscissae per sum, every series at once.
    fn fit_all<const K: usize>(&self, ys: &[[f64; K]]) -> ([[f64; 2]; K], [f64; K]) {
        let count = self.x.len() as f64;
        // Sums start at −0, as `Iterator::sum` does.
        let mut ym = [-0.0_f64; K];
        for y in ys {
            for (s, v) in ym.iter_mut().zip(y) {
                *s += v;
            }
        }
        for s in &mut ym {
            *s /= count;
        }
        let mut sxy = [-0.0_f64; K];
        for (x, y) in self.x.iter().zip(ys) {
            let dx = x - self.mean;
            for i in 0..K {
                sxy[i] += dx * (y[i] - ym[i]);
            }
        }
        let mut lines = [[0.0_f64; 2]; K];
        for (i, line) in lines.iter_mut().enumerate() {
            let slope = if self.sxx > 0.0 {
                sxy[i] / self.sxx
            } else {
                0.0
            };
            *line = [ym[i] - slope * self.mean, slope];
        }
        let mut residual = [0.0_f64; K];
        for (x, y) in self.x.iter().zip(ys) {
            for i in 0..K {
                let [intercept, slope] = lines[i];
                residual[i] = residual[i].max((y[i] - intercept - slope * x).abs());
            }
        }
        (lines, residual)
    }
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aperture::tests::mask_of;
    use proptest::prelude::*;

    use crate::ghost::fringe_table::NODES;
    use crate::ghost::mesh::SAMPLED_MIN_AREA;
    use crate::image::HdrImage;
    use crate::raster::{Coverage, rasterize_shaded_into};

    /// The iris the tests shade [`APERTURE_FLAG`] triangles with.
    static IRIS: Aperture = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.3,
        roundness: 0.2,
    };

    /// Five bins of unequal spans and colours (one channel negative in a bin, as a narrow
    /// band's linear sRGB can be).
    fn table() -> FringeTable {
        let spans = [[0.0, 0.3], [0.25, 0.5], [0.5, 0.65], [0.6, 0.8], [0.8, 1.0]];
        let colours = [
            [0.1, 0.2, 1.0],
            [-0.05, 0.5, 0.6],
            [0.3, 1.0, 0.1],
            [0.8, 0.6, 0.0],
            [1.0, 0.1, 0.02],
        ];
        FringeTable::new(&spans, &colours).unwrap()
    }

    #[test]
    fn a_table_runs_from_nothing_to_the_whole_colour() {
        let t = table();
        assert_eq!(t.share(-0.5), [0.0; 3]);
        assert_eq!(t.share(0.0), [0.0; 3]);
        assert_eq!(t.share(1.0), [1.0; 3]);
        assert_eq!(t.share(2.0), [1.0; 3]);
        for c in 0..3 {
            assert!((t.nodes[NODES][c] - 1.0).abs() < 1e-6);
        }
        // The mean over an interval is the integral's difference over its width.
        for (a, b) in [(0.1_f32, 0.4_f32), (-0.3, 0.2), (0.7, 1.6), (0.33, 0.3301)] {
            let m = t.mean_share(a, b);
            let steps = 20_000;
            for (c, mc) in m.iter().enumerate() {
                let sum: f32 = (0..steps)
                    .map(|i| t.share(a + (b - a) * (i as f32 + 0.5) / steps as f32)[c])
                    .sum();
                let expected = sum / steps as f32;
                assert!((mc - expected).abs() < 2e-4, "[{a}, {b}] channel {c}");
            }
        }
        // A channel with (almost) no colour cannot be split.
        assert!(FringeTable::new(&[[0.0, 0.5], [0.5, 1.0]], &[[1.0, 1.0, 0.0]; 2]).is_none());
        assert!(FringeTable::new(&[[0.5, 0.5]], &[[1.0; 3]]).is_none());
    }

    fn attrs(
        rgb: [f32; 3],
        r: [f32; 2],
        u: [f32; 2],
        v: [f32; 2],
        f: f32,
        flag: bool,
    ) -> FringeAttrs {
        let flag = if flag { 1.0 } else { 0.0 };
        [
            rgb[0], rgb[1], rgb[2], r[0], r[1], u[0], u[1], v[0], v[1], f, flag, 0.0,
        ]
    }

    /// Across a straight clip edge, the light the shader adds is what the bands add: the
    /// share integrated over the clip radius moves the edge by the colour's mean `τ` times
    /// the radius's change over `τ`, whatever the ramp's shape.
    #[test]
    fn a_fringed_edge_keeps_each_colour_s_light() {
        let tables = [table()];
        let shader = FringeShader {
            tables: &tables,
            aperture: crate::aperture::CIRCLE_SAMPLER,
        };
        let t = &tables[0];
        // The colour's mean τ per channel: ∫ τ dF = 1 − ∫₀¹ F.
        let integral = t.integral(1.0);
        for r1 in [0.05_f32, -0.03, 0.2, 1e-12] {
            let f = 0.01;
            let (lo, hi, steps) = (0.0_f32, 2.0_f32, 200_000);
            let dr = (hi - lo) / steps as f32;
            let mut sum = [0.0_f64; 3];
            for i in 0..steps {
                let r0 = lo + (i as f32 + 0.5) * dr;
                let s = shader.open_share(&attrs([1.0; 3], [r0, r1], [0.0; 2], [0.0; 2], f, false));
                for c in 0..3 {
                    sum[c] += f64::from(s[c]) * f64::from(dr);
                }
            }
            for c in 0..3 {
                // Band at τ is open for r0 < 1 − τ r1: on average 1 − r1 · mean τ.
                let mean_tau = f64::from(1.0 - integral[c]);
                let expected = 1.0 - f64::from(r1) * mean_tau;
                assert!(
                    (sum[c] - expected).abs() < 2e-4,
                    "r1 {r1} channel {c}: {} against {expected}",
                    sum[c]
                );
            }
        }
    }

    /// `∫₀¹ S(p + q τ) dF` summed over `steps` steps of `τ`: the oracle of the exact share.
    fn smooth_share_summed(t: &FringeTable, p: f64, q: f64, steps: usize) -> [f64; 3] {
        let mut acc = [0.0_f64; 3];
        let mut prev = t.share(0.0);
        for i in 0..steps {
            let next = t.share((i + 1) as f32 / steps as f32);
            let tau = (i as f64 + 0.5) / steps as f64;
            let x = (p + q * tau).clamp(0.0, 1.0);
            let w = x * x * (3.0 - 2.0 * x);
            for c in 0..3 {
                acc[c] += w * f64::from(next[c] - prev[c]);
            }
            prev = next;
        }
        acc
    }

    proptest! {
        /// A smoothstep of a linear function of τ integrates exactly against the colour:
        /// as the sum over 20 000 steps of τ, to 1e-4, wherever its ramp falls.
        #[test]
        fn a_smoothstep_integrates_exactly_against_the_colour(
            p in -4.0_f64..5.0, q in prop_oneof![-4.0_f64..-0.05, 0.05_f64..4.0],
        ) {
            let t = table();
            let exact = t.smooth_share(p, q);
            let summed = smooth_share_summed(&t, p, q, 20_000);
            for c in 0..3 {
                prop_assert!(
                    (f64::from(exact[c]) - summed[c]).abs() < 1e-4,
                    "channel {}: {:?} against {:?}", c, exact, summed
                );
            }
        }

        /// A wide end of the clip alone (its ramp over more than a quarter of τ's range) is
        /// integrated exactly: the shade's share is the 4096-step sum's within 1e-3.
        #[test]
        fn a_wide_clip_end_is_exact(
            r0 in 0.9_f32..1.1, r1 in 0.001_f32..0.02, sign in prop::bool::ANY,
            f in 0.02_f32..0.05,
        ) {
            let tables = [table()];
            let shader = FringeShader { tables: &tables, aperture: crate::aperture::CIRCLE_SAMPLER };
            let r1 = if sign { r1 } else { -r1 };
            let a = attrs([1.0; 3], [r0, r1], [0.0; 2], [0.0; 2], f, false);
            let (s, q) = (shader.open_share(&a), shader.stepped_share(&a, 4096));
            for c in 0..3 {
                prop_assert!((s[c] - q[c]).abs() < 1e-3, "channel {}: {:?} against {:?}", c, s, q);
            }
        }

        /// The analytic share against quadrature over τ with the feather's smoothstep and
        /// the stop's exact radius: the same within a few per cent of the whole colour (the
        /// ramps are linear and the clip's and the stop's ends are taken one at a time).
        #[test]
        fn the_share_follows_the_bands(
            r0 in 0.9_f32..1.1, r1 in -0.1_f32..0.1,
            u0 in -1.1_f32..1.1, u1 in -0.1_f32..0.1,
            v0 in -1.1_f32..1.1, v1 in -0.1_f32..0.1,
            f in 0.002_f32..0.05,
            flag in prop::bool::ANY,
        ) {
            let tables = [table()];
            let shader = FringeShader { tables: &tables, aperture: crate::aperture::CIRCLE_SAMPLER };
            let a = attrs([1.0; 3], [r0, r1], [u0, u1], [v0, v1], f, flag);
            let (s, q) = (shader.open_share(&a), shader.stepped_share(&a, 256));
            for c in 0..3 {
                prop_assert!((s[c] - q[c]).abs() < 0.03, "channel {}: {:?} against {:?}", c, s, q);
            }
        }

        /// An iris's outline ([`APERTURE_FLAG`]) stepped over τ against quadrature over 4096
        /// steps: within a step's share of the colour (the edge of a band falls on the
        /// nearest of [`CORNER_STEPS`] steps), exactly the clip's share where the iris is
        /// open along the whole segment, 0 where it is closed.
        #[test]
        fn an_iris_outline_follows_the_bands(
            r0 in 0.9_f32..1.1, r1 in -0.1_f32..0.1,
            u0 in -1.1_f32..1.1, u1 in -0.1_f32..0.1,
            v0 in -1.1_f32..1.1, v1 in -0.1_f32..0.1,
            f in 0.002_f32..0.05,
        ) {
            let tables = [table()];
            let shader = FringeShader { tables: &tables, aperture: IRIS.sampler() };
            let mut a = attrs([1.0; 3], [r0, r1], [u0, u1], [v0, v1], f, true);
            a[10] = APERTURE_FLAG;
            let (s, q) = (shader.open_share(&a), shader.stepped_share(&a, 4096));
            // The largest colour share of one step of τ, plus the clip's own approximation.
            let step_share = (0..CORNER_STEPS)
                .map(|i| {
                    let (lo, hi) = (i as f32 / CORNER_STEPS as f32, (i + 1) as f32 / CORNER_STEPS as f32);
                    let (p, n) = (tables[0].share(lo), tables[0].share(hi));
                    (0..3).map(|c| n[c] - p[c]).fold(0.0_f32, f32::max)
                })
                .fold(0.0_f32, f32::max);
            for c in 0..3 {
                prop_assert!(
                    (s[c] - q[c]).abs() < step_share + 0.03,
                    "channel {}: {:?} against {:?}", c, s, q
                );
            }
        }

        /// Pixels left out of a row's lit span shade to zero, and those in its core shade as
        /// the wholly open triangle.
        #[test]
        fn a_fringed_row_s_split_keeps_every_pixel_s_shade(
            rgb in prop::array::uniform3(0.1_f32..10.0),
            r0 in 0.8_f32..1.2, r1 in -0.1_f32..0.1, dr0 in -0.02_f32..0.02, dr1 in -0.01_f32..0.01,
            u0 in -1.1_f32..1.1, v0 in -1.1_f32..1.1,
            u1 in -0.1_f32..0.1, v1 in -0.1_f32..0.1,
            stop_step in prop::array::uniform4(-0.02_f32..0.02),
            f in 1e-4_f32..0.05,
            flag in prop::bool::ANY,
            iris in prop::bool::ANY,
            n in 1_usize..64,
        ) {
            let tables = [table()];
            let shader = FringeShader { tables: &tables, aperture: IRIS.sampler() };
            let mut a = attrs(rgb, [r0, r1], [u0, u1], [v0, v1], f, flag);
            if flag && iris {
                a[10] = APERTURE_FLAG;
            }
            let mut step = [0.0_f32; 12];
            step[0] = 0.01;
            step[3] = dr0;
            step[4] = dr1;
            step[5..9].copy_from_slice(&stop_step);
            // The row as a triangle of its own: its ends as the corners.
            let end: FringeAttrs =
                std::array::from_fn(|k| a[k] + (n - 1) as f32 * step[k]);
            let rows = shader.rows(&step, &[a, end, end]);
            let split = shader.split_row(&rows, &a, &step, n);
            prop_assert!(split.lit.end <= n && split.core.end <= n);
            let mut x = a;
            for k in 0..n {
                let full = shader.shade(&x);
                if !split.lit.contains(&k) {
                    prop_assert_eq!(full, [0.0; 3], "pixel {} outside {:?}", k, split.lit);
                } else if split.core.contains(&k) {
                    prop_assert_eq!(full, shader.shade_core(&x), "pixel {} in core", k);
                }
                for (v, d) in x.iter_mut().zip(&step) {
                    *v += d;
                }
            }
        }
    }

    /// Where the clip is open along τ, an iris's or a mask's outline crossing the pixel's
    /// segment is shaded as the clip's edge (three evaluations of the aperture), within a
    /// fraction of a per cent of quadrature over 4096 steps.
    #[test]
    fn an_outline_with_the_clip_open_is_shaded_as_the_clip_s_edge() {
        let tables = [table()];
        let mask = Aperture::Mask(mask_of(64, |u, v| u < 0.3 + 0.2 * v));
        for aperture in [IRIS.clone(), mask] {
            let shader = FringeShader {
                tables: &tables,
                aperture: aperture.sampler(),
            };
            let mut checked = 0;
            // Segments of stop crossings across the outline near (0.3, 0) (the mask's edge; the
            // iris's is farther out, at u ≈ 0.87: segments there too), feathers wider than the
            // mask's texel.
            for (u0, u1, f) in [
                (0.25, 0.1, 0.05),
                (0.28, 0.04, 0.04),
                (0.32, -0.06, 0.06),
                (0.84, 0.06, 0.05),
                (0.9, -0.05, 0.04),
            ] {
                let mut a = attrs([1.0; 3], [0.5, 0.02], [u0, u1], [0.01, 0.005], f, true);
                a[10] = APERTURE_FLAG;
                let (s, q) = (shader.open_share(&a), shader.stepped_share(&a, 4096));
                if aperture_as_clip(&shader.aperture, &a).is_some() {
                    checked += 1;
                    for c in 0..3 {
                        assert!((s[c] - q[c]).abs() < 0.005, "{c}: {s:?} against {q:?}");
                    }
                }
            }
            assert!(checked >= 2, "{aperture:?}: {checked}");
        }
    }

    /// A mask sampled bilinearly (a feather under its texel) across a segment of stop
    /// crossings short against a texel: its transmission is linear along it, integrated as
    /// such, within a fraction of a per cent of quadrature over 4096 steps.
    #[test]
    fn a_bilinear_mask_across_a_short_segment_is_integrated_as_linear() {
        let tables = [table()];
        // Columns 0 to 39 of 64 open.
        let mask = Aperture::Mask(mask_of(64, |u, _| u < 0.25));
        let shader = FringeShader {
            tables: &tables,
            aperture: mask.sampler(),
        };
        // The edge at u = 0.25 (column 40 of 64); a texel is 1/32 wide, the feather 0.01.
        let mut checked = 0;
        for u0 in [0.235_f32, 0.24, 0.245, 0.25, 0.255] {
            let mut a = attrs([1.0; 3], [0.5, 0.02], [u0, 0.004], [0.1, 0.001], 0.01, true);
            a[10] = APERTURE_FLAG;
            if shader.aperture_linear(&a).is_some() {
                checked += 1;
                let (s, q) = (shader.open_share(&a), shader.stepped_share(&a, 4096));
                for c in 0..3 {
                    assert!(
                        (s[c] - q[c]).abs() < 0.003,
                        "{u0}: {c}: {s:?} against {q:?}"
                    );
                }
            }
        }
        assert!(checked >= 3, "{checked}");
    }

    /// The fringe shader with no row split: every pixel of a sampled row shaded in full.
    struct Unsplit<'a>(FringeShader<'a>);

    impl Shader<12> for Unsplit<'_> {
        type Rows = ();

        fn shade(&self, a: &FringeAttrs) -> [f32; 3] {
            self.0.shade(a)
        }
    }

    proptest! {
        /// Rasterized, a fringed triangle gives the image its unsplit shade gives (up to
        /// rounding) — thin and steep triangles too, whose rows are the attribute plane evaluated
        /// inside them: what a row's split leaves out shades to zero and what it cores to the
        /// open shade (`FringeShader::rows` bounds the stop's reach by the corners').
        #[test]
        fn a_rasterized_fringe_triangle_matches_its_unsplit_shade(
            corners in prop::array::uniform3(prop::array::uniform2(0.0_f32..150.0)),
            r in prop::array::uniform3(0.85_f32..1.15),
            dr in prop::array::uniform3(-0.1_f32..0.1),
            uv in prop::array::uniform3(prop::array::uniform2(-1.1_f32..1.1)),
            duv in prop::array::uniform3(prop::array::uniform2(-0.1_f32..0.1)),
            f in 1e-3_f32..0.05,
            flag in prop::bool::ANY,
            iris in prop::bool::ANY,
            rgb in prop::array::uniform3(0.1_f32..10.0),
        ) {
            let tables = [table()];
            let corner_attrs: Vec<FringeAttrs> = (0..3)
                .map(|k| {
                    let (u0, v0) = (uv[k][0], uv[k][1]);
                    let mut a =
                        attrs(rgb, [r[k], dr[k]], [u0, duv[k][0]], [v0, duv[k][1]], f, flag);
                    if flag && iris {
                        a[10] = APERTURE_FLAG;
                    }
                    a
                })
                .collect();
            let (w, h) = (150, 150);
            let draw = |split: bool| {
                let mut img = HdrImage::new(w, h);
                let coverage = Coverage::Sampled { min_area: SAMPLED_MIN_AREA };
                let tris = [[0, 1, 2]];
                let shader = FringeShader { tables: &tables, aperture: IRIS.sampler() };
                if split {
                    rasterize_shaded_into(
                        &mut img.pixels, w, &corners, &corner_attrs, &tris, coverage, &shader,
                    );
                } else {
                    rasterize_shaded_into(
                        &mut img.pixels, w, &corners, &corner_attrs, &tris, coverage,
                        &Unsplit(shader),
                    );
                }
                img
            };
            let (split, whole) = (draw(true), draw(false));
            // The same up to rounding and the shade's approximations: a split row restarts
            // its attributes from the plane at each part, where the unsplit row steps them on,
            // and a rounding can move a pixel from one approximation of its open share to
            // another. Where the stop or an aperture is flagged, those are a ramp's exact
            // integral and sums over `CORNER_STEPS` steps of `τ` (`aperture_stepped`, the
            // wide ends' steps), and a feather narrow against the segment of stop crossings
            // falls in one step, counted whole or not at all: they differ by up to one step's
            // share of the colour (6% of a pixel under a 0.0014 feather across a segment 0.1
            // long; 3e-3 of the irradiance at a 0.033 one's tail). Elsewhere 2% of the pixel,
            // with a floor of 1e-4 of the triangle's irradiance at a feather's far tail. A
            // pixel wrongly left dark or taken as open would be off by its whole shade.
            let floor = 1e-4 * rgb.iter().fold(0.0_f32, |m, &v| m.max(v));
            let step_share: [f32; 3] = if flag {
                let table = &tables[0];
                let width = 1.0 / CORNER_STEPS as f32;
                (0..CORNER_STEPS).fold([0.0; 3], |m, i| {
                    let lo = table.share(i as f32 * width);
                    let hi = table.share((i + 1) as f32 * width);
                    [0, 1, 2].map(|c| m[c].max((hi[c] - lo[c]).abs()))
                })
            } else {
                [0.0; 3]
            };
            for (k, (a, b)) in split.pixels.iter().zip(&whole.pixels).enumerate() {
                for c in 0..3 {
                    let tol = 0.02 * a[c].abs().max(b[c].abs())
                        + floor
                        + step_share[c] * rgb[c].abs();
                    prop_assert!(
                        (a[c] - b[c]).abs() <= tol,
                        "pixel {} channel {}: split {} against {}", k, c, a[c], b[c]
                    );
                }
            }
        }
    }

    #[test]
    fn appended_fringes_keep_their_tables() {
        let mut a = GhostMesh::default();
        let mut b = GhostMesh::default();
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        a.fringe_tables.push(table());
        a.fringe.push(
            tri,
            [attrs([1.0; 3], [0.5, 0.0], [0.0; 2], [0.0; 2], 0.01, false); 3],
        );
        b.fringe_tables.push(table());
        b.fringe_tables.push(table());
        let mut second = attrs([1.0; 3], [0.5, 0.0], [0.0; 2], [0.0; 2], 0.01, false);
        second[11] = 1.0;
        b.fringe.push(tri, [second; 3]);
        a.append(&b);
        assert_eq!(a.fringe_tables.len(), 3);
        assert_eq!(a.fringe.attrs[0][11], 0.0);
        assert_eq!(a.fringe.attrs[3][11], 2.0);
        a.fringe.truncate_to(1);
        assert_eq!((a.fringe.len(), a.fringe.attrs.len()), (1, 3));
    }
}

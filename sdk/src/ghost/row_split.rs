//! Where along a rasterized row a ghost's shade is zero, and where it is the open shade: the
//! pixels below a bound of an affine attribute ([`linear_split`]) or of the squared distance
//! of an affine point from the origin ([`parabola_split`]), computed once a row by the edge and
//! fringe shaders; where an iris's or a mask's transmission is known to be 0 or 1 along a row
//! ([`aperture_split`]); and [`smoothstep`], the feather they step.

use crate::aperture::ApertureSampler;

/// Margin (in relative radius at the stop) by which the shaders' row splits (`split_row`)
/// keep pixels near a transition on the full shade: far more than the f32 rounding of the
/// interpolated attributes along a tile's row (a few 1e-6).
pub(crate) const SPLIT_MARGIN: f64 = 1e-4;

/// Normalised stop units kept between a row's pixels found dark or open by the aperture
/// ([`aperture_split`]) and the aperture's outline, for the f32 rounding of the pixels'
/// attributes along the row (far above it: a feather is at least 1e-4).
pub(crate) const APERTURE_SPLIT_MARGIN: f64 = 1e-5;

/// Rows with fewer lit pixels than this are not traced by [`aperture_split`] (they keep the
/// full shade): tracing, at least three evaluations of the aperture, would cost about as
/// many as it saves (measured on the Nikon zoom's default frame with a mask: at 4 pixels,
/// the edge rows' tracing took twice their shading).
pub(crate) const APERTURE_SPLIT_MIN_PIXELS: usize = 8;

/// The pixels `k` in `[0, n)` with `m0 + k·dm < outer`, and those with `m0 + k·dm < inner`.
pub(crate) fn linear_split(
    m0: f64,
    dm: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    linear_split_with(m0, dm, 1.0 / dm, [outer, inner], n)
}

/// [`linear_split`] with `1 / dm` given (`id`): a triangle's rows share it.
#[inline]
pub(crate) fn linear_split_with(
    m0: f64,
    dm: f64,
    id: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let below = |t: f64| if m0 < t { 0..n } else { 0..0 };
    if dm == 0.0 || dm.is_nan() {
        return (below(outer), below(inner));
    }
    let m1 = m0 + n.saturating_sub(1) as f64 * dm;
    if m0.max(m1) < inner {
        return (0..n, 0..n);
    }
    if m0.min(m1) >= outer {
        return (0..0, 0..0);
    }
    let (xl, xc) = ((outer - m0) * id, (inner - m0) * id);
    if dm > 0.0 {
        (0..ceil_index(xl, n), 0..ceil_index(xc, n))
    } else {
        (after_index(xl, n)..n, after_index(xc, n)..n)
    }
}

/// The pixels `k` in `[0, n)` with `|(u, v) + k (du, dv)| < outer`, and those with it
/// `< inner`.
pub(crate) fn parabola_split(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    [outer, inner]: [f64; 2],
    n: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let below = parabola_below(u, v, du, dv, n);
    (below(outer * outer), below(inner * inner))
}

/// The pixels `k` in `[0, n)` with `|(u, v) + k (du, dv)|² < t`, as a function of `t` (one
/// square root a call: where only one of [`parabola_split`]'s two bounds is wanted).
#[inline]
pub(crate) fn parabola_below(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    n: usize,
) -> impl Fn(f64) -> std::ops::Range<usize> {
    parabola_below_with(u, v, du, dv, StepNorm::new(du, dv), n)
}

/// `|(du, dv)|²` and its reciprocal (0 where it is 0), for [`parabola_below_with`]: a
/// triangle's rows share their step.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct StepNorm {
    a2: f64,
    ia: f64,
}

impl StepNorm {
    #[inline]
    pub(crate) fn new(du: f64, dv: f64) -> StepNorm {
        let a2 = du * du + dv * dv;
        StepNorm {
            a2,
            ia: if a2 > 0.0 { 1.0 / a2 } else { 0.0 },
        }
    }
}

/// [`parabola_below`] with the step's [`StepNorm`] given.
#[inline]
pub(crate) fn parabola_below_with(
    u: f64,
    v: f64,
    du: f64,
    dv: f64,
    StepNorm { a2, ia }: StepNorm,
    n: usize,
) -> impl Fn(f64) -> std::ops::Range<usize> {
    // Least at kc, where it is q0 (the row's own |(u, v)|² where it does not move).
    let (ia, kc, q0) = if a2 > 0.0 {
        let kc = -(u * du + v * dv) * ia;
        let (pu, pv) = (u + kc * du, v + kc * dv);
        (ia, kc, pu * pu + pv * pv)
    } else {
        (0.0, 0.0, u * u + v * v)
    };
    move |t: f64| {
        if a2 > 0.0 {
            // Below t for |k − kc| < √((t − q0)/a2).
            if t.is_nan() || q0.is_nan() || t <= q0 {
                return 0..0;
            }
            let h = ((t - q0) * ia).sqrt();
            after_index(kc - h, n)..ceil_index(kc + h, n)
        } else if q0 < t {
            // The row does not move across the stop.
            0..n
        } else {
            0..0
        }
    }
}

/// `⌈x⌉` clamped to `[0, n]` (0 for NaN), without a libm call or a conversion to an
/// unsigned integer (each a sequence of instructions on baseline x86-64; a row's split makes
/// several of these). For `n ≤ 2⁵¹` (a row of a tile: [`round_index`]).
#[inline]
fn ceil_index(x: f64, n: usize) -> usize {
    debug_assert!(n <= 1 << 51, "a row of {n} pixels");
    let x = x.clamp(0.0, n as f64);
    if x.is_nan() {
        return 0;
    }
    let (r, rf) = round_index(x);
    (r + usize::from(rf < x)).min(n)
}

/// `⌊x⌋ + 1`, the first index above `x`, clamped to `[0, n]` (`n` for NaN: with
/// [`ceil_index`]'s 0, a NaN bound gives an empty range). For `n ≤ 2⁵¹`, as
/// [`ceil_index`].
#[inline]
fn after_index(x: f64, n: usize) -> usize {
    debug_assert!(n <= 1 << 51, "a row of {n} pixels");
    if x < 0.0 {
        return 0;
    }
    let x = x.min(n as f64);
    if x.is_nan() {
        return n;
    }
    let (r, rf) = round_index(x);
    (r - usize::from(rf > x) + 1).min(n)
}

/// `x` (in `[0, 2⁵¹]`) rounded to the nearest integer, as an index and as an f64: adding 2⁵²
/// leaves the integer in the low bits of the sum.
#[inline]
fn round_index(x: f64) -> (usize, f64) {
    const SHIFT: f64 = 4_503_599_627_370_496.0;
    let r = x + SHIFT;
    ((r.to_bits() & ((1 << 52) - 1)) as usize, r - SHIFT)
}

pub(crate) fn intersect(
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
) -> std::ops::Range<usize> {
    a.start.max(b.start)..a.end.min(b.end)
}

/// 0 at `edge0`, 1 at `edge1`, smooth (C¹) in between; works for either order of the edges.
pub(crate) fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Narrows a row's `lit` pixels and its `core` (the pixels whose shade is the open one) by an
/// aperture other than the circle, whose transmission with `feather` is found at the points
/// `(u, v) + k (du, dv)` of pixels `k`: the pixels at either end where it is 0 within `margin`
/// (normalised stop units, at least [`APERTURE_SPLIT_MARGIN`]) of their point are left dark,
/// and the core is the run about the given core's middle where it is 1 within `margin` (none
/// where it is not 1 there). Traced along the row with [`ApertureSampler::transmission_reach`]: one evaluation
/// steps over every pixel within its reach, so a long row costs a few evaluations; a row of
/// under [`APERTURE_SPLIT_MIN_PIXELS`] lit pixels is left whole, with no core.
#[allow(clippy::too_many_arguments, reason = "a row's point, step and bounds")]
pub(crate) fn aperture_split(
    aperture: &ApertureSampler<'_>,
    [u, v]: [f64; 2],
    [du, dv]: [f64; 2],
    feather: f32,
    margin: f64,
    lit: std::ops::Range<usize>,
    core: std::ops::Range<usize>,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    if lit.len() < APERTURE_SPLIT_MIN_PIXELS {
        return (lit, 0..0);
    }
    let step = (du * du + dv * dv).sqrt();
    // How many pixels from `k` on (either way) have the transmission `want`: 0 when `k` has
    // not, nor when it is only `k` (an evaluation that steps one pixel saves none).
    let run = |k: usize, want: f32| -> usize {
        let (x, y) = (u + k as f64 * du, v + k as f64 * dv);
        let (t, reach) = aperture.transmission_reach(x as f32, y as f32, feather);
        let reach = f64::from(reach);
        #[allow(clippy::float_cmp, reason = "a known transmission is 0 or 1 exactly")]
        if t != want || reach <= margin {
            0
        } else if step > 0.0 {
            match ((reach - margin) / step).min(1e9) as usize {
                0 => 0,
                r => r + 1,
            }
        } else {
            usize::MAX
        }
    };
    let (mut start, mut end) = (lit.start, lit.end);
    while start < end {
        match run(start, 0.0) {
            0 => break,
            r => start = start.saturating_add(r).min(end),
        }
    }
    while end > start {
        match run(end - 1, 0.0) {
            0 => break,
            r => end = end.saturating_sub(r).max(start),
        }
    }
    let lit = start..end;
    let core = intersect(core, lit.clone());
    if core.is_empty() {
        return (lit, 0..0);
    }
    // The core: from its middle, where the transmission is 1, outward while it stays so.
    let middle = core.start + (core.end - core.start) / 2;
    let first = run(middle, 1.0);
    if first == 0 {
        return (lit, 0..0);
    }
    let (mut forward, mut backward) = (
        middle.saturating_add(first).min(core.end),
        middle.saturating_sub(first - 1).max(core.start),
    );
    while forward < core.end {
        match run(forward, 1.0) {
            0 => break,
            r => forward = forward.saturating_add(r).min(core.end),
        }
    }
    while backward > core.start {
        match run(backward - 1, 1.0) {
            0 => break,
            r => backward = backward.saturating_sub(r).max(core.start),
        }
    }
    (lit, backward..forward)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_indices_are_ceilings_and_floors_clamped_to_the_row() {
        let xs = [
            -3.0,
            -0.5,
            -0.0,
            0.0,
            1e-300,
            0.25,
            0.5,
            0.75,
            1.0,
            1.5,
            2.5,
            3.5,
            7.999_999_9,
            8.0,
            8.000_001,
            63.5,
            64.0,
            64.5,
            1e9,
            1e30,
            f64::INFINITY,
            f64::NAN,
        ];
        for n in [0, 1, 2, 8, 64, 100] {
            for &x in &xs {
                let nf = n as f64;
                let ceil = if x.is_nan() {
                    0
                } else {
                    x.clamp(0.0, nf).ceil() as usize
                };
                let after = if x.is_nan() {
                    n
                } else if x < 0.0 {
                    0
                } else {
                    (x.min(nf).floor() as usize + 1).min(n)
                };
                assert_eq!(ceil_index(x, n), ceil, "ceil {x} {n}");
                assert_eq!(after_index(x, n), after, "after {x} {n}");
            }
        }
    }
}

//! Surface profiles: the sag curve of one surface in the meridional plane, sampled for drawing.

use flarebench_sdk::Surface;

/// Intervals a curved profile starts from on each side of the axis, before refinement.
const BASE_INTERVALS: usize = 32;

/// How far (relative to the drawn semi-diameter) the sampled polyline may stray from the true
/// curve: an interval whose midpoint on the curve lies farther than this from its chord is
/// halved.
const TOLERANCE: f64 = 2e-5;

/// Halvings per base interval at most (a profile has at most 32 · 2⁸ intervals per side).
const MAX_DEPTH: u32 = 8;

/// The semi-diameter a surface is drawn to: its clear semi-diameter, or, where the sag is
/// undefined before that (a sphere or ellipsoid smaller than the semi-diameter), the largest
/// height where it is defined and finite. 0 for a surface of no extent.
pub fn drawn_semi_diameter(surface: &Surface) -> f64 {
    let sd = surface.semi_diameter;
    let ok = |r: f64| surface.sag(r).is_some_and(f64::is_finite);
    if !(sd.is_finite() && sd > 0.0 && ok(0.0)) {
        return 0.0;
    }
    if ok(sd) {
        return sd;
    }
    // The sag is defined on [0, r_max]: bisect for r_max.
    let (mut lo, mut hi) = (0.0, sd);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The heights `0 = y₀ < y₁ < … < yₙ = drawn semi-diameter` at which the profile of `surface`
/// is sampled: one interval for a flat surface; for a curved one, 32 equal intervals, each
/// halved until the curve lies within 2·10⁻⁵ of the semi-diameter of its chord (at most
/// eight times), so that steep rims get more points than the flat middle. Just `[0]` for a
/// surface of no extent.
pub fn profile_heights(surface: &Surface) -> Vec<f64> {
    let h = drawn_semi_diameter(surface);
    if h <= 0.0 {
        return vec![0.0];
    }
    let flat = surface.curvature == 0.0 && surface.aspheric.iter().all(|&a| a == 0.0);
    if flat {
        return vec![0.0, h];
    }
    let sag = |r: f64| surface.sag(r.min(h)).unwrap_or(0.0);
    let tol = TOLERANCE * h;
    let mut out = vec![0.0];
    let step = h / BASE_INTERVALS as f64;
    for k in 0..BASE_INTERVALS {
        let a = step * k as f64;
        let b = if k + 1 == BASE_INTERVALS {
            h
        } else {
            step * (k + 1) as f64
        };
        refine(&sag, a, b, sag(a), sag(b), tol, MAX_DEPTH, &mut out);
    }
    out
}

/// Appends the heights in `(a, b]` that sample `sag` on `[a, b]` within `tol`.
#[allow(
    clippy::too_many_arguments,
    reason = "a private recursion carrying its interval"
)]
fn refine(
    sag: &impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    za: f64,
    zb: f64,
    tol: f64,
    depth: u32,
    out: &mut Vec<f64>,
) {
    let m = 0.5 * (a + b);
    if depth > 0 && m > a && m < b {
        let zm = sag(m);
        // Distance from the curve's midpoint to the chord.
        let off = (zm - 0.5 * (za + zb)).abs() * (b - a) / (zb - za).hypot(b - a);
        if off > tol {
            refine(sag, a, m, za, zm, tol, depth - 1, out);
            refine(sag, m, b, zm, zb, tol, depth - 1, out);
            return;
        }
    }
    out.push(b);
}

/// The profile of `surface` with its vertex at `z0`: points (z, y) from the bottom rim
/// (y = −semi-diameter) through the vertex to the top rim, at [`profile_heights`], each on
/// the surface's sag (sphere, conic or even asphere), clipped where the sag is undefined (see
/// [`drawn_semi_diameter`]).
pub fn profile(surface: &Surface, z0: f64) -> Vec<[f64; 2]> {
    mirrored(surface, z0, &profile_heights(surface))
}

/// The points (z0 + sag(|y|), y) of `surface` at the heights `heights` (ascending from 0)
/// mirrored about the axis: from −yₙ up to +yₙ, the axis point once. Heights beyond the drawn
/// semi-diameter follow its rim (the flat step of an element's edge).
fn mirrored(surface: &Surface, z0: f64, heights: &[f64]) -> Vec<[f64; 2]> {
    let h = drawn_semi_diameter(surface);
    let z = |y: f64| z0 + surface.sag(y.abs().min(h)).unwrap_or(0.0);
    let below = heights.iter().rev().filter(|&&y| y > 0.0).map(|&y| -y);
    let above = heights.iter().copied();
    below.chain(above).map(|y| [z(y), y]).collect()
}

/// The profile of `surface` at `intervals + 1` equally spaced heights from −semi-diameter to
/// +semi-diameter (the editor's terminal side view, where a few points suffice); heights
/// where the sag is undefined are left out.
pub fn profile_uniform(surface: &Surface, z0: f64, intervals: usize) -> Vec<[f64; 2]> {
    let n = intervals.max(1);
    (0..=n)
        .filter_map(|k| {
            let y = surface.semi_diameter * (2.0 * k as f64 / n as f64 - 1.0);
            surface.sag(y.abs()).map(|dz| [z0 + dz, y])
        })
        .collect()
}

/// The upper rim of `surface` (vertex at `z0`): the point of its profile at the drawn
/// semi-diameter.
pub fn rim(surface: &Surface, z0: f64) -> [f64; 2] {
    let h = drawn_semi_diameter(surface);
    [z0 + surface.sag(h).unwrap_or(0.0), h]
}

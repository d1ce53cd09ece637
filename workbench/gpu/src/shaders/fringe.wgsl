// The fringe shader: a WGSL port of `FringeShader::shade` (flarebench_sdk::ghost::fringe),
// the colour fringes of a dispersive ghost drawn once for all its bands. `fringe_shade(a)`
// takes a pixel's 12 interpolated `FringeAttrs` (summed RGB irradiance; clip radius at τ = 0
// and its change over τ ∈ [0, 1]; likewise the stop crossing's u and v; the feather; the stop
// flag, 1 where the circular stop is evaluated and 2 where another aperture is (its soft
// transmission stepped over τ, `APERTURE_FLAG`); the index of the ghost's table) and returns
// its RGB: the irradiance times, per channel, the share of the ghost's colour over the open
// interval of τ.
//
// Meant to be concatenated into a shader module after aperture.wgsl (`aperture_soft`,
// `aperture_uniform_around`): no entry point; every global is prefixed `fringe_`. It reads the
// ghosts' `FringeTable`s, packed by `flarebench_gpu::fringe::pack_tables`, from group 1,
// binding 0: table k at `k * FRINGE_TABLE_STRIDE`, its node i (τ = i / 64) at `+ 6 i` as
// `[F_r, F_g, F_b, H_r, H_g, H_b]` (share and its integral).
//
// The CPU's f64 (the exact integral of a wide ramp's smoothstep, `smooth_share`, from the
// colour's partial moments) is replaced by a sum over the table's intervals of the
// smoothstep's exact mean on each times the interval's share of the colour (F is linear
// between nodes): the same integral without the moments' cancellation, in f32. Everything
// else follows the CPU's f32 arithmetic operation by operation.

@group(1) @binding(0) var<storage, read> fringe_data: array<f32>;

/// Intervals between a table's nodes (`FringeTable::NODE_COUNT`).
const FRINGE_NODES: u32 = 64u;
/// f32s per table: 65 nodes of 6.
const FRINGE_TABLE_STRIDE: u32 = 390u;
/// Width of the linear ramp that stands for the feather's smoothstep, in feathers: √(12/20).
const FRINGE_RAMP_WIDTH: f32 = 0.7745967;
/// Width in τ beyond which one end's ramp is summed step by step.
const FRINGE_WIDE_RAMP: f32 = 0.25;
/// Largest sag (in feathers) of the stop's radius below its chord for which a wide end of the
/// stop is integrated as linear in τ.
const FRINGE_MAX_SAG: f32 = 0.01;
/// `fringe::LINEAR_SAG`.
const FRINGE_LINEAR_SAG: f32 = 1e-3;
/// Steps over τ where ends meet, the stop is grazed or an end's ramp is wide.
const FRINGE_CORNER_STEPS: u32 = 16u;

/// Which way the last `fringe_shade` of this invocation went (for tests; the compiler drops
/// it where nothing reads it): 1 the stop's line misses it, 2 a still end closes everything,
/// 3 an end is closed throughout τ, 4 the stop is grazed (stepped), 5 ends overlap
/// (stepped between them), 6 a wide clip end (exact), 7 a wide stop end (exact), 8 a wide
/// end otherwise (stepped), 9 ends apart (mean shares), 10 ends apart, nothing open, 11 no
/// end in τ's range, 12 another aperture closed all along the stop's segment, 13 another
/// aperture stepped; plus 16 where the clip's value does not move with τ, 32 the stop's.
var<private> fringe_branch: u32;

/// Node i's share F of table `base` (offset of the table in `fringe_data`).
fn fringe_f(base: u32, i: u32) -> vec3<f32> {
    let k = base + 6u * i;
    return vec3<f32>(fringe_data[k], fringe_data[k + 1u], fringe_data[k + 2u]);
}

/// Node i's integral H.
fn fringe_h(base: u32, i: u32) -> vec3<f32> {
    let k = base + 6u * i + 3u;
    return vec3<f32>(fringe_data[k], fringe_data[k + 1u], fringe_data[k + 2u]);
}

/// `FringeTable::share`: F(τ), 0 below the range (and for NaN), 1 above it.
fn fringe_share(base: u32, t: f32) -> vec3<f32> {
    if !(t > 0.0) {
        return vec3<f32>(0.0);
    }
    if t >= 1.0 {
        return vec3<f32>(1.0);
    }
    let x = t * f32(FRINGE_NODES);
    let i = min(u32(x), FRINGE_NODES - 1u);
    let s = x - f32(i);
    let a = fringe_f(base, i);
    let b = fringe_f(base, i + 1u);
    return a + s * (b - a);
}

/// `FringeTable::integral`: H(τ) = ∫₀^τ F.
fn fringe_integral(base: u32, t: f32) -> vec3<f32> {
    if !(t > 0.0) {
        return vec3<f32>(0.0);
    }
    if t >= 1.0 {
        return fringe_h(base, FRINGE_NODES) + vec3<f32>(t - 1.0);
    }
    let x = t * f32(FRINGE_NODES);
    let i = min(u32(x), FRINGE_NODES - 1u);
    let s = x - f32(i);
    let a = fringe_f(base, i);
    let b = fringe_f(base, i + 1u);
    let h = 1.0 / f32(FRINGE_NODES);
    return fringe_h(base, i) + (h * s) * (a + (0.5 * s) * (b - a));
}

/// `FringeTable::mean_share`: the mean of F over [a, b] (a ≤ b).
fn fringe_mean_share(base: u32, a: f32, b: f32) -> vec3<f32> {
    if b <= 0.0 {
        return vec3<f32>(0.0);
    }
    if a >= 1.0 {
        return vec3<f32>(1.0);
    }
    let w = b - a;
    if !(w > 1e-5) {
        return fringe_share(base, 0.5 * (a + b));
    }
    return (fringe_integral(base, b) - fringe_integral(base, a)) / w;
}

/// `FringeTable::smooth_share`: ∫₀¹ S(p + q τ) dF(τ) per channel, S the smoothstep 3t² − 2t³
/// of t clamped to [0, 1], q ≠ 0. Where 0 < t < 1, summed over the table's intervals: F is
/// linear on each, so its part is the interval's share of the colour times S's mean over it,
/// exactly (G(t) = t³ − t⁴/2 differenced as a product, no cancellation).
fn fringe_smooth_share(base: u32, p: f32, q: f32) -> vec3<f32> {
    let zero = clamp(-p / q, 0.0, 1.0);
    let one = clamp((1.0 - p) / q, 0.0, 1.0);
    // Wholly open where t ≥ 1: above `one` for a rising t, below it for a falling one.
    let f_one = fringe_share(base, one);
    var out = select(f_one, vec3<f32>(1.0) - f_one, q > 0.0);
    let lo = min(zero, one);
    let hi = max(zero, one);
    if hi > lo {
        let n = f32(FRINGE_NODES);
        let first = min(u32(lo * n), FRINGE_NODES - 1u);
        let last = min(u32(ceil(hi * n)), FRINGE_NODES);
        var fa = fringe_f(base, first);
        for (var i = first; i < last; i++) {
            let fb = fringe_f(base, i + 1u);
            let ta = max(lo, f32(i) / n);
            let tb = min(hi, f32(i + 1u) / n);
            if tb > ta {
                let x = clamp(p + q * ta, 0.0, 1.0);
                let y = clamp(p + q * tb, 0.0, 1.0);
                // (G(y) − G(x)) / (y − x), S's mean over the interval.
                let mean_s = (x * x + x * y + y * y) - 0.5 * (x + y) * (x * x + y * y);
                out += ((tb - ta) * n * mean_s) * (fb - fa);
            }
            fa = fb;
        }
    }
    return out;
}

/// The feather's smoothstep from `e0` (0) to `e1` (1), `e0 > e1` allowed (the sdk's
/// `smoothstep`; WGSL's own is undefined there).
fn fringe_smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

/// At τ = t, the feather's smoothstep of the clip radius and (where flagged) of the stop's
/// exact radius, or (flag 2) the aperture's soft transmission at the stop crossing.
fn fringe_weight(a: array<f32, 12>, t: f32) -> f32 {
    let f = a[9];
    var w = fringe_smoothstep(1.0 + 0.5 * f, 1.0 - 0.5 * f, a[3] + t * a[4]);
    if a[10] > 1.5 {
        w *= aperture_soft(a[5] + t * a[6], a[7] + t * a[8], f);
    } else if a[10] > 0.5 {
        let u = a[5] + t * a[6];
        let v = a[7] + t * a[8];
        w *= fringe_smoothstep(1.0 + 0.5 * f, 1.0 - 0.5 * f, sqrt(u * u + v * v));
    }
    return w;
}

/// `FringeShader::stepped_between`: the open share summed over `FRINGE_CORNER_STEPS` steps of
/// τ over [lo, hi], the parts below and above at their side's end's weight.
fn fringe_stepped_between(a: array<f32, 12>, base: u32, lo: f32, hi: f32) -> vec3<f32> {
    var prev = fringe_share(base, lo);
    var acc = vec3<f32>(0.0);
    if lo > 0.0 {
        acc = fringe_weight(a, 0.5 * lo) * prev;
    }
    let width = (hi - lo) / f32(FRINGE_CORNER_STEPS);
    for (var i = 0u; i < FRINGE_CORNER_STEPS; i++) {
        let next = fringe_share(base, lo + f32(i + 1u) * width);
        let w = fringe_weight(a, lo + (f32(i) + 0.5) * width);
        acc += w * (next - prev);
        prev = next;
    }
    if hi < 1.0 {
        acc += fringe_weight(a, 0.5 * (hi + 1.0)) * (vec3<f32>(1.0) - prev);
    }
    return acc;
}

/// A ramp's span over the feather's whole smoothstep (the ramp is its narrower stand-in).
fn fringe_span(closed: f32, opened: f32) -> vec2<f32> {
    let mid = 0.5 * (opened + closed);
    let half = 0.5 * abs(opened - closed) / FRINGE_RAMP_WIDTH;
    return vec2<f32>(mid - half, mid + half);
}

/// `FringeShader::open_share`: the open share per channel at a pixel with attributes `a`.
fn fringe_open_share(a: array<f32, 12>, base: u32) -> vec3<f32> {
    let full = a[9];
    let f = full * FRINGE_RAMP_WIDTH;
    let ramp_in = 1.0 - 0.5 * f;
    let ramp_out = 1.0 + 0.5 * f;
    var factor = 1.0;
    // Candidate ends, in the CPU's order: 0 the clip's upper (open below), 1 the stop's
    // upper, 2 the clip's lower (open above), 3 the stop's lower.
    var has = array<bool, 4>(false, false, false, false);
    var closed = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var opened = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    // The clip radius r0 + τ r1, open below 1.
    let r0 = a[3];
    let r1 = a[4];
    let wholly = 1.0 - 0.5 * full;
    let clip_open = r0 < wholly && r0 + r1 < wholly;
    if !clip_open && abs(r1) < 1e-9 {
        factor *= fringe_smoothstep(1.0 + 0.5 * full, 1.0 - 0.5 * full, r0);
        fringe_branch |= 16u;
    } else if !clip_open {
        let k = select(2u, 0u, r1 > 0.0);
        has[k] = true;
        closed[k] = (ramp_out - r0) / r1;
        opened[k] = (ramp_in - r0) / r1;
    }
    // The circular stop: |(u0, v0) + τ (u1, v1)| open below 1.
    let u0 = a[5];
    let u1 = a[6];
    let v0 = a[7];
    let v1 = a[8];
    let ww = wholly * wholly;
    let inside0 = u0 * u0 + v0 * v0 < ww;
    let u_end = u0 + u1;
    let v_end = v0 + v1;
    let inside1 = u_end * u_end + v_end * v_end < ww;
    if a[10] > 0.5 && !(inside0 && inside1) {
        let dd = u1 * u1 + v1 * v1;
        if dd < 1e-14 {
            factor *= fringe_smoothstep(1.0 + 0.5 * full, 1.0 - 0.5 * full, sqrt(u0 * u0 + v0 * v0));
            fringe_branch |= 32u;
        } else {
            let tc = -(u0 * u1 + v0 * v1) / dd;
            let pu = u0 + tc * u1;
            let pv = v0 + tc * v1;
            let q2 = pu * pu + pv * pv;
            if q2 >= ramp_out * ramp_out {
                fringe_branch |= 1u;
                return vec3<f32>(0.0);
            }
            let h_out = sqrt(max(ramp_out * ramp_out - q2, 0.0) / dd);
            let h_in = sqrt(max(ramp_in * ramp_in - q2, 0.0) / dd);
            if q2 > ramp_in * ramp_in {
                // Grazed: the radius far from linear in τ over the feather.
                fringe_branch |= 4u;
                return fringe_stepped_between(a, base, 0.0, 1.0);
            }
            has[3] = true;
            closed[3] = tc - h_out;
            opened[3] = tc - h_in;
            has[1] = true;
            closed[1] = tc + h_out;
            opened[1] = tc + h_in;
        }
    }
    if factor == 0.0 {
        fringe_branch |= 2u;
        return vec3<f32>(0.0);
    }
    // The ends whose smoothstep reaches into τ ∈ [0, 1]; the others open or close throughout.
    var count = 0u;
    var e_closed = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var e_opened = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var e_lo = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var e_hi = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var e_upper = array<bool, 4>(false, false, false, false);
    var e_clip = array<bool, 4>(false, false, false, false);
    for (var k = 0u; k < 4u; k++) {
        if !has[k] {
            continue;
        }
        let s = fringe_span(closed[k], opened[k]);
        if s.y <= 0.0 || s.x >= 1.0 {
            let open_throughout = (opened[k] <= closed[k]) == (s.x >= 1.0);
            if !open_throughout {
                fringe_branch |= 3u;
                return vec3<f32>(0.0);
            }
            continue;
        }
        e_closed[count] = closed[k];
        e_opened[count] = opened[k];
        e_lo[count] = s.x;
        e_hi[count] = s.y;
        e_upper[count] = k < 2u;
        e_clip[count] = k % 2u == 0u;
        count += 1u;
    }
    if count == 0u {
        fringe_branch |= 11u;
        return vec3<f32>(factor);
    }
    var wide = false;
    var overlap = false;
    for (var i = 0u; i < count; i++) {
        wide = wide || abs(e_opened[i] - e_closed[i]) > FRINGE_WIDE_RAMP;
        for (var j = i + 1u; j < count; j++) {
            overlap = overlap || (e_lo[i] < e_hi[j] && e_lo[j] < e_hi[i]);
        }
    }
    if overlap {
        // Steps over where the ends' smoothsteps are.
        var lo = 1.0;
        var hi = 0.0;
        for (var i = 0u; i < count; i++) {
            lo = min(lo, e_lo[i]);
            hi = max(hi, e_hi[i]);
        }
        fringe_branch |= 5u;
        return fringe_stepped_between(a, base, max(lo, 0.0), min(hi, 1.0));
    }
    if wide {
        // One wide end linear in τ: its smoothstep integrated exactly against the colour.
        var linear = false;
        var x0 = 0.0;
        var x1 = 0.0;
        if count == 1u && e_clip[0] {
            linear = true;
            x0 = r0;
            x1 = r1;
            fringe_branch |= 6u;
        } else if count == 1u {
            let d0 = sqrt(u0 * u0 + v0 * v0);
            let d1 = sqrt(u_end * u_end + v_end * v_end);
            let um = u0 + 0.5 * u1;
            let vm = v0 + 0.5 * v1;
            let dm = sqrt(um * um + vm * vm);
            // The radius is convex in τ: its sag is at most twice that at the middle.
            linear = d0 + d1 - 2.0 * dm <= FRINGE_MAX_SAG * full;
            x0 = d0;
            x1 = d1 - d0;
            fringe_branch |= select(8u, 7u, linear);
        } else {
            fringe_branch |= 8u;
        }
        if !linear {
            return fringe_stepped_between(a, base, 0.0, 1.0);
        }
        // smoothstep(1 + f/2, 1 − f/2, x0 + τ x1) = S(p + q τ); 1 − x0 is exact near the edge.
        let p = ((1.0 - x0) + 0.5 * full) / full;
        let q = -x1 / full;
        return factor * fringe_smooth_share(base, p, q);
    }
    // Apart, each end cuts on its own: the share below the lowest upper end minus that below
    // the highest lower end; nothing where a lower end lies above an upper one.
    var below_hi = vec3<f32>(1.0);
    var below_lo = vec3<f32>(0.0);
    var top = 0.0;
    var bottom = 0.0;
    var have_top = false;
    var have_bottom = false;
    for (var i = 0u; i < count; i++) {
        if e_upper[i] {
            if !have_top || e_opened[i] < top {
                have_top = true;
                top = e_opened[i];
                below_hi = fringe_mean_share(base, e_opened[i], e_closed[i]);
            }
        } else if !have_bottom || e_opened[i] > bottom {
            have_bottom = true;
            bottom = e_opened[i];
            below_lo = fringe_mean_share(base, e_closed[i], e_opened[i]);
        }
    }
    if have_top && have_bottom && bottom > top {
        fringe_branch |= 10u;
        return vec3<f32>(0.0);
    }
    fringe_branch |= 9u;
    return factor * (below_hi - below_lo);
}

/// `FringeShader::shade`: the pixel's RGB from its 12 `FringeAttrs` `a`.
fn fringe_shade(a: array<f32, 12>) -> vec3<f32> {
    fringe_branch = 0u;
    // The table's index, rounded (the CPU truncates; an interpolated index may come a rounding
    // below its integer) and clamped to the tables there are.
    let tables = max(arrayLength(&fringe_data) / FRINGE_TABLE_STRIDE, 1u);
    let index = min(u32(max(round(a[11]), 0.0)), tables - 1u);
    let base = index * FRINGE_TABLE_STRIDE;
    var b = a;
    if a[10] > 1.5 {
        // `FringeShader::aperture_share`: the clip alone where the aperture is open along the
        // pixel's whole segment of stop crossings, nothing where it is closed, else stepped.
        let um = a[5] + 0.5 * a[6];
        let vm = a[7] + 0.5 * a[8];
        let half = 0.5 * sqrt(a[6] * a[6] + a[8] * a[8]);
        let uniform = aperture_uniform_around(um, vm, half, a[9]);
        if uniform == 0.0 {
            fringe_branch = 12u;
            return vec3<f32>(0.0);
        }
        if uniform < 0.0 {
            // `aperture_as_clip`: with the clip open all along τ and the aperture's signed
            // distance linear along the segment, its outline is shaded as the clip's edge.
            let f = a[9];
            let wholly = 1.0 - 0.5 * f;
            if a[3] < wholly && a[3] + a[4] < wholly && aperture_is_distance_ramp(f) {
                let d0 = aperture_distance(a[5], a[7]);
                let dm = aperture_distance(a[5] + 0.5 * a[6], a[7] + 0.5 * a[8]);
                let d1 = aperture_distance(a[5] + a[6], a[7] + a[8]);
                if abs(d0 + d1 - 2.0 * dm) <= 2.0 * FRINGE_MAX_SAG * f {
                    b[3] = 1.0 + d0;
                    b[4] = d1 - d0;
                    b[10] = 0.0;
                    let s = fringe_open_share(b, base);
                    fringe_branch = 14u;
                    return vec3<f32>(a[0], a[1], a[2]) * s;
                }
            }
            // `FringeShader::aperture_linear`: with the clip open along τ and the transmission
            // itself linear along the segment, integrated as such.
            if a[3] < wholly && a[3] + a[4] < wholly {
                let t0 = aperture_soft(a[5], a[7], f);
                let tm = aperture_soft(a[5] + 0.5 * a[6], a[7] + 0.5 * a[8], f);
                let t1 = aperture_soft(a[5] + a[6], a[7] + a[8], f);
                if abs(t0 + t1 - 2.0 * tm) <= 2.0 * FRINGE_LINEAR_SAG {
                    let h = fringe_integral(base, 1.0);
                    fringe_branch = 15u;
                    return vec3<f32>(a[0], a[1], a[2]) * (vec3<f32>(t0) + (t1 - t0) * (vec3<f32>(1.0) - h));
                }
            }
            fringe_branch = 13u;
            return vec3<f32>(a[0], a[1], a[2]) * fringe_stepped_between(a, base, 0.0, 1.0);
        }
        b[10] = 0.0;
    }
    let s = fringe_open_share(b, base);
    return vec3<f32>(a[0], a[1], a[2]) * s;
}

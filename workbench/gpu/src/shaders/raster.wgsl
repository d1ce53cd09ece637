// Ghost triangles drawn into a level's linear HDR target with additive blending, as the CPU
// rasterizer draws them (flarebench_sdk::raster, Coverage::Sampled): a triangle of at least
// `min_area` pixels², and at least MIN_SAMPLED_WIDTH across its longest side, is point-sampled
// at pixel centres, shaded with its attributes interpolated there; a smaller one (folds,
// caustics, slivers) adds to each pixel it overlaps the
// exact area of the pixel square it covers times the shade at that covered piece's centroid.
//
// Triangles are pulled from storage buffers (three corners each, `ATTRS` floats per corner);
// each instance is one triangle drawn as six vertices: the triangle itself and a degenerate
// one when it is large, the two halves of its bounding box in whole pixels when it is small.

override ATTRS: u32 = 3u;

// Narrowest a triangle may be (its height over its longest side, pixels) to be point-sampled:
// flarebench_sdk::raster::MIN_SAMPLED_WIDTH.
const MIN_SAMPLED_WIDTH: f32 = 1.0;

struct Level {
    // The level's frame in pixels.
    size: vec2<f32>,
    // Triangles of at least this many pixels² are point-sampled.
    min_area: f32,
    // Every shade is multiplied by this power of two (GhostRenderer::set_scale_log2; 1 by
    // default): exact in f32, and it lifts a frame's values into an f16 target's range.
    scale: f32,
}

@group(0) @binding(0) var<uniform> level: Level;
@group(0) @binding(1) var<storage, read> positions: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read> attrs: array<f32>;
@group(0) @binding(3) var<storage, read> tris: array<u32>;

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) tri: u32,
    @location(1) @interpolate(flat) small: u32,
    // A large triangle's attributes, interpolated by the rasterizer (up to 12 floats).
    @location(2) @interpolate(linear) a0: vec4<f32>,
    @location(3) @interpolate(linear) a1: vec4<f32>,
    @location(4) @interpolate(linear) a2: vec4<f32>,
}

fn is_finite(x: f32) -> bool {
    // NaN fails both comparisons; ±∞ the second.
    return x == x && abs(x) <= 3.4028235e38;
}

fn corner(t: u32, k: u32) -> vec2<f32> {
    return positions[tris[3u * t + k]];
}

// True when the triangle is drawn at all: finite corners and attributes, non-zero area (the
// CPU rasterizer skips the others).
fn usable(t: u32, p0: vec2<f32>, p1: vec2<f32>, p2: vec2<f32>) -> bool {
    if !(is_finite(p0.x) && is_finite(p0.y) && is_finite(p1.x) && is_finite(p1.y)
        && is_finite(p2.x) && is_finite(p2.y)) {
        return false;
    }
    for (var k = 0u; k < 3u; k++) {
        let base = tris[3u * t + k] * ATTRS;
        for (var i = 0u; i < ATTRS; i++) {
            if !is_finite(attrs[base + i]) {
                return false;
            }
        }
    }
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    return e1.x * e2.y - e2.x * e1.y != 0.0;
}

fn to_clip(p: vec2<f32>) -> vec4<f32> {
    return vec4<f32>(p.x / level.size.x * 2.0 - 1.0, 1.0 - p.y / level.size.y * 2.0, 0.0, 1.0);
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) t: u32) -> VsOut {
    let p0 = corner(t, 0u);
    let p1 = corner(t, 1u);
    let p2 = corner(t, 2u);
    var out: VsOut;
    out.tri = t;
    out.small = 0u;
    // Off-screen and degenerate by default.
    out.pos = vec4<f32>(-2.0, -2.0, 0.0, 1.0);
    if !usable(t, p0, p1, p2) {
        return out;
    }
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let area = 0.5 * abs(e1.x * e2.y - e2.x * e1.y);
    let e3 = p2 - p1;
    let longest2 = max(max(dot(e1, e1), dot(e2, e2)), dot(e3, e3));
    if area >= level.min_area && 4.0 * area * area >= MIN_SAMPLED_WIDTH * MIN_SAMPLED_WIDTH * longest2 {
        if vi < 3u {
            out.pos = to_clip(corner(t, vi));
            let a = corner_attrs(t, vi);
            out.a0 = vec4<f32>(a[0], a[1], a[2], a[3]);
            out.a1 = vec4<f32>(a[4], a[5], a[6], a[7]);
            out.a2 = vec4<f32>(a[8], a[9], a[10], a[11]);
        }
        return out;
    }
    out.small = 1u;
    let lo = max(floor(min(min(p0, p1), p2)), vec2<f32>(0.0));
    let hi = min(ceil(max(max(p0, p1), p2)), level.size);
    if !(lo.x < hi.x && lo.y < hi.y) {
        return out;
    }
    // Two triangles over the box: (lo, (hi.x, lo.y), (lo.x, hi.y)) and the opposite half.
    var q: vec2<f32>;
    switch vi {
        case 0u: { q = lo; }
        case 1u, 4u: { q = vec2<f32>(hi.x, lo.y); }
        case 2u, 3u: { q = vec2<f32>(lo.x, hi.y); }
        default: { q = hi; }
    }
    out.pos = to_clip(q);
    return out;
}

// What a fragment adds: `weight` times the shade of `a`, the attributes at the point sampled.
struct Sample {
    weight: f32,
    a: array<f32, 12>,
}

fn corner_attrs(t: u32, k: u32) -> array<f32, 12> {
    var a: array<f32, 12>;
    let base = tris[3u * t + k] * ATTRS;
    for (var i = 0u; i < ATTRS; i++) {
        a[i] = attrs[base + i];
    }
    return a;
}

// Attributes at barycentric weights (w1, w2) of corners 1 and 2.
fn interpolate(t: u32, w1: f32, w2: f32) -> array<f32, 12> {
    let a0 = corner_attrs(t, 0u);
    let a1 = corner_attrs(t, 1u);
    let a2 = corner_attrs(t, 2u);
    var a: array<f32, 12>;
    for (var i = 0u; i < ATTRS; i++) {
        a[i] = a0[i] + w1 * (a1[i] - a0[i]) + w2 * (a2[i] - a0[i]);
    }
    return a;
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - b.x * a.y;
}

// The polygon of a pixel square clipped by a triangle (Sutherland–Hodgman against its three
// edges), at most 7 corners, in coordinates relative to the pixel's corner.
struct Poly {
    n: u32,
    v: array<vec2<f32>, 8>,
}

// Keeps the part of `p` on the inner side of the edge a → b of a triangle wound `sign`.
fn clip_edge(p: Poly, a: vec2<f32>, b: vec2<f32>, sign: f32) -> Poly {
    var out: Poly;
    out.n = 0u;
    if p.n == 0u {
        return out;
    }
    let d = b - a;
    var prev = p.v[p.n - 1u];
    var prev_side = sign * cross2(d, prev - a);
    for (var i = 0u; i < p.n; i++) {
        let cur = p.v[i];
        let side = sign * cross2(d, cur - a);
        if (side >= 0.0) != (prev_side >= 0.0) {
            let s = prev_side / (prev_side - side);
            if out.n < 8u {
                out.v[out.n] = prev + s * (cur - prev);
                out.n += 1u;
            }
        }
        if side >= 0.0 && out.n < 8u {
            out.v[out.n] = cur;
            out.n += 1u;
        }
        prev = cur;
        prev_side = side;
    }
    return out;
}

fn sample(in: VsOut) -> Sample {
    var s: Sample;
    if in.small == 0u {
        // Point sampling at the pixel centre: the rasterizer's interpolated attributes.
        s.weight = 1.0;
        s.a = array<f32, 12>(
            in.a0.x, in.a0.y, in.a0.z, in.a0.w,
            in.a1.x, in.a1.y, in.a1.z, in.a1.w,
            in.a2.x, in.a2.y, in.a2.z, in.a2.w,
        );
        return s;
    }
    let frag = in.pos;
    let t = in.tri;
    let p0 = corner(t, 0u);
    let p1 = corner(t, 1u);
    let p2 = corner(t, 2u);
    // Exact coverage: the pixel square clipped to the triangle.
    let origin = floor(frag.xy);
    let q0 = p0 - origin;
    let q1 = p1 - origin;
    let q2 = p2 - origin;
    let e1 = q1 - q0;
    let e2 = q2 - q0;
    let area2 = cross2(e1, e2);
    let sign = select(-1.0, 1.0, area2 > 0.0);
    // A pixel wholly inside the triangle adds its whole area at its centre (as the CPU's full
    // runs do), one wholly beyond an edge nothing: only pixels on an edge are clipped (most
    // fragments of a large triangle drawn with exact coverage are inside it).
    var whole = true;
    for (var e = 0u; e < 3u; e++) {
        var a = q0;
        var b = q1;
        if e == 1u {
            a = q1;
            b = q2;
        } else if e == 2u {
            a = q2;
            b = q0;
        }
        let d = b - a;
        var inside = 0u;
        for (var k = 0u; k < 4u; k++) {
            let corner = vec2<f32>(f32(k & 1u), f32(k >> 1u));
            if sign * cross2(d, corner - a) >= 0.0 {
                inside += 1u;
            }
        }
        if inside == 0u {
            s.weight = 0.0;
            return s;
        }
        whole = whole && inside == 4u;
    }
    if whole {
        let c = vec2<f32>(0.5) - q0;
        let inv_whole = 1.0 / area2;
        s.weight = 1.0;
        s.a = interpolate(t, cross2(c, e2) * inv_whole, cross2(e1, c) * inv_whole);
        return s;
    }
    var poly: Poly;
    poly.n = 4u;
    poly.v[0] = vec2<f32>(0.0, 0.0);
    poly.v[1] = vec2<f32>(1.0, 0.0);
    poly.v[2] = vec2<f32>(1.0, 1.0);
    poly.v[3] = vec2<f32>(0.0, 1.0);
    poly = clip_edge(poly, q0, q1, sign);
    poly = clip_edge(poly, q1, q2, sign);
    poly = clip_edge(poly, q2, q0, sign);
    var a2 = 0.0;
    var cx = 0.0;
    var cy = 0.0;
    if poly.n >= 3u {
        var prev = poly.v[poly.n - 1u];
        for (var i = 0u; i < poly.n; i++) {
            let cur = poly.v[i];
            let c = cross2(prev, cur);
            a2 += c;
            cx += (prev.x + cur.x) * c;
            cy += (prev.y + cur.y) * c;
            prev = cur;
        }
    }
    let area = 0.5 * abs(a2);
    if !(area > 0.0) {
        s.weight = 0.0;
        return s;
    }
    let centroid = clamp(vec2<f32>(cx, cy) / (3.0 * a2), vec2<f32>(0.0), vec2<f32>(1.0));
    // Barycentric weights at the centroid, clamped to the triangle (CPU `Setup::interpolate`).
    let d = centroid - q0;
    let inv = 1.0 / area2;
    var w1 = clamp(cross2(d, e2) * inv, 0.0, 1.0);
    var w2 = clamp(cross2(e1, d) * inv, 0.0, 1.0);
    let sum = w1 + w2;
    if sum > 1.0 {
        w1 /= sum;
        w2 /= sum;
    }
    s.weight = min(area, 1.0);
    s.a = interpolate(t, w1, w2);
    return s;
}

// The smoothstep from 0 at e0 to 1 at e1 (either order), as the CPU's `smoothstep`.
fn smoothstep_between(e0: f32, e1: f32, x: f32) -> f32 {
    let t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// Wholly open triangles: the interpolated RGB irradiance.
@fragment
fn fs_open(in: VsOut) -> @location(0) vec4<f32> {
    let s = sample(in);
    if !(s.weight > 0.0) {
        discard;
    }
    return vec4<f32>(level.scale * (s.weight * vec3<f32>(s.a[0], s.a[1], s.a[2])), 0.0);
}

// Edge triangles (flarebench_sdk::ghost::mesh::EdgeAttrs): the irradiance times the
// feathered clip at relative radius 1 and, where flagged, the aperture at the stop crossing.
@fragment
fn fs_edge(in: VsOut) -> @location(0) vec4<f32> {
    let s = sample(in);
    if !(s.weight > 0.0) {
        discard;
    }
    let a = s.a;
    let feather = a[6];
    var t = smoothstep_between(1.0 + 0.5 * feather, 1.0 - 0.5 * feather, a[5]);
    if a[7] > 0.5 {
        t *= aperture_soft(a[3], a[4], feather);
    }
    return vec4<f32>(level.scale * (s.weight * t * vec3<f32>(a[0], a[1], a[2])), 0.0);
}

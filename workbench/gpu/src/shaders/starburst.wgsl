// A starburst pattern added to the output by exact area resampling, as the CPU's
// `flarebench_sdk::starburst::add_starburst`: bin (i, j) covers pixel coordinates
// first + (i, j)·step to first + (i + 1, j + 1)·step (x steps to the left), and each pixel
// gathers every bin it overlaps, weighted by the share of the bin it holds along each axis,
// times the flux. One quad per light over the pixels the pattern reaches.

struct Splat {
    // Pixel coordinate of bin 0's first edge, and signed pixels per bin, per axis.
    first: vec2<f32>,
    step: vec2<f32>,
    // The pixels the pattern covers: [x0, y0, x1, y1], within the frame.
    rect: vec4<f32>,
    // Frame size in pixels.
    frame: vec2<f32>,
    // Bins per side, and where this pattern starts in `patterns` (in bins).
    size: u32,
    offset: u32,
    flux: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(0) var<uniform> splat: Splat;
// RGB per bin, row-major, every pattern of the frame one after another.
@group(0) @binding(1) var<storage, read> patterns: array<f32>;

@vertex
fn vs_splat(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    var q: vec2<f32>;
    switch vi {
        case 0u: { q = splat.rect.xy; }
        case 1u, 4u: { q = vec2<f32>(splat.rect.z, splat.rect.y); }
        case 2u, 3u: { q = vec2<f32>(splat.rect.x, splat.rect.w); }
        default: { q = splat.rect.zw; }
    }
    return vec4<f32>(q.x / splat.frame.x * 2.0 - 1.0, 1.0 - q.y / splat.frame.y * 2.0, 0.0, 1.0);
}

// The bins a pixel [p, p + 1) overlaps along one axis, in bin units: [t_lo, t_hi].
fn bin_span(p: f32, first: f32, step: f32) -> vec2<f32> {
    let t0 = (p - first) / step;
    let t1 = (p + 1.0 - first) / step;
    return vec2<f32>(min(t0, t1), max(t0, t1));
}

@fragment
fn fs_splat(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let px = floor(pos.xy);
    let n = splat.size;
    let sx = bin_span(px.x, splat.first.x, splat.step.x);
    let sy = bin_span(px.y, splat.first.y, splat.step.y);
    let i0 = u32(clamp(floor(sx.x), 0.0, f32(n)));
    let i1 = u32(clamp(ceil(sx.y), 0.0, f32(n)));
    let j0 = u32(clamp(floor(sy.x), 0.0, f32(n)));
    let j1 = u32(clamp(ceil(sy.y), 0.0, f32(n)));
    var acc = vec3<f32>(0.0);
    for (var j = j0; j < j1; j++) {
        let wy = min(sy.y, f32(j + 1u)) - max(sy.x, f32(j));
        if wy <= 0.0 {
            continue;
        }
        var row = vec3<f32>(0.0);
        let base = splat.offset + j * n;
        for (var i = i0; i < i1; i++) {
            let wx = min(sx.y, f32(i + 1u)) - max(sx.x, f32(i));
            if wx > 0.0 {
                let k = 3u * (base + i);
                row += wx * vec3<f32>(patterns[k], patterns[k + 1u], patterns[k + 2u]);
            }
        }
        acc += wy * row;
    }
    return vec4<f32>(acc * splat.flux, 0.0);
}

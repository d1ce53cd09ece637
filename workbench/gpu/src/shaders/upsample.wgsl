// A coarse level added to the full-resolution target: the coarse density interpolated
// bilinearly between coarse pixel centres (constant beyond the outermost ones) and divided by
// factor² (flarebench_sdk::image::upsample, CoarseGrid). Drawn as one full-screen triangle
// with additive blending; texels read exactly (no filtering hardware, whose weights may be
// rounded to 8 bits).

struct Upsample {
    // Full-resolution pixels per coarse pixel, and 1 / factor².
    factor: f32,
    norm: f32,
    // Full-resolution pixels by which the coarse grid starts before the frame.
    offset: vec2<f32>,
}

@group(0) @binding(0) var<uniform> up: Upsample;
@group(0) @binding(1) var coarse: texture_2d<f32>;

@vertex
fn vs_full(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let x = f32((vi << 1u) & 2u);
    let y = f32(vi & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

// Along one axis: the coarse index below the full-resolution pixel's centre, the next one,
// and the next one's weight.
fn axis(x: f32, offset: f32, last: f32) -> vec3<f32> {
    let u = (x + offset) / up.factor - 0.5;
    if u <= 0.0 {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    if u >= last {
        return vec3<f32>(last, last, 0.0);
    }
    let i = floor(u);
    return vec3<f32>(i, i + 1.0, u - i);
}

@fragment
fn fs_upsample(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(coarse));
    // `pos` is the pixel centre, x + ½.
    let ax = axis(pos.x, up.offset.x, size.x - 1.0);
    let ay = axis(pos.y, up.offset.y, size.y - 1.0);
    let i0 = i32(ax.x);
    let i1 = i32(ax.y);
    let j0 = i32(ay.x);
    let j1 = i32(ay.y);
    let top0 = textureLoad(coarse, vec2<i32>(i0, j0), 0).rgb;
    let top1 = textureLoad(coarse, vec2<i32>(i1, j0), 0).rgb;
    let bot0 = textureLoad(coarse, vec2<i32>(i0, j1), 0).rgb;
    let bot1 = textureLoad(coarse, vec2<i32>(i1, j1), 0).rgb;
    let top = (top0 + ax.z * (top1 - top0)) * up.norm;
    let bottom = (bot0 + ax.z * (bot1 - bot0)) * up.norm;
    return vec4<f32>(top + ay.z * (bottom - top), 0.0);
}

// The PNG writer's tone mapping as a last pass: exposure (×2^ev), the ACES fit or a clamp,
// the sRGB transfer function, 8 bits rounded to nearest — the same formulas as the CPU's
// `ToneMap::map_channel`. Written to an Rgba8Unorm target as exact multiples of 1/255.

struct Tone {
    scale: f32,
    // 0 ACES, 1 clamp.
    curve: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> tone: Tone;
@group(0) @binding(1) var hdr: texture_2d<f32>;

@vertex
fn vs_full(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let x = f32((vi << 1u) & 2u);
    let y = f32(vi & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

fn srgb_encode(linear: f32) -> f32 {
    let v = select(0.0, min(linear, 1.0), linear >= 0.0);
    if v <= 0.0031308 {
        return 12.92 * v;
    }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

fn map_channel(linear: f32) -> f32 {
    let x = max(linear * tone.scale, 0.0);
    var y = x;
    if tone.curve == 0u {
        y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    }
    // Past about 1.8e19 the ACES ratio's x² overflows; from 1e9 up it clamps to white anyway.
    if x > 1e9 {
        y = 1.0;
    }
    return round(srgb_encode(y) * 255.0) / 255.0;
}

@fragment
fn fs_tone(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(hdr, vec2<i32>(pos.xy), 0).rgb;
    return vec4<f32>(map_channel(c.r), map_channel(c.g), map_channel(c.b), 1.0);
}

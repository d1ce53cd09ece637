// The stop's opening at a point (u, v) of the stop (normalised by its working radius), with
// the edge feathered over a band `feather` wide: the circle, an iris of straight or rounded
// blades, or a mask image with its signed distance field. The same formulas as the CPU's
// `flarebench_sdk::aperture` (ApertureSampler::transmission_soft), in f32.

struct ApertureParams {
    // 0 circle, 1 iris, 2 mask.
    kind: u32,
    // Iris: walk the edge normals (1) or fold by the polar angle (0); blade count.
    by_normals: u32,
    blades: u32,
    // Mask size in texels.
    mask_width: u32,
    mask_height: u32,
    // 1 where every texel is 0 or 1 (ApertureMask::is_binary); the distance field's slope
    // bound (ApertureMask::field_slope).
    mask_binary: u32,
    mask_slope: f32,
    _pad0: u32,
    // Iris constants (flarebench_sdk::aperture::iris::IrisGeometry).
    rotation: f32,
    sector: f32,
    half_sector: f32,
    a: f32,
    c: f32,
    kappa: f32,
    w: f32,
    s: f32,
    first_normal: vec2<f32>,
    step: vec2<f32>,
}

@group(0) @binding(4) var<uniform> aperture: ApertureParams;
// Mask transmission, then its signed distance field: two fields of width × height texels,
// row-major, row 0 at v = +1.
@group(0) @binding(5) var<storage, read> mask_fields: array<f32>;

// The smoothstep 3t² − 2t³ of t clamped to [0, 1].
fn ap_smooth(t: f32) -> f32 {
    let x = clamp(t, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// The step across an edge at signed distance d over a band `feather` wide (CPU smooth_edge);
// a NaN distance gives 0.
fn ap_smooth_edge(d: f32, feather: f32) -> f32 {
    let t = 0.5 - d / feather;
    if !(t > 0.0) {
        return 0.0;
    }
    return ap_smooth(t);
}

fn ap_iris_fold(u: f32, v: f32) -> vec2<f32> {
    if aperture.by_normals == 1u {
        let cs = aperture.step.x;
        let ss = aperture.step.y;
        var normal = aperture.first_normal;
        var best = normal;
        var x = u * normal.x + v * normal.y;
        for (var k = 1u; k < aperture.blades; k++) {
            normal = vec2<f32>(normal.x * cs - normal.y * ss, normal.x * ss + normal.y * cs);
            let d = u * normal.x + v * normal.y;
            if d > x {
                x = d;
                best = normal;
            }
        }
        return vec2<f32>(x, abs(v * best.x - u * best.y));
    }
    let r = sqrt(u * u + v * v);
    var psi = atan2(v, u) - aperture.rotation;
    psi = psi - floor(psi / aperture.sector) * aperture.sector;
    let t = abs(psi - aperture.half_sector);
    return vec2<f32>(r * cos(t), r * sin(t));
}

fn ap_iris_distance(u: f32, v: f32) -> f32 {
    let f = ap_iris_fold(u, v);
    let x = f.x;
    let y = f.y;
    let a = aperture.a;
    let c = aperture.c;
    let k = aperture.kappa;
    let w = aperture.w;
    let dx = x - a;
    if w * y - c * (k * dx + w) > 0.0 {
        return sqrt(dx * dx + (y - c) * (y - c));
    }
    let e = dx - aperture.s;
    let kx = k * dx + w;
    let ky = k * y;
    let kq = sqrt(kx * kx + ky * ky);
    return (k * (e * e + y * y) + 2.0 * e) / (kq + 1.0);
}

// One axis of the mask's bilinear lookup: position p in 0..=2 over n texels → (i0, i1, weight).
fn ap_mask_axis(p: f32, n: u32) -> vec3<f32> {
    let last = f32(n - 1u);
    let x = clamp(p * 0.5 * f32(n) - 0.5, 0.0, last);
    let i0 = floor(x);
    let i1 = min(i0 + 1.0, last);
    return vec3<f32>(i0, i1, x - i0);
}

// Bilinear lookup of field `field` (0 transmission, 1 distance) at (u, v), clamped to edge.
fn ap_mask_bilinear(field: u32, u: f32, v: f32) -> f32 {
    let w = aperture.mask_width;
    let h = aperture.mask_height;
    let base = field * w * h;
    let ax = ap_mask_axis(u + 1.0, w);
    let ay = ap_mask_axis(1.0 - v, h);
    let i0 = u32(ax.x);
    let i1 = u32(ax.y);
    let j0 = u32(ay.x);
    let j1 = u32(ay.y);
    let t00 = mask_fields[base + j0 * w + i0];
    let t01 = mask_fields[base + j0 * w + i1];
    let t10 = mask_fields[base + j1 * w + i0];
    let t11 = mask_fields[base + j1 * w + i1];
    let top = t00 + ax.z * (t01 - t00);
    let bottom = t10 + ax.z * (t11 - t10);
    return top + ay.z * (bottom - top);
}

fn ap_mask_transmission(u: f32, v: f32) -> f32 {
    if !(abs(u) <= 1.0 && abs(v) <= 1.0) {
        return 0.0;
    }
    return ap_mask_bilinear(0u, u, v);
}

fn ap_mask_distance(u: f32, v: f32) -> f32 {
    let tu = 2.0 / f32(aperture.mask_width);
    let tv = 2.0 / f32(aperture.mask_height);
    let eu = 1.0 - 0.5 * tu;
    let ev = 1.0 - 0.5 * tv;
    let uc = clamp(u, -eu, eu);
    let vc = clamp(v, -ev, ev);
    let du = u - uc;
    let dv = v - vc;
    return ap_mask_bilinear(1u, uc, vc) + sqrt(du * du + dv * dv);
}

// Transmission with the edge feathered over `feather` (feather > 0).
fn aperture_soft(u: f32, v: f32, feather: f32) -> f32 {
    switch aperture.kind {
        case 0u: {
            return ap_smooth_edge(sqrt(u * u + v * v) - 1.0, feather);
        }
        case 1u: {
            if !(feather > 0.0) {
                return select(0.0, 1.0, ap_iris_distance(u, v) <= 0.0);
            }
            return ap_smooth_edge(ap_iris_distance(u, v), feather);
        }
        default: {
            let texel = max(2.0 / f32(aperture.mask_width), 2.0 / f32(aperture.mask_height));
            if !(feather > texel) {
                return ap_mask_transmission(u, v);
            }
            return ap_smooth_edge(ap_mask_distance(u, v), feather);
        }
    }
}

// The signed distance to the opening's edge (negative inside): the CPU's
// ApertureSampler::signed_distance.
fn aperture_distance(u: f32, v: f32) -> f32 {
    switch aperture.kind {
        case 0u: {
            return sqrt(u * u + v * v) - 1.0;
        }
        case 1u: {
            return ap_iris_distance(u, v);
        }
        default: {
            return ap_mask_distance(u, v);
        }
    }
}

// True where aperture_soft with `feather` is the feather's smoothstep of aperture_distance
// (the CPU's ApertureSampler::soft_is_distance_ramp): the circle and the iris, a mask where
// the feather is wider than a texel.
fn aperture_is_distance_ramp(feather: f32) -> bool {
    if aperture.kind < 2u {
        return feather > 0.0;
    }
    let texel = max(2.0 / f32(aperture.mask_width), 2.0 / f32(aperture.mask_height));
    return feather > texel;
}

// Where aperture_soft with `feather` is the same at every point within `radius` of (u, v): 1
// wholly open, 0 wholly closed, −1 where it may vary (the CPU's
// ApertureSampler::uniform_around: exact for the circle and the iris, conservative for a
// mask).
fn aperture_uniform_around(u: f32, v: f32, radius: f32, feather: f32) -> f32 {
    if !(feather > 0.0) || !(radius >= 0.0) {
        return -1.0;
    }
    var d = 0.0;
    var margin = radius + 0.5 * feather + 1e-6;
    switch aperture.kind {
        case 0u: {
            d = sqrt(u * u + v * v) - 1.0;
        }
        case 1u: {
            d = ap_iris_distance(u, v);
        }
        default: {
            d = ap_mask_distance(u, v);
            let texel = max(2.0 / f32(aperture.mask_width), 2.0 / f32(aperture.mask_height));
            if !(feather > texel) {
                if aperture.mask_binary == 0u {
                    return -1.0;
                }
                margin = 2.0 * radius + 4.0 * texel + 1e-5;
            } else {
                // The field's slope: its bound within the texel centres' square (the CPU's
                // ApertureMask::slope_within), one more beyond.
                let eu = 1.0 - 1.0 / f32(aperture.mask_width);
                let ev = 1.0 - 1.0 / f32(aperture.mask_height);
                let inside = abs(u) + radius <= eu && abs(v) + radius <= ev;
                let slope = aperture.mask_slope + select(1.0, 0.0, inside);
                margin = slope * radius + 0.5 * feather + 1e-5;
            }
        }
    }
    if d <= -margin {
        return 1.0;
    }
    if d >= margin {
        return 0.0;
    }
    return -1.0;
}

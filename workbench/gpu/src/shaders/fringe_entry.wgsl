// Fringed triangles (flarebench_sdk::ghost::fringe): the bands' summed irradiance times the
// ghost's colour over the open interval of the dispersion coordinate (fringe.wgsl). Appended to
// the raster module with fringe.wgsl for the fringe pipeline only (it binds group 1).
@fragment
fn fs_fringe(in: VsOut) -> @location(0) vec4<f32> {
    let s = sample(in);
    if !(s.weight > 0.0) {
        discard;
    }
    return vec4<f32>(level.scale * (s.weight * fringe_shade(s.a)), 0.0);
}

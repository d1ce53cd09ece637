//! f32 against f64 on every bundled lens: the batched f32 tracer lands within a stated bound of
//! the f64 one, and agrees on every ray's fate away from aperture edges.

use flarebench_sdk::LensSystem;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::{Fate, Ray, RayBatch, Sequence};
use flarebench_test_support::{library_stems, load_lens};

/// Bound on |landing(f32) − landing(f64)| on the sensor, relative to the EFL. Measured worst
/// case over the library: 1.34e-6 × EFL (Laikin wide angle), most lenses 1e-7 to
/// 9e-7; the bound leaves 3× headroom. For a 50 mm lens that is 0.2 µm, far below a pixel.
const MAX_RELATIVE_LANDING_ERROR: f64 = 4e-6;

/// A 41 × 41 grid of collimated rays at `field` over 1.2 × the paraxial entrance pupil, so that
/// most rays pass and the grid's rim tests vignetting.
fn rays(sys: &LensSystem, field: f64) -> Vec<Ray> {
    let p = analyse(sys, 550.0).unwrap();
    let semi = 0.6 * p.entrance_pupil_diameter_mm;
    let shift = p.entrance_pupil_z_mm * field.tan();
    let n = 41;
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let mut r = Ray::collimated(field, 0.0, (2.0 * v - 1.0) * semi - shift);
            r.origin.x = (2.0 * u - 1.0) * semi;
            out.push(r);
        }
    }
    out
}

#[test]
fn f32_batches_track_f64_on_every_lens() {
    let mut worst_overall = 0.0f64;
    for stem in library_stems() {
        let sys = load_lens(&stem);
        let efl = analyse(&sys, 550.0).unwrap().efl_mm.abs();
        let half_diag = 0.5 * sys.film_width_mm.hypot(sys.film_height_mm);
        let half_field = (half_diag / efl).atan().min(30f64.to_radians());
        let seq = Sequence::forward(&sys, 550.0);
        let seq32 = seq.cast::<f32>();
        let mut worst = 0.0f64;
        let mut compared = 0;
        for field in [0.0, 0.5 * half_field, 0.9 * half_field] {
            let rays = rays(&sys, field);
            let mut b64 = RayBatch::<f64>::with_capacity(rays.len());
            let mut b32 = RayBatch::<f32>::with_capacity(rays.len());
            for r in &rays {
                b64.push(r.origin.to_array(), r.dir.to_array());
                b32.push(r.origin.as_vec3().to_array(), r.dir.as_vec3().to_array());
            }
            seq.trace_batch(&mut b64);
            seq32.trace_batch(&mut b32);
            let mut hits = Vec::new();
            for (i, ray) in rays.iter().enumerate() {
                let (p64, _, f64fate, _) = b64.get(i);
                let (p32, _, f32fate, _) = b32.get(i);
                // Fates agree unless the ray grazes an aperture edge somewhere.
                hits.clear();
                seq.trace_with_hits(ray, &mut hits);
                let grazes = hits.iter().any(|h| (h.relative_radius - 1.0).abs() < 1e-4);
                if !grazes && b64.completed(i) {
                    assert_eq!(f32fate, f64fate, "{stem}: ray {i} at field {field}");
                }
                if f64fate == Fate::Sensor && f32fate == Fate::Sensor {
                    let d = (p32[0] as f64 - p64[0]).hypot(p32[1] as f64 - p64[1]);
                    worst = worst.max(d / efl);
                    compared += 1;
                }
            }
        }
        assert!(
            compared > 100,
            "{stem}: only {compared} rays reached the sensor"
        );
        eprintln!(
            "{stem}: worst f32 landing error {:.2e} × EFL over {compared} rays",
            worst
        );
        assert!(
            worst < MAX_RELATIVE_LANDING_ERROR,
            "{stem}: {worst:e} × EFL"
        );
        worst_overall = worst_overall.max(worst);
    }
    eprintln!("worst over the library: {worst_overall:.2e} × EFL");
}

//! Property tests of the tracer and the interface physics.

use flarebench_sdk::coating::{Coating, CoatingLayer};
use flarebench_sdk::fresnel;
use flarebench_sdk::trace::{Fate, Interaction, Ray, RayBatch, Sequence};
use flarebench_sdk::{LensSystem, Medium, Surface};
use glam::DVec3;
use proptest::prelude::*;

const LAMBDA: f64 = 550.0;

/// A reversed ray's return to its first hit (mm): f64 rounding over a forward and a backward
/// trace through up to six surfaces.
const REVERSED_POSITION_TOL_MM: f64 = 1e-9;
/// A reversed ray's final direction against the start's, reversed: the same rounding on unit
/// vectors.
const REVERSED_DIRECTION_TOL: f64 = 1e-12;
/// A traced direction's length against 1: f64 rounding of the refractions.
const UNIT_DIRECTION_TOL: f64 = 1e-12;
/// R + T against 1 for a bare interface: f64 rounding of one subtraction.
const ENERGY_SUM_TOL: f64 = 1e-15;

/// A random but sensible lens: 2–6 refracting surfaces, radii of either sign (or flat), glass
/// indices 1.4–1.9, the stop first.
fn lens() -> impl Strategy<Value = LensSystem> {
    let surface = (
        prop_oneof![Just(0.0), 15.0f64..400.0, -400.0f64..-15.0],
        0.5f64..12.0,
        1.4f64..1.9,
        any::<bool>(),
    );
    prop::collection::vec(surface, 2..=6).prop_map(|specs| {
        let mut surfaces = vec![Surface::stop(2.0, 4.0)];
        for (i, (r, t, n, glass)) in specs.iter().enumerate() {
            let medium = if *glass && i + 1 < specs.len() {
                Medium::Model {
                    nd: *n,
                    vd: Some(50.0),
                }
            } else {
                Medium::Air
            };
            surfaces.push(Surface::spherical(*r, *t, medium, 10.0));
        }
        surfaces.push(Surface::sensor(30.0));
        LensSystem::new("random", surfaces)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Trace forward to the last surface, turn the ray round, trace back: it returns to where
    /// it started within 1e-9 mm.
    #[test]
    fn rays_are_reversible(sys in lens(), h in -3.0f64..3.0, field in -0.3f64..0.3, az in 0.0f64..6.3) {
        let last = sys.surfaces.len() - 2;
        let fwd: Vec<_> = (1..=last).map(|s| (s, Interaction::Refract)).collect();
        let back: Vec<_> = (1..=last).rev().map(|s| (s, Interaction::Refract)).collect();
        let seq_f = Sequence::custom(&sys, LAMBDA, true, &fwd).unwrap();
        let seq_b = Sequence::custom(&sys, LAMBDA, false, &back).unwrap();
        let start = Ray::collimated(field, az, h);
        let mut hits = Vec::new();
        let f = seq_f.trace_with_hits(&start, &mut hits);
        prop_assume!(f.completed);
        let reversed = Ray { origin: f.ray.origin, dir: -f.ray.dir };
        let b = seq_b.trace(&reversed);
        prop_assert!(b.completed, "{:?}", b.fate);
        let first_hit = hits[0].position;
        prop_assert!((b.ray.origin - first_hit).length() < REVERSED_POSITION_TOL_MM, "{} vs {}", b.ray.origin, first_hit);
        prop_assert!((b.ray.dir + start.dir).length() < REVERSED_DIRECTION_TOL);
    }

    /// Batched f64 tracing is the scalar tracer, ray for ray, bit for bit.
    #[test]
    fn batched_equals_scalar(sys in lens(), rays in prop::collection::vec((-6.0f64..6.0, -0.5f64..0.5, 0.0f64..6.3), 1..150)) {
        let seq = Sequence::forward(&sys, LAMBDA);
        let mut batch = RayBatch::<f64>::with_capacity(rays.len());
        let rays: Vec<Ray> = rays.iter().map(|&(h, a, p)| Ray::collimated(a, p, h)).collect();
        for r in &rays {
            batch.push(r.origin.to_array(), r.dir.to_array());
        }
        seq.trace_batch(&mut batch);
        for (i, r) in rays.iter().enumerate() {
            let s = seq.trace(r);
            let (p, d, fate, rel) = batch.get(i);
            prop_assert_eq!(fate, s.fate);
            prop_assert_eq!(batch.completed(i), s.completed);
            if s.completed {
                prop_assert_eq!(p, s.ray.origin.to_array());
                prop_assert_eq!(d, s.ray.dir.to_array());
            }
            prop_assert_eq!(rel, s.max_relative_radius);
        }
    }

    /// Directions stay unit vectors and nothing is NaN for any ray that completes; a ray that
    /// does not complete says why.
    #[test]
    fn traced_rays_stay_well_formed(sys in lens(), h in -20.0f64..20.0, field in -1.5f64..1.5) {
        let seq = Sequence::forward(&sys, LAMBDA);
        let r = seq.trace(&Ray::collimated(field, 0.0, h));
        if r.completed {
            prop_assert!(r.ray.origin.is_finite() && r.ray.dir.is_finite());
            prop_assert!((r.ray.dir.length() - 1.0).abs() < UNIT_DIRECTION_TOL);
        } else {
            // Stopped: the fate names the first event (a vignetting may precede the stop).
            prop_assert!(r.fate != Fate::Sensor, "{:?}", r.fate);
        }
        prop_assert!(r.throughput >= 0.0 && r.throughput <= 1.0);
    }

    /// Energy: R + T = 1 and 0 ≤ R ≤ 1 for bare interfaces and coatings, any angle, either way.
    #[test]
    fn reflectance_is_a_fraction(n1 in 1.0f64..2.0, n2 in 1.0f64..2.0, cos_i in 0.0f64..=1.0, l in 380.0f64..780.0,
                                 nc in 1.2f64..2.4, d in 20.0f64..300.0, forward in any::<bool>()) {
        let r = fresnel::reflectance(n1, n2, cos_i);
        prop_assert!((0.0..=1.0).contains(&r.s) && (0.0..=1.0).contains(&r.p));
        prop_assert!((r.unpolarised() + r.transmittance() - 1.0).abs() < ENERGY_SUM_TOL);
        let stack = Coating::Stack(vec![CoatingLayer { index: nc, thickness_nm: d }, CoatingLayer { index: 1.38, thickness_nm: 100.0 }]);
        let rc = stack.reflectance(n1, n2, cos_i, l, forward);
        prop_assert!((-1e-12..=1.0 + 1e-12).contains(&rc), "R = {}", rc);
    }
}

#[test]
fn grazing_and_parallel_rays_never_produce_nan() {
    let sys = LensSystem::new(
        "g",
        vec![
            Surface::stop(1.0, 5.0),
            Surface::spherical(20.0, 3.0, Medium::Model { nd: 1.5, vd: None }, 10.0),
            Surface::spherical(-20.0, 20.0, Medium::Air, 10.0),
            Surface::sensor(20.0),
        ],
    );
    let seq = Sequence::forward(&sys, LAMBDA);
    for dir in [
        DVec3::X,
        DVec3::new(1.0, 0.0, 1e-300),
        DVec3::new(0.0, 1.0, 1e-9),
    ] {
        let r = seq.trace(&Ray::new(DVec3::ZERO, dir));
        assert!(r.fate.is_terminal() || r.ray.origin.is_finite(), "{r:?}");
        assert!(
            matches!(r.fate, Fate::Missed { .. } | Fate::Vignetted { .. }),
            "{r:?}"
        );
    }
}

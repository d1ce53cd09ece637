//! The chief ray of a wide-angle lens far off axis, where its real entrance pupil lies far
//! from the paraxial one: the fisheye (Muller 16 mm f/4 scaled to 10 mm, a 155.9° field)
//! once reported its chief ray lost at 60° and 70° while its ghosts reached the sensor.

use flarebench_sdk::paraxial::stop_opening;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::starburst::chief_ray_landing;
use flarebench_sdk::trace::{Ray, Sequence};
use flarebench_test_support::load_lens;

/// A scanned ray counts as through the stop's centre within this share of the stop's radius,
/// and as landing where the chief ray does within this share of its image height.
const NEAR_SHARE: f64 = 0.01;
/// The scan's step over the entrance: 60 mm in 4000 steps.
const SCAN_STEPS: usize = 4000;

#[test]
fn a_fisheyes_chief_ray_is_found_far_off_axis_and_its_image_height_grows_with_the_angle() {
    let sys = load_lens("fisheye-10mm");
    let stop = sys.stop_index().unwrap();
    let seq = Sequence::forward(&sys, LAMBDA_D_NM);
    let mut last = 0.0;
    for deg in [10.0f64, 30.0, 50.0, 60.0, 70.0] {
        let theta = deg.to_radians();
        let [x, y] = chief_ray_landing(&sys, LAMBDA_D_NM, theta, 0.0)
            .unwrap_or_else(|e| panic!("{deg}°: {e}"));
        assert!(x.abs() < 1e-9, "{deg}°: x {x}");
        assert!(y.abs() > last, "{deg}°: image height {y} after {last}");
        last = y.abs();
        // Some ray at this angle crosses the stop's centre and lands there: find it by
        // scanning, and compare.
        let mut hits = Vec::new();
        let crosses_centre = (0..=SCAN_STEPS).any(|k| {
            let h = -30.0 + 60.0 * k as f64 / SCAN_STEPS as f64;
            hits.clear();
            let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
            r.completed
                && hits
                    .iter()
                    .find(|hit| hit.surface == stop)
                    .is_some_and(|hit| hit.position.y.abs() < NEAR_SHARE * stop_opening(&sys))
                && (r.ray.origin.y - y).abs() < 5.0 * NEAR_SHARE * y.abs()
        });
        assert!(
            crosses_centre,
            "{deg}°: no ray near the stop's centre lands near {y}"
        );
    }
}

/// The M.Zuiko 8 mm f/1.8 fisheye at 70°: rays entering outside its front element fold back
/// there, their stop crossings jumping from +16.4 mm to −16.4 mm between two neighbouring
/// heights of the bracketing scan, ahead (in the scan's order) of the true chief ray near
/// h = −28.8 mm. Bisecting that jump once ended on a ray that does not complete its path, and
/// the chief ray was reported lost.
#[test]
fn a_fold_at_the_front_rim_does_not_hide_a_fisheyes_chief_ray() {
    let sys = load_lens("olympus/olympus-m.zuiko-ed-8mm-f1.8-fisheye");
    let stop = sys.stop_index().unwrap();
    let seq = Sequence::forward(&sys, LAMBDA_D_NM);
    let theta = 70f64.to_radians();
    let [x, y] = chief_ray_landing(&sys, LAMBDA_D_NM, theta, 0.0).expect("found at 70°");
    assert!(x.abs() < 1e-9, "x {x}");
    // The ray that lands there crosses the stop's centre and passes every clear aperture.
    let mut hits = Vec::new();
    let found = (0..=SCAN_STEPS).any(|k| {
        let h = -40.0 + 20.0 * k as f64 / SCAN_STEPS as f64;
        hits.clear();
        let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
        r.fate.reached_sensor()
            && hits
                .iter()
                .find(|hit| hit.surface == stop)
                .is_some_and(|hit| hit.position.y.abs() < NEAR_SHARE * stop_opening(&sys))
            && (r.ray.origin.y - y).abs() < NEAR_SHARE * y.abs()
    });
    assert!(
        found,
        "no unvignetted ray through the stop's centre lands near {y}"
    );
}

//! Lights from on axis to well past the edge of the field, on every bundled lens: every ghost
//! that reaches the sensor has an energy, and the plan draws the ghosts that reach the frame —
//! also where the light's own image is vignetted away inside the lens (the sun just out of
//! frame), which once left every ghost with a zero energy share and an empty plan.

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::GridTrace;
use flarebench_sdk::ghost::bounds;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::InterfaceTableSet;
use flarebench_test_support::{library_stems, load_lens};
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, BOUNDS_LAMBDA_NM, DropReason, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// The light's angle as multiples of the half-diagonal field angle.
const FIELD_MULTIPLES: [f64; 6] = [0.0, 0.5, 1.0, 1.25, 1.5, 2.0];
/// The largest angle tried (degrees): a fisheye's doubled field would pass 90°.
const MAX_DEG: f64 = 85.0;
/// The drawn ghosts carry all but the preset's dim budget of the on-frame ghosts' energy; this
/// is the room left for rounding in that sum.
const SUM_SLACK: f64 = 1e-9;

fn bundled() -> Vec<(String, LensSystem)> {
    library_stems()
        .into_iter()
        .map(|stem| {
            let sys = load_lens(&stem);
            (stem, sys)
        })
        .collect()
}

/// The field angle of half the film diagonal (degrees), paraxially.
fn half_field_deg(sys: &LensSystem) -> f64 {
    let efl = analyse(sys, 587.6).unwrap().efl_mm.abs();
    (0.5 * sys.film_width_mm.hypot(sys.film_height_mm) / efl)
        .atan()
        .to_degrees()
}

#[test]
#[ignore = "slow tier: 114 plans of the 19 core lenses at the default preset; by default the \
            Nikon zoom's light just outside its field"]
fn ghosts_that_reach_the_frame_are_drawn_from_the_axis_to_past_the_field() {
    let preset = PlanOptions::for_quality(Quality::Default, None);
    let budget = Quality::Default.dim_budget();
    // (lens, angle) cases whose own image is vignetted away while ghosts are drawn.
    let mut beyond_the_image = Vec::new();
    let mut cases = 0;
    for (stem, sys) in bundled() {
        let frame = Frame::across_film(240, 160, sys.film_width_mm);
        let field = half_field_deg(&sys);
        let tables = InterfaceTableSet::for_system(&sys, BOUNDS_LAMBDA_NM);
        for m in FIELD_MULTIPLES {
            let deg = (m * field).min(MAX_DEG);
            let light = LightSpec::parse(&format!("{deg},90")).unwrap();
            let lp = &plan::plan(&sys, &[light], &frame, &preset).unwrap()[0];
            cases += 1;
            let lit: Vec<f64> = lp
                .ghosts
                .iter()
                .map(|g| g.energy_share)
                .chain(
                    lp.dropped
                        .iter()
                        .filter(|d| d.reason != DropReason::NoLight)
                        .map(|d| d.energy_share),
                )
                .collect();
            for e in &lit {
                assert!(
                    e.is_finite() && *e > 0.0,
                    "{stem} at {deg:.1}°: a ghost with light has energy share {e}"
                );
            }
            let on_frame: f64 = lp.ghosts.iter().map(|g| g.energy_share).sum::<f64>()
                + lp.dropped
                    .iter()
                    .filter(|d| d.reason == DropReason::Dim)
                    .map(|d| d.energy_share)
                    .sum::<f64>();
            if on_frame > 0.0 {
                // Culling weighs each ghost by its energy on the frame, and leaves out at most
                // the budget of the frame's ghost energy.
                assert!(
                    !lp.ghosts.is_empty() && lp.culled_share <= budget + SUM_SLACK,
                    "{stem} at {deg:.1}°: {} ghosts drawn, {} of the frame's ghost energy culled",
                    lp.ghosts.len(),
                    lp.culled_share
                );
            }
            let direct =
                bounds::direct_flux(&sys, &tables, deg.to_radians(), &mut GridTrace::default());
            if direct == 0.0 && !lp.ghosts.is_empty() {
                beyond_the_image.push(format!("{stem} {deg:.1}°"));
            }
        }
    }
    assert!(cases >= 19 * FIELD_MULTIPLES.len());
    // Past the field's edge several lenses vignette their own image away and still flare.
    assert!(
        beyond_the_image.len() >= 5,
        "lights beyond their own image that flare: {beyond_the_image:?}"
    );
}

/// The case a user met: the Nikon zoom at its long end with the light at 9°, 90°, whose own
/// image is vignetted away, renders a flare.
#[test]
fn the_nikon_zoom_flares_for_a_light_just_outside_its_field() {
    let sys = load_lens("nikon-zoom-long");
    let tables = InterfaceTableSet::for_system(&sys, BOUNDS_LAMBDA_NM);
    let direct = bounds::direct_flux(&sys, &tables, 9f64.to_radians(), &mut GridTrace::default());
    assert_eq!(direct, 0.0, "the light's own image is vignetted away at 9°");
    let frame = Frame::across_film(320, 180, sys.film_width_mm);
    let light = LightSpec::parse("9,90").unwrap();
    let preset = PlanOptions::for_quality(Quality::Fast, None);
    let plans = plan::plan(&sys, &[light], &frame, &preset).unwrap();
    assert!(
        plans[0].ghosts.len() > 10,
        "{} drawn",
        plans[0].ghosts.len()
    );
    let (total, dropped) = plans[0].energy();
    assert!(total > 0.0 && dropped < total, "{total:e} {dropped:e}");
    let (img, _) =
        ghosts::render_with(&sys, &Aperture::Circular, frame, &plans, Default::default()).unwrap();
    let lit = img.pixels.iter().filter(|p| p[1] > 0.0).count();
    assert!(
        lit > img.pixels.len() / 100,
        "{lit} of {} pixels lit",
        img.pixels.len()
    );
}

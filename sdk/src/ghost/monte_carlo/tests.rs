//! The Monte-Carlo reference against closed forms: a plane-parallel plate's ghost and direct
//! flux (Fresnel products times the stop's area), its error bar's honesty, reproducibility.

use super::*;
use crate::fresnel;
use crate::system::{Medium, Surface};

/// The plate of `flarebench-test-support` (stop of radius 2 mm at the entrance plane, a
/// 3 mm plate of n = 1.5 without dispersion, uncoated), built here: the sdk's unit tests
/// cannot share the support crate's `LensSystem` type.
fn plate() -> LensSystem {
    let mut sys = LensSystem::new(
        "plate",
        vec![
            Surface::stop(5.0, 2.0),
            Surface::spherical(0.0, 3.0, Medium::Model { nd: 1.5, vd: None }, 10.0),
            Surface::spherical(0.0, 10.0, Medium::Air, 10.0),
            Surface::sensor(15.0),
        ],
    );
    sys.film_width_mm = 20.0;
    sys.film_height_mm = 20.0;
    sys
}

/// The plate's ghost (back face, then front face) at `theta`: every ray crosses the stop at
/// the entrance plane and meets both faces at the same angles, so its flux is
/// `π r² cos θ · T(θ)² R(θ')²` (θ' inside the glass; a face reflects the same from either
/// side at matching angles, and transmits `1 − R`).
fn plate_ghost_flux(theta: f64) -> f64 {
    let n = 1.5;
    let cos_i = theta.cos();
    let cos_t = (1.0 - (theta.sin() / n).powi(2)).sqrt();
    let r = fresnel::unpolarised(1.0, n, cos_i);
    let r_inside = fresnel::unpolarised(n, 1.0, cos_t);
    std::f64::consts::PI * 4.0 * cos_i * (1.0 - r).powi(2) * r_inside.powi(2)
}

/// Closed form against estimate: within this many standard errors (a 4σ miss has odds of
/// 6e-5 for a normal estimate).
const SIGMAS: f64 = 4.0;

fn settings(rays: usize) -> McSettings {
    McSettings {
        rays,
        batches: 16,
        seed: 7,
        pilot: 65,
        outside_weight: 1.0,
    }
}

fn white() -> [McBand; 1] {
    [McBand {
        lambda_nm: 550.0,
        rgb: [1.0; 3],
    }]
}

/// The plate's ghost 2-1 by the Monte-Carlo reference, at light direction `light` (θ, φ,
/// intensity), on a `px × px` frame over the plate's 20 mm film, with `rays` rays.
fn plate_ghost(px: usize, light: (f64, f64, f64), rays: usize) -> McGhost {
    ghost_monte_carlo(
        &plate(),
        &Aperture::Circular,
        &Frame::across_film(px, px, 20.0),
        GhostPath::two(2, 1),
        light,
        &white(),
        &settings(rays),
        None,
    )
    .expect("the plate's ghost has a sequence")
}

#[test]
fn plate_ghost_flux_matches_the_fresnel_product_within_its_error_bar() {
    for theta_deg in [0.0_f64, 20.0] {
        let theta = theta_deg.to_radians();
        let g = plate_ghost(64, (theta, 0.0, 1.0), 200_000);
        let exact = plate_ghost_flux(theta);
        let err = (g.flux.mean - exact).abs();
        assert!(
            err <= SIGMAS * g.flux.std_error,
            "θ = {theta_deg}°: MC {} ± {} against {exact}",
            g.flux.mean,
            g.flux.std_error
        );
        // The error bar is small enough to mean something: under 0.2%.
        assert!(g.flux.relative_error() < 2e-3, "{:?}", g.flux);
    }
}

#[test]
fn plate_direct_flux_matches_the_stop_area_times_two_transmittances() {
    let sys = plate();
    for theta_deg in [0.0_f64, 15.0] {
        let theta = theta_deg.to_radians();
        let seq = Sequence::forward(&sys, 550.0);
        let est = path_flux(&sys, &seq, theta, &settings(100_000));
        let cos_t = (1.0 - (theta.sin() / 1.5).powi(2)).sqrt();
        let t = (1.0 - fresnel::unpolarised(1.0, 1.5, theta.cos()))
            * (1.0 - fresnel::unpolarised(1.5, 1.0, cos_t));
        let exact = std::f64::consts::PI * 4.0 * theta.cos() * t;
        assert!(
            (est.mean - exact).abs() <= SIGMAS * est.std_error,
            "θ = {theta_deg}°: {est:?} against {exact}"
        );
    }
}

#[test]
fn a_wrong_closed_form_is_caught() {
    // The same ghost against the flux with one reflectance left out of the product (the
    // test above must be able to fail): far outside the error bar.
    let g = plate_ghost(64, (0.0, 0.0, 1.0), 50_000);
    let wrong = plate_ghost_flux(0.0) * 1.01;
    assert!((g.flux.mean - wrong).abs() > SIGMAS * g.flux.std_error);
}

#[test]
fn the_plate_ghost_lands_centred_with_the_stop_s_second_moments() {
    // On axis the ghost is the stop's disc (radius 2 mm) on the sensor: centroid at the
    // image centre, second moments r²/4 per axis, none across.
    let g = plate_ghost(100, (0.0, 0.0, 1.0), 200_000);
    let px = 100.0 / 20.0;
    let var = 4.0 / 4.0 * px * px;
    for a in 0..2 {
        assert!(
            (g.centroid_px[a] - 50.0).abs() < 0.05,
            "{:?}",
            g.centroid_px
        );
    }
    assert!(
        (g.moments_px2[0] / var - 1.0).abs() < 3e-3,
        "{:?}",
        g.moments_px2
    );
    assert!(
        (g.moments_px2[2] / var - 1.0).abs() < 3e-3,
        "{:?}",
        g.moments_px2
    );
    assert!(g.moments_px2[1].abs() < 1e-3 * var, "{:?}", g.moments_px2);
}

#[test]
fn the_splatted_image_holds_the_in_frame_flux_and_the_same_seed_gives_the_same_bits() {
    let sys = plate();
    let frame = Frame::across_film(40, 40, 20.0);
    let run = || {
        let mut images = McImages::new(&frame);
        let g = ghost_monte_carlo(
            &sys,
            &Aperture::Circular,
            &frame,
            GhostPath::two(2, 1),
            (0.1, 0.3, 1.0),
            &white(),
            &settings(20_000),
            Some(&mut images),
        )
        .expect("the plate's ghost has a sequence");
        (g, images)
    };
    let (a, ia) = run();
    let (b, ib) = run();
    assert_eq!(a, b);
    // The image's pixels are summed per thread, in an order the scheduling decides.
    for (p, q) in ia.image.pixels.iter().zip(&ib.image.pixels) {
        for c in 0..3 {
            assert!((p[c] - q[c]).abs() <= 1e-5 * p[c].abs().max(1e-12));
        }
    }
    // Each ray's flux goes to the pixel it lands in; this ghost lies well inside the frame.
    let sum = ia.image.sum()[1];
    assert!(
        (sum / a.flux_in_frame.mean - 1.0).abs() < 1e-5,
        "{sum} {:?}",
        a.flux_in_frame
    );
    assert!(ia.relative_noise() > 0.0 && ia.relative_noise() < 0.05);
}

#[test]
fn fewer_rays_than_cells_still_estimate_the_flux_without_bias() {
    // 40 rays a batch over the plate's ~150 active cells: each ray stands for a run of cells.
    for (theta_deg, seed) in [(0.0_f64, 3), (20.0, 4)] {
        let theta = theta_deg.to_radians();
        let g = ghost_monte_carlo(
            &plate(),
            &Aperture::Circular,
            &Frame::across_film(64, 64, 20.0),
            GhostPath::two(2, 1),
            (theta, 0.0, 1.0),
            &white(),
            &McSettings {
                seed,
                ..settings(16 * 40)
            },
            None,
        )
        .expect("the plate's ghost has a sequence");
        assert_eq!(g.strata, Strata::Runs(40), "{} cells", g.cells);
        assert_eq!(g.rays, 16 * 40);
        let exact = plate_ghost_flux(theta);
        assert!(
            (g.flux.mean - exact).abs() <= SIGMAS * g.flux.std_error,
            "θ = {theta_deg}°: {:?} against {exact}",
            g.flux
        );
        assert!(g.flux.relative_error() < 0.03, "{:?}", g.flux);
    }
}

#[test]
fn strata_keep_to_the_rays_and_never_drop_below_one_a_batch() {
    assert_eq!(Strata::for_rays(0, 100), Strata::Runs(1));
    assert_eq!(Strata::for_rays(99, 100), Strata::Runs(99));
    assert_eq!(Strata::for_rays(100, 100), Strata::PerCell(1));
    assert_eq!(Strata::for_rays(899, 100), Strata::PerCell(2));
    assert_eq!(Strata::for_rays(900, 100), Strata::PerCell(3));
    assert_eq!(Strata::Runs(99).rays(100), 99);
    assert_eq!(Strata::Runs(99).rays(10), 99);
    assert_eq!(Strata::PerCell(3).rays(100), 900);
    assert_eq!(Strata::Runs(5).rays(0), 0);
}

#[test]
fn rays_gathered_on_the_frame_keep_every_estimate_unbiased_and_cut_the_in_frame_noise() {
    // The plate's ghost on axis is a 4 mm disc centred on the sensor; a 1.5 mm frame, off
    // centre by the light's tilt, holds a small part of it, so most entry cells land outside.
    let run = |outside_weight: f64, seed: u64| {
        ghost_monte_carlo(
            &plate(),
            &Aperture::Circular,
            &Frame::across_film(16, 16, 1.5),
            GhostPath::two(2, 1),
            (0.0, 0.0, 1.0),
            &white(),
            &McSettings {
                outside_weight,
                seed,
                ..settings(16 * 4000)
            },
            None,
        )
        .expect("the plate's ghost has a sequence")
    };
    let uniform = run(1.0, 5);
    let gathered = run(0.05, 6);
    assert!(matches!(gathered.strata, Strata::Runs(4000)));
    // The whole flux against the closed form, both ways.
    let exact = plate_ghost_flux(0.0);
    for g in [&uniform, &gathered] {
        assert!(
            (g.flux.mean - exact).abs() <= SIGMAS * g.flux.std_error,
            "{:?} against {exact}",
            g.flux
        );
    }
    // The in-frame flux: the frame's share of a uniform disc, (1.5 mm)² over π (2 mm)².
    let in_frame = exact * 1.5 * 1.5 / (std::f64::consts::PI * 4.0);
    for g in [&uniform, &gathered] {
        let f = g.flux_in_frame;
        assert!(
            (f.mean - in_frame).abs() <= SIGMAS * f.std_error,
            "{f:?} against {in_frame}"
        );
    }
    // Gathering is what it is for: the in-frame estimate half as tight again at least (a fifth
    // of the uniform rays land in the frame, four fifths of the gathered: √4 in theory).
    assert!(
        gathered.flux_in_frame.relative_error() * 1.5 < uniform.flux_in_frame.relative_error(),
        "{:?} against {:?}",
        gathered.flux_in_frame,
        uniform.flux_in_frame
    );
}

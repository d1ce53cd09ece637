//! Lenses built for one difficulty each, measured against closed forms or against the
//! independent Monte-Carlo reference.
//!
//! - **Analytic plate**: a 3 mm plate of n = 1.5 behind a 2 mm stop, wide enough that nothing
//!   but the stop limits the beam up to 80°: its two-reflection ghost carries `cos θ · π r² ·
//!   T R R T` and its four-reflection ghost `cos θ · π r² · T R⁴ T` (Fresnel at the internal
//!   angle), in f32 and f64.
//! - **Near-flat**: the plate with its front face of R = 1e7 mm against the flat one: the
//!   same ghost image (the sag differs by 5e-6 mm at the rim), in f32 and f64.
//! - **Near TIR**: a plano-convex lens of n = 1.9 whose back face (R = −8 mm) turns rays
//!   entering above 4.2 mm from the axis back by total internal reflection: rays on both
//!   sides of the critical angle in every ghost; energies against Monte-Carlo.
//! - **Thin air gap**: a doublet whose two inner faces, R = −30 mm both, are 0.01 mm apart:
//!   the ghost between them focuses close to the sensor (a caustic); energies against
//!   Monte-Carlo.
//! - **Tiny and huge radii**: the Heliar scaled by 1e-3 (radii of tens of micrometres) and by
//!   1e3, against itself: the image in pixels is the same and its energy scales with the area.
//! - **Real lenses' caustics**: every ghost of the Heliar (and, in the full suite, the Nikon
//!   zoom) that the renderer draws, its energy against Monte-Carlo.

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::fresnel;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::ghost::bounds;
use flarebench_sdk::ghost::context::{Band, GhostContext, GhostGrid, GhostLight};
use flarebench_sdk::ghost::monte_carlo::McSettings;
use flarebench_sdk::ghost::render::{GhostScratch, render_ghost};
use flarebench_sdk::ghost::{GhostPath, GridTrace};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::trace::InterfaceTableSet;
use flarebench_sdk::{LensSystem, Medium, Surface};
use ghost_raytrace::crosscheck::{Allot, CrosscheckOptions, crosscheck};
use ghost_raytrace::plan::PlanOptions;
use ghost_raytrace::scene::{LightSpec, Quality};

use super::{
    Finding, SuiteOptions, default_plan, difference, frame_of, non_finite, precision_findings,
    render_pair,
};

/// A plate ghost's energy against its closed form (relative): the interface tables (linear in
/// cos θ over 256 entries) and the grid's sampling of the stop's disc.
pub const PLATE_ENERGY_LIMIT: f64 = 2e-3;
/// The near-flat plate's ghost image against the flat one's (relative RMSE).
pub const NEAR_FLAT_LIMIT: f64 = 1e-3;
/// A scaled lens's image (its energy divided by the scale²) against the unscaled one's
/// (relative RMSE).
pub const SCALE_LIMIT: f64 = 2e-3;
/// The scaled lens's image is compared with the lens's own only when its Airy radius is
/// below this many pixels: the ghosts' triangles are grown to the Airy disc where they
/// collapse, and at a thousandth of the size (a 36 µm film) the disc spans 13 pixels of a
/// 160-pixel frame and spreads the ghosts (and some of their light off the frame): the image
/// differs, rightly; the flux before the frame crops it does not.
pub const AIRY_PX_SCALE_IMAGE: f64 = 0.5;
/// A ghost's energy from the renderer against the Monte-Carlo estimate (relative), for ghosts
/// holding at least [`MC_MIN_SHARE`] of the light's ghost energy; the limit widens to
/// [`MC_SIGMAS`] standard errors where the estimate is noisier than that.
pub const MC_ENERGY_LIMIT: f64 = 0.03;
/// Ghosts below this share of the drawn ghost energy are not compared with Monte-Carlo.
pub const MC_MIN_SHARE: f64 = 0.01;
/// Standard errors of the Monte-Carlo estimate a ghost's energy may lie from it.
pub const MC_SIGMAS: f64 = 4.0;

/// The plate: a stop of radius 2 mm, 5 mm of air, 3 mm of n = 1.5 (no dispersion), 10 mm of
/// air, the sensor; every rim wide enough (250 mm) that only the stop limits the beam at 80°.
pub fn plate(front_radius: f64) -> LensSystem {
    let mut sys = LensSystem::new(
        "plate",
        vec![
            Surface::stop(5.0, 2.0),
            Surface::spherical(
                front_radius,
                3.0,
                Medium::Model { nd: 1.5, vd: None },
                250.0,
            ),
            Surface::spherical(0.0, 10.0, Medium::Air, 250.0),
            Surface::sensor(250.0),
        ],
    );
    sys.film_width_mm = 20.0;
    sys.film_height_mm = 20.0;
    sys
}

/// The plate's ghost through `path` at `theta`, one band at 550 nm of unit colour, on a grid
/// of `n²` rays, into a square frame of `px²` pixels and `film` mm centred on the axis.
fn plate_ghost(
    sys: &LensSystem,
    path: GhostPath,
    theta: f64,
    film: f64,
    trace_f64: bool,
) -> Option<HdrImage> {
    const PX: usize = 256;
    const GRID: usize = 64;
    let tables = InterfaceTableSet::for_system(sys, 550.0);
    let mut scratch = GridTrace::default();
    let reference = bounds::reference_flux(sys, &tables, &mut scratch);
    let b = bounds::precise(sys, path, &tables, theta, reference, &mut scratch)?;
    let frame = Frame {
        width: PX,
        height: PX,
        film_width_mm: film,
        film_height_mm: film,
    };
    let ctx = GhostContext {
        system: sys,
        aperture: &Aperture::Circular,
        frame,
        stop_radius: stop_opening(sys),
        f_number: 2.8,
        trace_f64,
    };
    let band = Band::new(sys, 550.0, [1.0, 1.0, 1.0]);
    let mut img = HdrImage::new(PX, PX);
    render_ghost(
        &ctx,
        &GhostGrid {
            path,
            bounds: &b,
            n: GRID,
            light: GhostLight {
                theta,
                phi: 0.0,
                irradiance: 1.0,
            },
        },
        &[band.as_ref()],
        &mut GhostScratch::default(),
        &mut img,
    );
    Some(img)
}

/// The plate's closed forms at `theta`: the ghost's energy after `2 + 2k` reflections
/// (`k` extra round trips), and its centre's height on the sensor (mm).
fn plate_closed_form(theta: f64, extra_round_trips: i32) -> (f64, f64) {
    let n = 1.5;
    let sin_t = theta.sin() / n;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let t_in = 1.0 - fresnel::unpolarised(1.0, n, theta.cos());
    let r = fresnel::unpolarised(n, 1.0, cos_t);
    let t_out = 1.0 - r;
    let energy =
        theta.cos() * std::f64::consts::PI * 4.0 * t_in * r.powi(2 + 2 * extra_round_trips) * t_out;
    let passes = 3.0 + 2.0 * f64::from(extra_round_trips);
    let y = theta.tan() * 15.0 + passes * 3.0 * sin_t / cos_t;
    (energy, y)
}

fn check_plate(quick: bool) -> Vec<Finding> {
    let mut out = Vec::new();
    let sys = plate(0.0);
    let angles: &[f64] = if quick {
        &[0.0, 45.0, 80.0]
    } else {
        &[0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0]
    };
    for (path, trips) in [(GhostPath::two(2, 1), 0), (GhostPath::four(2, 1, 2, 1), 1)] {
        for &deg in angles {
            let theta = f64::to_radians(deg);
            let (want, y) = plate_closed_form(theta, trips);
            // A frame that holds the ghost (and the axis): the disc is 4 mm across.
            let film = 2.0 * (y.abs() + 4.0);
            for trace_f64 in [false, true] {
                let case = format!("{path} θ {deg}° {}", if trace_f64 { "f64" } else { "f32" });
                match plate_ghost(&sys, path, theta, film, trace_f64) {
                    Some(img) => {
                        let got = img.sum()[1];
                        out.push(Finding::measured(
                            "plate-energy",
                            "plate",
                            case,
                            if non_finite(&img) > 0 {
                                f64::NAN
                            } else {
                                (got / want - 1.0).abs()
                            },
                            PLATE_ENERGY_LIMIT,
                            format!(
                                "energy {got:.6e} against T R^{} T = {want:.6e}",
                                2 + 2 * trips
                            ),
                        ));
                    }
                    None => out.push(Finding::failed(
                        "plate-energy",
                        "plate",
                        case,
                        "the bounds search found no light".into(),
                    )),
                }
            }
        }
    }
    out
}

fn check_near_flat() -> Vec<Finding> {
    let mut out = Vec::new();
    let (flat, near) = (plate(0.0), plate(1e7));
    let path = GhostPath::two(2, 1);
    for deg in [0.0, 30.0] {
        let theta = f64::to_radians(deg);
        let film = 2.0 * (plate_closed_form(theta, 0).1.abs() + 4.0);
        for trace_f64 in [false, true] {
            let case = format!("R 1e7 against flat, θ {deg}° {}", precision(trace_f64));
            match (
                plate_ghost(&flat, path, theta, film, trace_f64),
                plate_ghost(&near, path, theta, film, trace_f64),
            ) {
                (Some(a), Some(b)) => {
                    let (rmse, _) = difference(&b, &a);
                    let bad = non_finite(&b);
                    out.push(Finding::measured(
                        "near-flat",
                        "plate",
                        case,
                        if bad > 0 { f64::NAN } else { rmse },
                        NEAR_FLAT_LIMIT,
                        "relative RMSE of the ghost 2-1 with the front face at R = 1e7 mm \
                         against flat"
                            .into(),
                    ));
                }
                _ => out.push(Finding::failed(
                    "near-flat",
                    "plate",
                    case,
                    "the bounds search found no light".into(),
                )),
            }
        }
    }
    out
}

fn precision(trace_f64: bool) -> &'static str {
    if trace_f64 { "f64" } else { "f32" }
}

/// `system` with its back focal distance set so the sensor sits at the paraxial focus.
fn focused(mut system: LensSystem) -> LensSystem {
    let last = system.surfaces.len() - 2;
    if let Ok(p) = analyse(&system, 587.5618) {
        system.surfaces[last].thickness -= p.focus_error_mm;
    }
    system
}

/// A plano-convex lens of n = 1.9 whose back face (R = −8 mm) meets rays entering above
/// 4.2 mm from the axis beyond the critical angle (31.8°).
pub fn near_tir_lens() -> LensSystem {
    let mut sys = LensSystem::new(
        "near-tir",
        vec![
            Surface::stop(2.0, 6.5),
            Surface::spherical(
                0.0,
                6.0,
                Medium::Model {
                    nd: 1.9,
                    vd: Some(25.0),
                },
                7.0,
            ),
            Surface::spherical(-8.0, 8.0, Medium::Air, 7.0),
            Surface::sensor(20.0),
        ],
    );
    sys.film_width_mm = 24.0;
    sys.film_height_mm = 24.0;
    focused(sys)
}

/// A crown–flint doublet whose two inner faces (R = −30 mm both) are 0.01 mm apart.
pub fn thin_gap_lens() -> LensSystem {
    let mut sys = LensSystem::new(
        "thin-air-gap",
        vec![
            Surface::stop(4.0, 6.0),
            Surface::spherical(
                40.0,
                5.0,
                Medium::Model {
                    nd: 1.52,
                    vd: Some(64.0),
                },
                10.0,
            ),
            Surface::spherical(-30.0, 0.01, Medium::Air, 10.0),
            Surface::spherical(
                -30.0,
                2.0,
                Medium::Model {
                    nd: 1.72,
                    vd: Some(29.0),
                },
                10.0,
            ),
            Surface::spherical(-120.0, 60.0, Medium::Air, 10.0),
            Surface::sensor(30.0),
        ],
    );
    sys.film_width_mm = 24.0;
    sys.film_height_mm = 16.0;
    focused(sys)
}

/// `system` scaled by `k`: every length, and the aspheric coefficients as the lengths demand.
pub fn scaled(system: &LensSystem, k: f64) -> LensSystem {
    let mut s = system.clone();
    for surf in &mut s.surfaces {
        surf.curvature /= k;
        surf.thickness *= k;
        surf.semi_diameter *= k;
        // The term a_i r^(2i+2) keeps its sag (a length) when a_i scales by k^(-1-2i).
        for (i, a) in surf.aspheric.iter_mut().enumerate() {
            *a *= k.powi(-1 - 2 * i as i32);
        }
    }
    s.film_width_mm *= k;
    s.film_height_mm *= k;
    s.name = format!("{} ×{k:e}", system.name);
    s
}

fn check_scale(heliar: &LensSystem, options: SuiteOptions) -> Vec<Finding> {
    let mut out = Vec::new();
    let plan = default_plan();
    let light = (10.0, 30.0);
    let base = match render_pair(
        heliar,
        &Aperture::Circular,
        frame_of(heliar, options.width),
        light.0,
        light.1,
        &plan,
    ) {
        Ok(p) => p,
        Err(e) => {
            out.push(Finding::failed("scale", &heliar.name, "×1".into(), e));
            return out;
        }
    };
    let f_number = analyse(heliar, 550.0).map_or(f64::NAN, |p| p.f_number);
    for k in [1e-3, 1e3] {
        let sys = scaled(heliar, k);
        let case = format!("×{k:e}, θ {}°", light.0);
        match render_pair(
            &sys,
            &Aperture::Circular,
            frame_of(&sys, options.width),
            light.0,
            light.1,
            &plan,
        ) {
            Ok(pair) => {
                out.extend(precision_findings(&heliar.name, &case, &pair));
                let flux = pair.f64_flux / (k * k);
                out.push(Finding::measured(
                    "scale-flux",
                    &heliar.name,
                    case.clone(),
                    (flux / base.f64_flux - 1.0).abs(),
                    SCALE_LIMIT,
                    format!(
                        "the ghosts' flux over the scale² against the lens's own \
                         ({flux:.6e} against {:.6e}); {} and {} ghosts drawn",
                        base.f64_flux, pair.ghosts, base.ghosts
                    ),
                ));
                // The image is the same in pixels only where diffraction does not show: the
                // Airy disc (1.22 λ N) does not scale with the lens.
                let airy_px = 1.22 * 550e-6 * f_number * frame_of(&sys, options.width).width as f64
                    / sys.film_width_mm;
                if airy_px > AIRY_PX_SCALE_IMAGE {
                    continue;
                }
                let mut unscaled = pair.f64_image.clone();
                let inv = (1.0 / (k * k)) as f32;
                for p in &mut unscaled.pixels {
                    for v in p.iter_mut() {
                        *v *= inv;
                    }
                }
                let (rmse, energy) = difference(&unscaled, &base.f64_image);
                out.push(Finding::measured(
                    "scale-image",
                    &heliar.name,
                    case,
                    rmse,
                    SCALE_LIMIT,
                    format!(
                        "relative RMSE of the scaled lens's image over the scale² against \
                         the lens's own (energy {energy:+.1e}; Airy radius {airy_px:.2} px)"
                    ),
                ));
            }
            Err(e) => out.push(Finding::failed("scale", &heliar.name, case, e)),
        }
    }
    out
}

/// The Heliar's ghosts with its four-reflection paths (every one the energy bound keeps, none
/// culled) at 10°, in f32 and f64.
fn check_four_reflections(heliar: &LensSystem, options: SuiteOptions) -> Vec<Finding> {
    // Every ghost with light, however dim (the presets cull the four-reflection ones).
    let plan = PlanOptions {
        reflections: ReflectionOrder::Four,
        cull: false,
        ..default_plan()
    };
    let case = "four reflections, θ 10°".to_string();
    match render_pair(
        heliar,
        &Aperture::Circular,
        frame_of(heliar, options.width),
        10.0,
        30.0,
        &plan,
    ) {
        Ok(pair) => precision_findings(&heliar.name, &case, &pair),
        Err(e) => vec![Finding::failed("non-finite", &heliar.name, case, e)],
    }
}

/// Every ghost of `system` lit at `theta_deg` the renderer draws, its energy against the
/// Monte-Carlo estimate: the worst relative difference among the ghosts holding at least
/// [`MC_MIN_SHARE`] of the drawn energy (each against its own limit, the larger of
/// [`MC_ENERGY_LIMIT`] and [`MC_SIGMAS`] standard errors).
pub fn check_against_mc(
    check: &'static str,
    system: &LensSystem,
    theta_deg: f64,
    options: SuiteOptions,
) -> Vec<Finding> {
    let case = format!("θ {theta_deg}°");
    let light = LightSpec {
        theta_deg,
        phi_deg: 30.0,
        ..LightSpec::parse("0,0").expect("a valid light")
    };
    let rays = if options.quick { 1 << 15 } else { 1 << 17 };
    let opts = CrosscheckOptions {
        mc: McSettings {
            rays,
            batches: 8,
            ..McSettings::default()
        },
        quality: Quality::Default,
        reference: false,
        ghosts: Vec::new(),
        allot: Allot::Even,
    };
    let frame = frame_of(system, options.width.min(160));
    let cc = match crosscheck(system, &Aperture::Circular, frame, &light, &opts) {
        Ok(cc) => cc,
        Err(e) => return vec![Finding::failed(check, &system.name, case, e.to_string())],
    };
    let drawn: f64 = cc
        .ghosts
        .iter()
        .filter_map(|g| g.renderer.map(|r| r.energy))
        .sum();
    // (ratio − 1 over its limit, ghost, ratio, σ) of the worst ghost.
    let mut worst: Option<(f64, String, f64, f64)> = None;
    let mut compared = 0;
    for g in &cc.ghosts {
        let Some(r) = g.renderer else { continue };
        if r.energy < MC_MIN_SHARE * drawn || g.mc_energy.mean <= 0.0 {
            continue;
        }
        compared += 1;
        let ratio = r.energy / g.mc_energy.mean;
        let sigma = g.mc_energy.relative_error();
        let limit = MC_ENERGY_LIMIT.max(MC_SIGMAS * sigma);
        let score = (ratio - 1.0).abs() / limit;
        if worst.as_ref().is_none_or(|w| score > w.0) {
            worst = Some((score, g.path.clone(), ratio, sigma));
        }
    }
    let bad = non_finite(&cc.images.renderer) + non_finite(&cc.images.mc.image);
    let mut out = vec![Finding::measured(
        "non-finite",
        &system.name,
        format!("{case}, renderer and Monte-Carlo"),
        bad as f64,
        0.0,
        "NaN/Inf values in the renderer's and the Monte-Carlo images".into(),
    )];
    out.push(match worst {
        Some((score, path, ratio, sigma)) => Finding::measured(
            check,
            &system.name,
            case,
            score,
            1.0,
            format!(
                "worst of {compared} ghosts over {:.0}% of the drawn energy: {path} at {ratio:.4} \
                 of Monte-Carlo (±{:.2}%), over its limit (the larger of {:.0}% and {MC_SIGMAS}σ)",
                100.0 * MC_MIN_SHARE,
                100.0 * sigma,
                100.0 * MC_ENERGY_LIMIT
            ),
        ),
        None => Finding::failed(check, &system.name, case, "no ghost drawn".into()),
    });
    out
}

/// The synthetic lenses, named, for `flarebench stability --export` (to reproduce a finding
/// with the other commands).
pub fn lenses() -> Vec<LensSystem> {
    let mut near_flat = plate(1e7);
    near_flat.name = "plate-near-flat".into();
    vec![plate(0.0), near_flat, near_tir_lens(), thin_gap_lens()]
}

/// Every synthetic check (the real lenses' caustics load the bundled Heliar and Nikon zoom).
pub fn check_all(options: SuiteOptions) -> Vec<Finding> {
    let mut out = check_plate(options.quick);
    out.extend(check_near_flat());
    for sys in [near_tir_lens(), thin_gap_lens()] {
        let frame = frame_of(&sys, options.width);
        for deg in [0.0, 10.0] {
            let case = format!("θ {deg}°");
            match render_pair(&sys, &Aperture::Circular, frame, deg, 30.0, &default_plan()) {
                Ok(pair) => out.extend(precision_findings(&sys.name, &case, &pair)),
                Err(e) => out.push(Finding::failed("non-finite", &sys.name, case, e)),
            }
        }
        out.extend(check_against_mc("ghost-energy-mc", &sys, 5.0, options));
    }
    match crate::lens_library::load("heliar-tronnier", true) {
        Ok(heliar) => {
            out.extend(check_scale(&heliar.system, options));
            out.extend(check_four_reflections(&heliar.system, options));
            out.extend(check_against_mc(
                "ghost-energy-mc",
                &heliar.system,
                10.0,
                options,
            ));
        }
        Err(e) => out.push(Finding::failed(
            "scale",
            "heliar-tronnier",
            String::new(),
            format!("{e:#}"),
        )),
    }
    if !options.quick {
        match crate::lens_library::load("nikon-zoom-short", true) {
            Ok(nikon) => out.extend(check_against_mc(
                "ghost-energy-mc",
                &nikon.system,
                5.0,
                options,
            )),
            Err(e) => out.push(Finding::failed(
                "ghost-energy-mc",
                "nikon-zoom-short",
                String::new(),
                format!("{e:#}"),
            )),
        }
    }
    out
}

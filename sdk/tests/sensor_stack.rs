//! The sensor stack (`system::SensorStack`, docs/physics.md §9): plates in front of the sensor
//! and the sensor's own reflectance — the focus kept, the ghosts enumerated and traced, their
//! throughput against the closed forms of a plane-parallel plate, the file format's round trip
//! and its errors, and nothing changed without a stack.

use std::f64::consts::PI;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::coating::Coating;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::bounds::{self};
use flarebench_sdk::ghost::context::{Band, GhostContext, GhostGrid, GhostLight};
use flarebench_sdk::ghost::render::{GhostScratch, render_ghost};
use flarebench_sdk::ghost::{
    GhostPath, GridTrace, enumerate_ghosts, reflecting_surfaces, trace_grid, trace_grid_f64,
};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::{parse_olf_xml, write_olf_xml, write_xml};
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::rect::Rect;
use flarebench_sdk::system::{Plate, SensorStack, SpectralReflectance};
use flarebench_sdk::trace::{Fate, InterfaceTableSet, PathError, Ray, Sequence};
use flarebench_sdk::{LensSystem, Medium, Surface};
use flarebench_test_support::load_lens;
use glam::DVec3;

/// Per-ray throughput of the f64 tracers against the closed forms (relative): rounding only.
const F64_THROUGHPUT_TOL: f64 = 1e-12;
/// The same for the f32 batches, whose weights are f32 products of f32 table entries (about
/// 20 factors of 6e-8 each).
const F32_THROUGHPUT_TOL: f64 = 1e-6;
/// A plate ghost's image energy against T R R T of the stop's disc at oblique incidence: the
/// interface tables (linear over 256 entries) and the f32 grid, as for the lens plate's
/// ghost in `ghost_render.rs` (`PLATE_GHOST_ENERGY_TOL`).
const PLATE_IMAGE_ENERGY_TOL: f64 = 2e-3;
/// The paraxial focus with and without the stack (mm): rounding of the sums along the axis.
const FOCUS_TOL_MM: f64 = 1e-9;

/// MgF₂ (n = 1.38) a quarter wave thick at 550 nm.
fn mgf2() -> Coating {
    Coating::SingleLayer {
        design_wavelength_nm: 550.0,
        index: 1.38,
    }
}

/// Plate A: 1.5 mm of n = 1.5 (no dispersion), MgF₂ on both faces, 0.5 mm before plate B:
/// 0.5 mm of n = 1.5, bare, 1 mm before the sensor, which reflects 8% at 500 nm and 4% from
/// 600 nm on.
fn stack() -> SensorStack {
    let plate = |thickness: f64, gap: f64, coating: Coating| Plate {
        medium: Medium::Model { nd: 1.5, vd: None },
        thickness,
        gap,
        semi_diameter: 12.0,
        front_coating: coating.clone(),
        back_coating: coating,
    };
    SensorStack::new(
        vec![plate(1.5, 0.5, mgf2()), plate(0.5, 1.0, Coating::None)],
        SpectralReflectance::new(vec![(500.0, 0.08), (600.0, 0.04)]).unwrap(),
    )
}

/// A stop of radius 2 mm 20 mm in front of the sensor, no lens: light at normal incidence
/// meets every face of the stack at normal incidence, so every ray of a ghost has its closed
/// form. Surfaces: 0 stop, 1–2 plate A, 3–4 plate B, 5 sensor.
fn afocal() -> LensSystem {
    let mut sys = LensSystem::new(
        "stop",
        vec![Surface::stop(20.0, 2.0), Surface::sensor(15.0)],
    );
    sys.film_width_mm = 20.0;
    sys.film_height_mm = 20.0;
    sys.with_sensor_stack(Some(stack())).unwrap()
}

/// Normal-incidence reflectance of a quarter-wave layer n₁ between n₀ and n₂ at its design
/// wavelength: ((n₀n₂ − n₁²)/(n₀n₂ + n₁²))², the same from either side.
fn quarter_wave_r(n0: f64, n1: f64, n2: f64) -> f64 {
    ((n0 * n2 - n1 * n1) / (n0 * n2 + n1 * n1)).powi(2)
}

/// Each ghost's throughput over the direct light's, per ray at normal incidence and 550 nm:
/// qa for plate A's coated faces, rb = ((n − 1)/(n + 1))² for plate B's bare ones, rs the
/// sensor's reflectance (0.08 + (0.04 − 0.08)/2 at 550 nm). Every transmission the ghost shares
/// with the direct light cancels.
fn closed_forms() -> Vec<(GhostPath, f64)> {
    let qa = quarter_wave_r(1.0, 1.38, 1.5);
    let rb: f64 = ((1.5 - 1.0) / (1.5 + 1.0_f64)).powi(2);
    let rs = 0.06;
    vec![
        // Plate A's double reflection (back face, then front face, both from inside).
        (GhostPath::two(2, 1), qa * qa),
        // Plate B's.
        (GhostPath::two(4, 3), rb * rb),
        // Plate B's front face, then plate A's back face from the air between them.
        (GhostPath::two(3, 2), rb * qa),
        // The sensor, then plate B's back face from the air behind it.
        (GhostPath::two(5, 4), rs * rb),
        // The sensor, then plate A's front face from inside plate A: back through plate B and
        // plate A's back face, and forward through them again.
        (
            GhostPath::two(5, 1),
            rs * qa * (1.0 - qa).powi(2) * (1.0 - rb).powi(4),
        ),
    ]
}

#[test]
fn plate_and_sensor_ghosts_match_their_closed_forms_ray_by_ray() {
    let sys = afocal();
    let lambda = 550.0;
    let direct = Sequence::forward(&sys, lambda);
    let tables = InterfaceTableSet::for_system(&sys, lambda);
    let stop = stop_opening(&sys);
    let rect = Rect {
        x0: -1.8,
        y0: -1.8,
        x1: 1.8,
        y1: 1.8,
    };
    for (path, want) in closed_forms() {
        let seq = Sequence::ghost_path(&sys, lambda, &path).unwrap();
        // The scalar f64 tracer, ray by ray over the stop.
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.3, -1.7), (-1.2, 1.1)] {
            let ray = Ray::new(DVec3::new(x, y, 0.0), DVec3::Z);
            let (g, d) = (seq.trace(&ray), direct.trace(&ray));
            assert_eq!(g.fate, Fate::Sensor, "{path}");
            let got = g.throughput / d.throughput;
            assert!(
                (got / want - 1.0).abs() < F64_THROUGHPUT_TOL,
                "{path} at ({x}, {y}): {got} vs {want}"
            );
        }
        // The batches, from the interface tables, in f64 and f32: every vertex inside the
        // stop.
        let tabled = seq.clone().with_tables_from(&tables);
        let direct_tabled = direct.clone().with_tables_from(&tables);
        for f32_batch in [false, true] {
            let (mut gg, mut gd) = (GridTrace::default(), GridTrace::default());
            if f32_batch {
                trace_grid(&tabled.cast::<f32>(), 0.0, rect, 9, stop, &mut gg);
                trace_grid(&direct_tabled.cast::<f32>(), 0.0, rect, 9, stop, &mut gd);
            } else {
                trace_grid_f64(&tabled, 0.0, rect, 9, stop, &mut gg);
                trace_grid_f64(&direct_tabled, 0.0, rect, 9, stop, &mut gd);
            }
            let tol = if f32_batch {
                F32_THROUGHPUT_TOL
            } else {
                // The grid hands its weights on as f32.
                F32_THROUGHPUT_TOL / 10.0
            };
            let mut inside = 0;
            for v in 0..81 {
                if gg.max_rel[v] >= 1.0 || !gg.completed[v] {
                    continue;
                }
                inside += 1;
                let got = f64::from(gg.weight[v]) / f64::from(gd.weight[v]);
                assert!(
                    (got / want - 1.0).abs() < tol,
                    "{path}, f32 {f32_batch}, vertex {v}: {got} vs {want}"
                );
            }
            assert!(inside > 30, "{path}: {inside} vertices inside the stop");
        }
    }
}

/// The stack's plate A seen at 0°, 5° and 15°: its ghost 2-1 is the stop's disc dimmed by
/// T R R T with the coating's reflectances at the angle in the glass, and plate B's two
/// transmissions — the same closed form as a lens plate's ghost, through the whole renderer.
#[test]
fn the_stack_s_plate_ghost_image_carries_its_closed_form_energy() {
    let sys = afocal();
    let path = GhostPath::two(2, 1);
    let px = 400;
    let frame = Frame {
        width: px,
        height: px,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_height_mm,
    };
    let mut scratch = GridTrace::default();
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let reference = bounds::reference_flux(&sys, &tables, &mut scratch);
    let n: f64 = 1.5;
    for deg in [0.0f64, 5.0, 15.0] {
        let theta = deg.to_radians();
        let b = bounds::precise(&sys, path, &tables, theta, reference, &mut scratch)
            .expect("the ghost reaches the sensor");
        let ctx = GhostContext {
            system: &sys,
            aperture: &Aperture::Circular,
            frame,
            stop_radius: stop_opening(&sys),
            f_number: 2.8,
            trace_f64: false,
        };
        let ghost = GhostGrid {
            path,
            bounds: &b,
            n: 64,
            light: GhostLight {
                theta,
                phi: 0.0,
                irradiance: 1.0,
            },
        };
        let band = Band::new(&sys, 550.0, [1.0, 1.0, 1.0]);
        let mut img = HdrImage::new(px, px);
        render_ghost(
            &ctx,
            &ghost,
            &[band.as_ref()],
            &mut GhostScratch::default(),
            &mut img,
        );
        let (ci, ct) = (theta.cos(), (1.0 - (theta.sin() / n).powi(2)).sqrt());
        let coated = |n1: f64, n2: f64, c: f64| mgf2().reflectance(n1, n2, c, 550.0, true);
        let bare = |n1: f64, n2: f64, c: f64| Coating::None.reflectance(n1, n2, c, 550.0, true);
        let t_in = 1.0 - coated(1.0, n, ci);
        let r_back = mgf2().reflectance(n, 1.0, ct, 550.0, true);
        let r_front = mgf2().reflectance(n, 1.0, ct, 550.0, false);
        let t_out = 1.0 - r_back;
        let plate_b = (1.0 - bare(1.0, n, ci)) * (1.0 - bare(n, 1.0, ct));
        let want = ci * PI * 4.0 * t_in * r_back * r_front * t_out * plate_b;
        let got = img.sum()[1];
        assert!(
            (got / want - 1.0).abs() < PLATE_IMAGE_ENERGY_TOL,
            "{deg}°: energy {got} vs {want}"
        );
    }
}

fn heliar_with_stack() -> (LensSystem, LensSystem) {
    let bare = load_lens("heliar-tronnier");
    let with = bare.with_sensor_stack(Some(stack())).unwrap();
    (bare, with)
}

/// A plate of thickness t and index n moves the focus back by t (1 − 1/n): the stack adds
/// that to the back distance, so the sensor stays where it was relative to the focus.
#[test]
fn the_stack_keeps_the_sensor_at_the_lens_s_focus() {
    let (bare, with) = heliar_with_stack();
    let shift = 2.0 * (1.0 - 1.0 / 1.5);
    assert!((with.total_track() - bare.total_track() - shift).abs() < FOCUS_TOL_MM);
    for lambda in [486.1327, 587.5618, 656.2725] {
        let (a, b) = (
            analyse(&bare, lambda).unwrap(),
            analyse(&with, lambda).unwrap(),
        );
        // The plates have no dispersion here: the same at every wavelength.
        assert!(
            (a.focus_error_mm - b.focus_error_mm).abs() < FOCUS_TOL_MM,
            "{lambda} nm: {} vs {}",
            a.focus_error_mm,
            b.focus_error_mm
        );
        assert!((a.efl_mm - b.efl_mm).abs() < FOCUS_TOL_MM);
    }
    // Without the shift the sensor would sit 2/3 mm in front of where it was.
    let mut unshifted = with.clone();
    let last_lens = with.sensor_stack_start().unwrap() - 1;
    unshifted.surfaces[last_lens].thickness -= shift;
    let p = analyse(&unshifted, 587.5618).unwrap();
    let q = analyse(&bare, 587.5618).unwrap();
    assert!((p.focus_error_mm - q.focus_error_mm + shift).abs() < 1e-6);
}

#[test]
fn stack_ghosts_are_enumerated_and_only_the_sensor_s_arrival_side_reflects() {
    let (bare, with) = heliar_with_stack();
    assert_eq!(enumerate_ghosts(&bare).len(), 28);
    // 8 lens surfaces, 4 plate faces and the sensor.
    let r = reflecting_surfaces(&with);
    assert_eq!(r, vec![0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11, 12, 13]);
    let ghosts = enumerate_ghosts(&with);
    assert_eq!(ghosts.len(), 13 * 12 / 2);
    let sensor = with.sensor_index();
    assert_eq!(sensor, 13);
    assert_eq!(ghosts.iter().filter(|g| g.first() == sensor).count(), 12);
    // The sensor reflects the light arriving at it, never the light going back.
    let ok = |p: GhostPath| Sequence::ghost_path(&with, 550.0, &p);
    assert!(ok(GhostPath::two(13, 6)).is_ok());
    assert!(ok(GhostPath::four(13, 6, 13, 9)).is_ok());
    assert_eq!(
        ok(GhostPath::four(12, 6, 13, 13)).unwrap_err(),
        PathError::NotReflecting(13)
    );
    assert_eq!(
        ok(GhostPath::two(12, 13)).unwrap_err(),
        PathError::NotReflecting(13)
    );
    // Without a stack the sensor does not reflect.
    assert_eq!(
        Sequence::ghost_path(&bare, 550.0, &GhostPath::two(9, 6)).unwrap_err(),
        PathError::NotReflecting(9)
    );
    // The sensor's reflection uses its own reflectance, not Fresnel (air on both sides).
    let seq = ok(GhostPath::two(13, 12)).unwrap();
    let step = seq
        .steps
        .iter()
        .find(|s| s.surface == 13 && s.interaction == flarebench_sdk::trace::Interaction::Reflect)
        .unwrap();
    assert_eq!(seq.reflectance(step, 1.0), 0.06);
    assert_eq!(seq.reflectance(step, 0.3), 0.06);
}

#[test]
fn a_lens_with_a_stack_round_trips_through_our_xml_and_loses_it_for_openlensflare() {
    let (bare, mut with) = heliar_with_stack();
    // Every kind of coating and of glass on the plates.
    let mut s = with.sensor_stack.clone().unwrap();
    s.plates[1].front_coating = Coating::Stack(vec![
        flarebench_sdk::coating::CoatingLayer {
            index: 1.38,
            thickness_nm: 99.6,
        },
        flarebench_sdk::coating::CoatingLayer {
            index: 2.05,
            thickness_nm: 130.0,
        },
    ]);
    let bk7 = flarebench_sdk::GlassCatalog::bundled()
        .find("N-BK7")
        .unwrap();
    s.plates[0].medium = Medium::Glass {
        name: bk7.canonical_name(),
        dispersion: bk7.dispersion.clone(),
    };
    with = with.with_sensor_stack(Some(s)).unwrap();
    let text = write_xml(&with);
    assert!(text.contains("<sensorStack>"), "{text}");
    let back = parse_olf_xml(&text, "stack.xml").unwrap();
    assert_eq!(back.system, with);
    assert_eq!(write_xml(&back.system), text);
    // The elements are the bare lens's: the file reads as that lens in OpenLensFlare.
    let olf = write_olf_xml(&with);
    assert!(!olf.contains("sensorStack"));
    let read = parse_olf_xml(&olf, "olf.xml").unwrap().system;
    assert_eq!(read.surfaces.len(), bare.surfaces.len());
    assert_eq!(read.total_track(), bare.total_track());
    assert!(read.sensor_stack.is_none());
    // Without a stack nothing is written, so the lens files and their fingerprints are as
    // before.
    assert!(!write_xml(&bare).contains("sensorStack"));
    assert_eq!(with.with_sensor_stack(None).unwrap(), bare);
}

/// The file the errors below edit: the Heliar with the stack.
fn stack_file() -> String {
    write_xml(&heliar_with_stack().1)
}

/// Reads `text` and returns the error's display, asserting its line holds `needle`.
fn error_at(text: &str, needle: &str) -> String {
    let e = parse_olf_xml(text, "bad.xml").unwrap_err();
    let line = text.lines().nth(e.line - 1).unwrap_or("");
    assert!(line.contains(needle), "{e} points at `{line}`");
    e.to_string()
}

#[test]
fn bad_stacks_are_errors_naming_the_file_line_and_field() {
    let good = stack_file();
    let bad = good.replacen(
        "<thickness>1.5</thickness>",
        "<thickness>-1.5</thickness>",
        1,
    );
    let e = error_at(&bad, "<thickness>-1.5");
    assert!(
        e.starts_with("bad.xml:") && e.contains("field `thickness`"),
        "{e}"
    );
    assert!(e.contains("plate 1: must be > 0 mm, got -1.5"), "{e}");

    let bad = good.replacen(
        "<reflectance>0.04</reflectance>",
        "<reflectance>1.4</reflectance>",
        1,
    );
    let e = error_at(&bad, "<reflectance>1.4");
    assert!(
        e.contains("field `reflectance`") && e.contains("point 2"),
        "{e}"
    );

    let bad = good.replacen(
        "<wavelength>600</wavelength>",
        "<wavelength>450</wavelength>",
        1,
    );
    let e = error_at(&bad, "<wavelength>450");
    assert!(e.contains("wavelengths must increase"), "{e}");

    let bad = good.replacen("<gap>1</gap>", "<gap>90</gap>", 1);
    let e = error_at(&bad, "<sensorStack>");
    assert!(
        e.contains("field `sensorStack`") && e.contains("mm long"),
        "{e}"
    );

    let start = good.find("<sensorReflectance>").unwrap();
    let end = good.find("</sensorReflectance>").unwrap() + "</sensorReflectance>".len();
    let bad = format!("{}{}", &good[..start], &good[end..]);
    let e = error_at(&bad, "<sensorStack>");
    assert!(e.contains("needs <sensorReflectance>"), "{e}");

    let bad = good.replacen("<refractiveIndex>1.5</refractiveIndex>", "", 1);
    let e = error_at(&bad, "<plate>");
    assert!(e.contains("plate 1 needs its glass"), "{e}");

    let bad = good.replacen(
        "<coatingIor>1.38</coatingIor></front>",
        "<coatingIor>-2</coatingIor></front>",
        1,
    );
    let e = parse_olf_xml(&bad, "bad.xml").unwrap_err().to_string();
    assert!(
        e.contains("field `front`") && e.contains("coating index must be > 0"),
        "{e}"
    );
}

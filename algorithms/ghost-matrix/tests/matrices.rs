//! The ghost matrices against independent references: a plate's ghost in closed form, and the
//! sdk's real ray tracer in the paraxial limit along every ghost path of the Heliar.

use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::{Scene, SceneLight};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::{LightSpectrum, SpectralSampling};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::paraxial::{analyse, stop_opening};
use flarebench_sdk::raster::rasterize;
use flarebench_sdk::trace::{Ray, Sequence};
use flarebench_test_support::{load_lens, plate};
use ghost_matrix::matrix::{self, path_matrices};
use ghost_matrix::{ghost_mesh, outline, polygon_area};

fn heliar() -> LensSystem {
    load_lens("heliar-tronnier")
}

/// A plate ghost's magnification, centre and area scale against their closed forms: f64
/// rounding of a chain of flat-surface matrices.
const PLATE_MATRIX_TOL: f64 = 1e-12;

/// A plate ghost's throughput against T R…R T (relative): f64 rounding of the Fresnel
/// coefficients and their product.
const PLATE_THROUGHPUT_REL_TOL: f64 = 1e-9;

#[test]
fn a_plate_ghost_is_the_stop_shifted_by_two_extra_passes() {
    let g = matrix::ghost(&plate(), GhostPath::two(2, 1), 550.0).unwrap();
    // Flat surfaces: no magnification; the ghost crosses the plate three times, so its centre
    // is (5 + 3·3/1.5 + 10) tan θ = 21 tan θ (the direct image: 17 tan θ).
    assert!((g.magnification - 1.0).abs() < PLATE_MATRIX_TOL);
    assert!(
        (g.centre_per_tan - 21.0).abs() < PLATE_MATRIX_TOL,
        "{}",
        g.centre_per_tan
    );
    assert!((g.entrance_area_scale - 1.0).abs() < PLATE_MATRIX_TOL);
    // In, reflect at the back, reflect at the front, out: T R R T with R = (0.5/2.5)².
    let r = 0.04;
    let want = (1.0 - r) * r * r * (1.0 - r);
    assert!(
        (g.throughput / want - 1.0).abs() < PLATE_THROUGHPUT_REL_TOL,
        "{} vs {want}",
        g.throughput
    );
}

/// The chain of matrices takes a four-reflection path as it is: the plate's 2-1-2-1 ghost
/// crosses the plate five times, (5 + 5·3/1.5 + 10) tan θ = 25 tan θ, and carries T R⁴ T.
#[test]
fn a_plate_four_reflection_ghost_is_two_more_passes_further() {
    let g = matrix::ghost(&plate(), GhostPath::four(2, 1, 2, 1), 550.0).unwrap();
    assert!((g.magnification - 1.0).abs() < PLATE_MATRIX_TOL);
    assert!(
        (g.centre_per_tan - 25.0).abs() < PLATE_MATRIX_TOL,
        "{}",
        g.centre_per_tan
    );
    assert!((g.entrance_area_scale - 1.0).abs() < PLATE_MATRIX_TOL);
    let r: f64 = 0.04;
    let want = (1.0 - r) * r.powi(4) * (1.0 - r);
    assert!(
        (g.throughput / want - 1.0).abs() < PLATE_THROUGHPUT_REL_TOL,
        "{} vs {want}",
        g.throughput
    );
    // An invalid order is no ghost.
    assert!(matrix::ghost(&plate(), GhostPath::four(2, 1, 1, 0), 550.0).is_none());
}

/// Heights and angles small enough that third-order terms are below 1e-6 relative.
const H_MM: f64 = 1e-3;
const U_RAD: f64 = 1e-5;
/// Agreement of finite differences of the real trace with the matrices, relative to
/// 1 + |value| (measured: 3.1e-8 at worst over the Heliar's 28 paths; the tolerance leaves
/// room for the cubic terms).
const PARAXIAL_TOL: f64 = 1e-5;
/// The matrices' throughput against a ray's Fresnel throughput 1e-3 mm off axis (relative):
/// the real ray's departure from normal incidence.
const NEAR_AXIS_THROUGHPUT_REL_TOL: f64 = 1e-6;

#[test]
fn every_heliar_ghost_matrix_matches_the_real_trace_in_the_paraxial_limit() {
    let sys = heliar();
    let stop = sys.stop_index().unwrap();
    let lambda = 550.0;
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for path in enumerate_ghosts(&sys) {
        let seq = Sequence::ghost(&sys, lambda, path.first(), path.second()).unwrap();
        let m = path_matrices(&seq).expect("every ghost path crosses the stop");
        let mut hits = Vec::new();
        let mut trace = |theta: f64, h: f64| {
            hits.clear();
            let r = seq.trace_with_hits(&Ray::collimated(theta, 0.0, h), &mut hits);
            let at_stop = hits
                .iter()
                .rev()
                .find(|x| x.surface == stop)
                .map(|x| x.position.y);
            (r.completed, r.ray.origin.y, at_stop, r.throughput)
        };
        let (ok1, y1, s1, t1) = trace(0.0, H_MM);
        let (ok2, y2, s2, _) = trace(0.0, -H_MM);
        let (ok3, y3, s3, _) = trace(U_RAD, 0.0);
        if !(ok1 && ok2 && ok3) {
            continue;
        }
        let mut close = |got: f64, want: f64| {
            let e = (got - want).abs() / (1.0 + want.abs());
            worst = worst.max(e);
            e <= PARAXIAL_TOL
        };
        let a_sensor = (y1 - y2) / (2.0 * H_MM);
        let a_stop = (s1.unwrap() - s2.unwrap()) / (2.0 * H_MM);
        let u = U_RAD.tan();
        assert!(
            close(m.to_sensor.a, a_sensor),
            "{path}: A {} vs {a_sensor}",
            m.to_sensor.a
        );
        assert!(
            close(m.to_stop.a, a_stop),
            "{path}: A_stop {} vs {a_stop}",
            m.to_stop.a
        );
        assert!(
            close(m.to_sensor.b, y3 / u),
            "{path}: B {} vs {}",
            m.to_sensor.b,
            y3 / u
        );
        assert!(close(m.to_stop.b, s3.unwrap() / u), "{path}: B_stop");
        // Near the axis the real ray's Fresnel throughput is the normal-incidence one.
        let with_tables = Sequence::ghost(&sys, lambda, path.first(), path.second())
            .unwrap()
            .with_interface_tables();
        let tp = path_matrices(&with_tables).unwrap().throughput;
        assert!(
            (tp / t1 - 1.0).abs() < NEAR_AXIS_THROUGHPUT_REL_TOL,
            "{path}: throughput {tp} vs {t1}"
        );
        checked += 1;
    }
    eprintln!("{checked} paths checked, worst relative difference {worst:.2e}");
    assert!(
        checked >= 20,
        "only {checked} of the Heliar's 28 ghost paths were checked"
    );
}

/// −1/C of the forward path's matrix against the paraxial EFL (relative): f64 rounding of two
/// formulations of the same paraxial trace.
const EFL_REL_TOL: f64 = 1e-9;

#[test]
fn the_forward_path_has_the_lens_focal_length() {
    let sys = heliar();
    let seq = Sequence::forward(&sys, 587.5618);
    // The forward path has no reflection; its matrix's C is −1/EFL.
    let m = ghost_matrix_forward(&seq);
    let efl = analyse(&sys, 587.5618).unwrap().efl_mm;
    assert!(
        (-1.0 / m - efl).abs() < EFL_REL_TOL * efl,
        "{} vs {efl}",
        -1.0 / m
    );
}

fn ghost_matrix_forward(seq: &Sequence<f64>) -> f64 {
    path_matrices(seq).unwrap().to_sensor.c
}

/// The rasterizer conserves energy to f32 rounding of the pixel sums.
const ENERGY_TOL: f64 = 1e-4;

#[test]
fn the_mesh_carries_each_ghosts_flux() {
    let sys = plate();
    let path = GhostPath::two(2, 1);
    let frame = Frame {
        width: 200,
        height: 200,
        film_width_mm: 20.0,
        film_height_mm: 20.0,
    };
    let scene = Scene {
        lights: vec![SceneLight {
            theta_deg: 3.0,
            phi_deg: 40.0,
            intensity: 2.0,
            spectrum: LightSpectrum::D65,
        }],
        frame,
        aperture: Aperture::Iris {
            blades: 5,
            rotation_rad: 0.1,
            roundness: 0.4,
        },
    };
    let (mesh, drawn) = ghost_mesh(&sys, &[path], &scene, 1).unwrap();
    assert_eq!(drawn, 1);
    let mut img = HdrImage::new(200, 200);
    let pos: Vec<[f32; 2]> = mesh.vertices.iter().map(|v| [v.x, v.y]).collect();
    let rgb: Vec<[f32; 3]> = mesh.vertices.iter().map(|v| v.rgb).collect();
    rasterize(&mut img, &pos, &rgb, &mesh.triangles, |&c| c);
    // One band: the sdk's weight of the single 380–780 nm bin for D65.
    let sampling = SpectralSampling::new(1, LightSpectrum::D65).unwrap();
    let w = sampling.weights()[0];
    let lambda = sampling.wavelengths_nm()[0];
    let r = stop_opening(&sys);
    let area = polygon_area(&outline(&scene.aperture)) * r * r;
    let g = matrix::ghost(&sys, path, lambda).unwrap();
    let want = 2.0 * 3f64.to_radians().cos() * area * g.throughput;
    for (got, wc) in img.sum().into_iter().zip(w) {
        let want = want * wc as f64;
        assert!((got / want - 1.0).abs() < ENERGY_TOL, "{got} vs {want}");
    }
}

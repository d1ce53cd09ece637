//! The sequential f64 tracer against an independent optical design code (optiland), ray by ray
//! and surface by surface, and the paraxial EFL/BFL against the same code.
//!
//! The oracle files `tests/data/oracle/<lens>.json` are made offline by
//! `tests/data/oracle/generate.py` (see the README there for the conventions and for how the
//! oracle's own precision was measured). Each holds the prescription the oracle traced, the
//! rays (as `Ray::collimated` arguments or as an explicit origin and direction), and after
//! every surface the oracle's global intersection point and direction cosines, plus a 50-digit
//! reference of the same. This test loads `lenses/<lens>.xml` with `read_lens`, checks it is
//! the prescription the oracle traced, traces every ray with `Sequence::forward` at the d line
//! and compares.

use std::path::{Path, PathBuf};

use flarebench_sdk::LensSystem;
use flarebench_sdk::SurfaceKind;
use flarebench_sdk::io::read_lens;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::{Fate, Hit, Ray, Sequence};
use glam::DVec3;
use serde::Deserialize;

/// Agreement required of every intersection (mm) and direction cosine. The oracle itself is
/// within 1.1e-13 mm and 6e-15 of a 50-digit reference (README), so this leaves a margin of
/// about 1e4 for the difference in formulation between the two f64 codes.
const TOL: f64 = 1e-9;
/// The d line, where every medium has index nd in the oracle.
const LAMBDA_D_NM: f64 = 587.5618;
/// A surface's curvature against 1/R of the oracle's radius (relative): f64 rounding of one
/// division.
const CURVATURE_REL_TOL: f64 = 1e-15;
/// A medium's index at the d line against the oracle's nd: f64 rounding.
const INDEX_TOL: f64 = 1e-15;
/// The lens file's sensor against the oracle's paraxial focus (mm): the file writes it with
/// fewer digits.
const FILE_SENSOR_TOL_MM: f64 = 1e-5;
/// Vertex positions against the oracle's (mm): f64 rounding of the summed thicknesses.
const VERTEX_Z_TOL_MM: f64 = 1e-12;
/// A collimated start ray against the generator's, same formula (mm): libm rounding.
const START_ORIGIN_TOL_MM: f64 = 1e-14;
/// A collimated start ray's direction cosines against the generator's: libm rounding.
const START_DIRECTION_TOL: f64 = 1e-15;

#[derive(Deserialize)]
struct OracleFile {
    lens: String,
    lens_file: String,
    oracle: OracleInfo,
    wavelength_nm: f64,
    prescription: Vec<PrescribedSurface>,
    vertex_z_mm: Vec<f64>,
    /// `file_sensor`: the sensor of the lens file; `paraxial_focus`: a plane at
    /// `image_plane_z_mm` (the oracle's paraxial focus), where our sensor is moved.
    image_plane: String,
    image_plane_z_mm: f64,
    paraxial: OracleParaxial,
    rays: Vec<OracleRay>,
}

#[derive(Deserialize)]
struct OracleInfo {
    name: String,
    version: String,
}

#[derive(Deserialize)]
struct PrescribedSurface {
    kind: String,
    radius_mm: f64,
    thickness_mm: f64,
    n_after: f64,
}

#[derive(Deserialize)]
struct OracleParaxial {
    efl_mm: f64,
    bfl_mm: f64,
}

#[derive(Deserialize)]
struct OracleRay {
    kind: String,
    field_deg: f64,
    #[serde(default)]
    azimuth_deg: f64,
    #[serde(default)]
    height_mm: f64,
    origin: [f64; 3],
    dir: [f64; 3],
    hits: Vec<OracleHit>,
}

#[derive(Deserialize)]
struct OracleHit {
    surface: usize,
    position: [f64; 3],
    direction: [f64; 3],
    position_ref50: [f64; 3],
    direction_ref50: [f64; 3],
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn load_oracle(lens: &str) -> OracleFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/oracle")
        .join(format!("{lens}.json"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let file: OracleFile = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("cannot parse {}: {e}", path.display()));
    assert_eq!(file.lens, lens);
    assert_eq!(file.wavelength_nm, LAMBDA_D_NM);
    file
}

fn max_abs_diff(a: DVec3, b: [f64; 3]) -> f64 {
    (a - DVec3::from_array(b)).abs().max_element()
}

/// The lens file, checked against the prescription the oracle traced, with the sensor moved to
/// the oracle's image plane where the oracle chose its own.
fn load_system(oracle: &OracleFile) -> LensSystem {
    let path = repo_root().join(&oracle.lens_file);
    let loaded = read_lens(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut system = loaded.system;
    let pres = &oracle.prescription;
    assert_eq!(
        system.surfaces.len(),
        pres.len(),
        "{}: surface count differs from the oracle's prescription",
        oracle.lens
    );
    let n = system.indices(LAMBDA_D_NM);
    let sensor = system.sensor_index();
    for (i, (s, p)) in system.surfaces.iter().zip(pres).enumerate() {
        let kind = match s.kind {
            SurfaceKind::Refracting => "refracting",
            SurfaceKind::ApertureStop => "stop",
            SurfaceKind::Sensor => "sensor",
        };
        let ctx = format!("{} surface {i}", oracle.lens);
        assert_eq!(kind, p.kind, "{ctx}: kind");
        let c = if p.radius_mm == 0.0 {
            0.0
        } else {
            1.0 / p.radius_mm
        };
        assert!(
            (s.curvature - c).abs() <= CURVATURE_REL_TOL * c.abs(),
            "{ctx}: curvature {} in the lens file, 1/{} in the oracle",
            s.curvature,
            p.radius_mm
        );
        assert!(s.conic == 0.0 && !s.is_aspheric(), "{ctx}: not spherical");
        if i < sensor {
            assert!(
                (n[i + 1] - p.n_after).abs() <= INDEX_TOL,
                "{ctx}: index {} at the d line, oracle {}",
                n[i + 1],
                p.n_after
            );
        }
        let moved = oracle.image_plane == "paraxial_focus" && i + 1 == sensor;
        if i < sensor && !moved {
            assert_eq!(s.thickness, p.thickness_mm, "{ctx}: thickness");
        }
    }
    let last = sensor - 1;
    match oracle.image_plane.as_str() {
        "file_sensor" => {}
        "paraxial_focus" => {
            // Our lens file also puts its sensor at the paraxial focus, written with fewer
            // digits; the oracle's plane is stated exactly in the JSON, so trace to that plane.
            let z_last = system.vertex_z()[last];
            let file_sensor = system.vertex_z()[sensor];
            assert!(
                (file_sensor - oracle.image_plane_z_mm).abs() < FILE_SENSOR_TOL_MM,
                "{}: the lens file's sensor z {file_sensor} is not at the paraxial focus {}",
                oracle.lens,
                oracle.image_plane_z_mm
            );
            system.surfaces[last].thickness = oracle.image_plane_z_mm - z_last;
        }
        other => panic!("unknown image_plane {other}"),
    }
    let z = system.vertex_z();
    for (i, (a, b)) in z.iter().zip(&oracle.vertex_z_mm).enumerate() {
        assert!(
            (a - b).abs() <= VERTEX_Z_TOL_MM,
            "{}: vertex {i} at z = {a}, oracle {b}",
            oracle.lens
        );
    }
    assert!((z[sensor] - oracle.image_plane_z_mm).abs() <= VERTEX_Z_TOL_MM);
    system
}

fn start_ray(r: &OracleRay, ctx: &str) -> Ray {
    match r.kind.as_str() {
        "collimated" => {
            let ray = Ray::collimated(
                r.field_deg.to_radians(),
                r.azimuth_deg.to_radians(),
                r.height_mm,
            );
            // The generator evaluated the same formula; only libm rounding may differ.
            assert!(
                max_abs_diff(ray.origin, r.origin) <= START_ORIGIN_TOL_MM,
                "{ctx}: origin"
            );
            assert!(
                max_abs_diff(ray.dir, r.dir) <= START_DIRECTION_TOL,
                "{ctx}: direction"
            );
            ray
        }
        "skew" => Ray {
            origin: DVec3::from_array(r.origin),
            dir: DVec3::from_array(r.dir),
        },
        other => panic!("{ctx}: unknown ray kind {other}"),
    }
}

/// The largest deviation seen, and where.
#[derive(Debug, Default)]
struct Worst {
    value: f64,
    at: String,
}

impl Worst {
    fn see(&mut self, value: f64, at: impl FnOnce() -> String) {
        // NaN must count as a failure, not be skipped by `>`.
        if value.is_nan() || value > self.value {
            self.value = value;
            self.at = at();
        }
    }
}

#[derive(Debug, Default)]
struct Deviations {
    position: Worst,
    direction: Worst,
    position_ref50: Worst,
    direction_ref50: Worst,
}

/// Traces every ray of the oracle file through `system` and returns the worst deviations
/// from the oracle and from the 50-digit reference.
fn compare_rays(oracle: &OracleFile, system: &LensSystem) -> Deviations {
    let seq = Sequence::forward(system, LAMBDA_D_NM);
    let mut dev = Deviations::default();
    let mut hits: Vec<Hit> = Vec::new();
    for (j, r) in oracle.rays.iter().enumerate() {
        let ctx = match r.kind.as_str() {
            "collimated" => format!(
                "{} ray {j} (collimated: field {}°, azimuth {}°, height {} mm)",
                oracle.lens, r.field_deg, r.azimuth_deg, r.height_mm
            ),
            _ => format!(
                "{} ray {j} ({}: field {}°, origin {:?})",
                oracle.lens, r.kind, r.field_deg, r.origin
            ),
        };
        let ray = start_ray(r, &ctx);
        hits.clear();
        let result = seq.trace_with_hits(&ray, &mut hits);
        assert!(
            result.completed && matches!(result.fate, Fate::Sensor | Fate::Vignetted { .. }),
            "{ctx}: {} (the oracle traced it to the image plane)",
            result.fate
        );
        assert_eq!(hits.len(), r.hits.len(), "{ctx}: number of surfaces");
        for (h, o) in hits.iter().zip(&r.hits) {
            assert_eq!(h.surface, o.surface, "{ctx}: surface order");
            let at = || format!("{ctx}, surface {}", o.surface);
            dev.position.see(max_abs_diff(h.position, o.position), at);
            dev.direction
                .see(max_abs_diff(h.direction, o.direction), at);
            dev.position_ref50
                .see(max_abs_diff(h.position, o.position_ref50), at);
            dev.direction_ref50
                .see(max_abs_diff(h.direction, o.direction_ref50), at);
        }
    }
    dev
}

fn check_lens(lens: &str) {
    let oracle = load_oracle(lens);
    let system = load_system(&oracle);
    let dev = compare_rays(&oracle, &system);
    let total_hits: usize = oracle.rays.iter().map(|r| r.hits.len()).sum();
    println!(
        "{lens}: {} rays, {total_hits} hits vs {} {}\n  \
         worst position  {:.3e} mm at {}\n  worst direction {:.3e} at {}\n  \
         vs 50-digit reference: position {:.3e} mm, direction {:.3e}",
        oracle.rays.len(),
        oracle.oracle.name,
        oracle.oracle.version,
        dev.position.value,
        dev.position.at,
        dev.direction.value,
        dev.direction.at,
        dev.position_ref50.value,
        dev.direction_ref50.value,
    );
    for (what, w) in [
        ("position (mm) vs oracle", &dev.position),
        ("direction vs oracle", &dev.direction),
        ("position (mm) vs 50-digit reference", &dev.position_ref50),
        ("direction vs 50-digit reference", &dev.direction_ref50),
    ] {
        assert!(
            w.value <= TOL,
            "{lens}: worst {what} {:.3e} > {TOL:e} at {}",
            w.value,
            w.at
        );
    }

    let par = analyse(&system, LAMBDA_D_NM).expect("paraxial analysis");
    let (efl, bfl) = (oracle.paraxial.efl_mm, oracle.paraxial.bfl_mm);
    println!(
        "  EFL {:.12} mm (oracle {efl:.12}, Δ {:.1e}), BFL {:.12} mm (oracle {bfl:.12}, Δ {:.1e})",
        par.efl_mm,
        par.efl_mm - efl,
        par.bfl_mm,
        par.bfl_mm - bfl
    );
    assert!(
        (par.efl_mm - efl).abs() <= TOL * efl.abs().max(1.0),
        "{lens}: EFL {} vs oracle {efl}",
        par.efl_mm
    );
    assert!(
        (par.bfl_mm - bfl).abs() <= TOL * bfl.abs().max(1.0),
        "{lens}: BFL {} vs oracle {bfl}",
        par.bfl_mm
    );
}

#[test]
fn heliar_tronnier_matches_oracle() {
    check_lens("heliar-tronnier");
}

#[test]
fn nikon_zoom_short_matches_oracle() {
    check_lens("nikon-zoom-short");
}

#[test]
fn canon_zoom_short_matches_oracle() {
    check_lens("canon-zoom-short");
}

#[test]
fn double_gauss_50mm_matches_oracle() {
    check_lens("double-gauss-50mm");
}

/// The comparison has teeth: a prescription error far below anything visible (one radius
/// changed by 1 part in a million) is caught at the tolerance used above.
#[test]
fn a_tiny_prescription_change_is_detected() {
    let oracle = load_oracle("heliar-tronnier");
    let mut system = load_system(&oracle);
    system.surfaces[2].curvature *= 1.0 + 1e-6;
    let dev = compare_rays(&oracle, &system);
    assert!(
        dev.position.value > 10.0 * TOL && dev.direction.value > 10.0 * TOL,
        "a radius change of 1e-6 went unnoticed: {dev:?}"
    );
}

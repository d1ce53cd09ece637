//! End-to-end tests of the `flarebench` binary: real output, real exit codes.

use crate::common;

use common::{flarebench, json, temp_dir};
use std::path::PathBuf;

/// Paraxial figures from `info` against values quoted to 3 or 4 decimals (mm).
const QUOTED_FIGURE_TOL_MM: f64 = 1e-3;
/// The f-number against the stop's f/22: f64 rounding.
const F_NUMBER_TOL: f64 = 1e-9;
/// x of a meridional ray at the sensor (mm): f64 rounding.
const MERIDIONAL_X_TOL_MM: f64 = 1e-12;
/// A ray traced at azimuth 90° against the one at 0° turned (mm): f64 rounding of the two
/// traces.
const ROTATION_TOL_MM: f64 = 1e-9;

/// Writes `text` to `name` in a fresh directory; the directory goes when the `TempDir` does.
fn temp_file(name: &str, text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = temp_dir("cli");
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

#[test]
fn info_json_gives_paraxial_data_and_surfaces() {
    let v = json(&["info", "heliar-tronnier", "--json"]);
    assert!(
        (v["efl_mm"].as_f64().unwrap() - 99.2358).abs() < QUOTED_FIGURE_TOL_MM,
        "{v}"
    );
    for key in [
        "bfl_mm",
        "f_number",
        "entrance_pupil_diameter_mm",
        "total_track_mm",
    ] {
        assert!(v[key].as_f64().is_some(), "missing {key}");
    }
    assert!(
        (v["f_number"].as_f64().unwrap() - 22.0).abs() < F_NUMBER_TOL,
        "the stop closes to f/22"
    );
    assert!((v["total_track_mm"].as_f64().unwrap() - 114.077).abs() < QUOTED_FIGURE_TOL_MM);
    let surfaces = v["surfaces"].as_array().unwrap();
    assert_eq!(surfaces.len(), 10);
    assert_eq!(surfaces[5]["kind"], "stop");
    assert_eq!(surfaces[9]["kind"], "sensor");
}

#[test]
fn info_follows_the_wavelength() {
    let d = json(&["info", "heliar-tronnier", "--json"]);
    let f = json(&[
        "info",
        "heliar-tronnier",
        "--json",
        "--wavelength-nm",
        "486.1327",
    ]);
    let (ed, ef) = (d["efl_mm"].as_f64().unwrap(), f["efl_mm"].as_f64().unwrap());
    // Glass indices rise toward the blue, so the focal length shortens.
    assert!(ef < ed - 0.05, "EFL at F {ef} vs d {ed}");
    assert_eq!(f["wavelength_nm"].as_f64().unwrap(), 486.1327);
}

#[test]
fn info_table_shows_the_prescription() {
    let out = flarebench(&["info", "double-gauss-50mm"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("effective focal length"), "{text}");
    assert!(text.contains("50.35"), "{text}");
    assert!(text.contains("stop"));
}

#[test]
fn trace_reaches_the_sensor_on_axis() {
    let v = json(&[
        "trace",
        "heliar-tronnier",
        "--field-deg",
        "0",
        "--height-mm",
        "1",
        "--json",
    ]);
    assert_eq!(v["fate"], "sensor");
    assert!(v["fate_surface"].is_null());
    let hits = v["hits"].as_array().unwrap();
    assert_eq!(hits.len(), 10);
    assert!(v["x_mm"].as_f64().unwrap().abs() < MERIDIONAL_X_TOL_MM);
    // A ray 1 mm off axis crosses near focus: the sensor is 1.54 mm behind the paraxial focus,
    // so it lands at about −1 · 1.54/81.3 mm (plus spherical aberration), i.e. near −0.02 mm.
    let y = v["y_mm"].as_f64().unwrap();
    assert!(y < 0.0 && y > -0.05, "y = {y}");
}

#[test]
fn trace_reports_vignetting_and_still_gives_the_landing_point() {
    // The Heliar's stop at f/22 has a working radius of about 2.05 mm: a 6 mm ray is blocked.
    let v = json(&[
        "trace",
        "heliar-tronnier",
        "--field-deg",
        "0",
        "--height-mm",
        "6",
        "--json",
    ]);
    assert_eq!(v["fate"], "vignetted");
    assert_eq!(v["fate_surface"], 5);
    assert!(v["x_mm"].is_number() && v["y_mm"].is_number());
}

#[test]
fn trace_azimuth_rotates_the_landing_point() {
    let a = json(&[
        "trace",
        "nikon-zoom-short",
        "--field-deg",
        "5",
        "--height-mm",
        "2",
        "--json",
    ]);
    let b = json(&[
        "trace",
        "nikon-zoom-short",
        "--field-deg",
        "5",
        "--height-mm",
        "2",
        "--azimuth-deg",
        "90",
        "--json",
    ]);
    let (ya, xb) = (a["y_mm"].as_f64().unwrap(), b["x_mm"].as_f64().unwrap());
    assert!(
        (ya + xb).abs() < ROTATION_TOL_MM,
        "rotation by 90° maps y to −x: {ya} vs {xb}"
    );
}

#[test]
fn a_lens_path_works_like_a_name() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../lenses/cooke-triplet-25mm.xml"
    );
    let v = json(&["info", path, "--json"]);
    assert!((v["efl_mm"].as_f64().unwrap() - 24.9907).abs() < QUOTED_FIGURE_TOL_MM);
}

#[test]
fn a_bad_file_gives_file_line_and_field_and_no_panic() {
    let (_dir, p) = temp_file(
        "bad.xml",
        "<opticalSystem>\n  <elements>\n    <element>\n      <type>lensSpherical</type>\n      <radius>abc</radius>\n",
    );
    let out = flarebench(&["info", p.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("bad.xml:"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn an_unknown_lens_points_to_the_listing_of_the_library() {
    let out = flarebench(&["info", "no-such-lens"]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("no lens file `no-such-lens`") && err.contains("`flarebench lenses` lists"),
        "{err}"
    );
}

#[test]
fn out_of_range_arguments_are_refused() {
    let out = flarebench(&[
        "trace",
        "heliar-tronnier",
        "--field-deg",
        "95",
        "--height-mm",
        "1",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--field-deg"));
    let out = flarebench(&["info", "heliar-tronnier", "--wavelength-nm", "5"]);
    assert!(!out.status.success());
}

/// Output into a pipe whose reader has gone (`flarebench info … | head -1`) ends the process
/// quietly instead of panicking on the failed write.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_output_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = common::command()
        .args(["info", "nikon-zoom-short"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    // Close the reading end before the program writes.
    drop(child.stdout.take());
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    child.wait().unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
}

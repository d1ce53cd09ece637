//! End-to-end tests of Zemax, PBRT and FlareSim files on the command line: `convert` to XML,
//! `info` and `trace` reading them directly, `--config`, `--pbrt-convention`,
//! `--lens-aperture` and `--lenient-apertures`.

use crate::common;

use common::{flarebench, json};

/// EFL against a catalogue's nominal focal length (mm).
const CATALOGUE_EFL_TOL_MM: f64 = 0.01;
/// EFL against optiland's: both codes use refractiveindex.info's glass formulas (measured
/// agreement ~1e-12 mm, `sdk/tests/zemax_pbrt.rs`).
const SAME_GLASS_DATA_MM: f64 = 1e-6;
/// Entrance pupil diameter against the configuration's stated EPD (mm): f64 rounding.
const EPD_TOL_MM: f64 = 1e-12;
/// EFL of the 100 mm pbrt table against twice the 50 mm table's 3-decimal header (mm).
const SCALED_PBRT_HEADER_EFL_TOL_MM: f64 = 2e-3;

/// The hand-worked singlet's entrance pupil against its closed form (the stop's diameter):
/// f64 rounding of the paraxial products and of the f/4 setting (measured ≤ 4e-15 mm).
const CLOSED_FORM_MM: f64 = 1e-9;
/// A stated focal length of FlareSim's library against the paraxial EFL: the issue's
/// measure, 1% (the AF Nikkor 85 mm f/1.4D: 85.0001 mm, `sdk/tests/flaresim.rs`).
const STATED_FOCAL_REL: f64 = 0.01;

fn data(file: &str) -> String {
    let dir = if file.ends_with(".dat") {
        "pbrt"
    } else if file.ends_with(".lens") {
        "flaresim"
    } else {
        "zemax"
    };
    format!("{}/../tests/data/{dir}/{file}", env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(tag: &str) -> tempfile::TempDir {
    common::temp_dir(&format!("convert-{tag}"))
}

#[test]
fn a_converted_zemax_lens_has_the_same_paraxial_data_as_the_original() {
    let tmp = temp_dir("same");
    let dir = tmp.path();
    for file in ["ol_lens1.zmx", "ol_lens_thorlabs_iso_8859_1.zmx"] {
        let out = dir.join(file.replace(".zmx", ".xml"));
        let run = flarebench(&["convert", &data(file), "-o", out.to_str().unwrap()]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let said = String::from_utf8(run.stdout).unwrap();
        assert!(
            said.starts_with(&format!("wrote {}", out.display())),
            "{said}"
        );
        let zmx = json(&["info", &data(file), "--json"]);
        let xml = json(&["info", out.to_str().unwrap(), "--json"]);
        for key in [
            "efl_mm",
            "bfl_mm",
            "entrance_pupil_diameter_mm",
            "wavelength_nm",
            "primary_wavelength_nm",
        ] {
            assert_eq!(zmx[key], xml[key], "{file}: {key}");
        }
        assert_eq!(zmx["surfaces"], xml["surfaces"], "{file}");
    }
    // The Thorlabs asphere's paraxial data default to its design wavelength.
    let v = json(&["info", &data("ol_lens_thorlabs_iso_8859_1.zmx"), "--json"]);
    assert_eq!(v["wavelength_nm"], 780.0);
    // Thorlabs AL1815: f = 15 mm at 780 nm.
    assert!(
        (v["efl_mm"].as_f64().unwrap() - 15.0).abs() < CATALOGUE_EFL_TOL_MM,
        "{v}"
    );
    tmp.close().unwrap();
}

#[test]
fn convert_prints_what_it_approximated() {
    let tmp = temp_dir("warn");
    let dir = tmp.path();
    let out = dir.join("edmund.xml");
    let run = flarebench(&[
        "convert",
        &data("ol_lens2.zmx"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success());
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(
        err.contains("warning: ") && err.contains("ol_lens2.zmx:34:3: the stop is on SURF 1"),
        "{err}"
    );
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(
        written.contains("a flat aperture stop is inserted"),
        "{written}"
    );
    assert!(written.contains("<primaryWavelength>587.6</primaryWavelength>"));
    // --quiet prints nothing, still writes.
    std::fs::remove_file(&out).unwrap();
    let run = flarebench(&[
        "convert",
        "-q",
        &data("ol_lens2.zmx"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success() && run.stderr.is_empty() && run.stdout.is_empty());
    assert!(out.is_file());
    // Only XML is written.
    let run = flarebench(&["convert", &data("ol_lens2.zmx"), "-o", "lens.zmx"]);
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("must end in .xml"));
    tmp.close().unwrap();
}

#[test]
fn refused_files_give_file_line_and_no_output() {
    let tmp = temp_dir("refused");
    let dir = tmp.path();
    let out = dir.join("mirror.xml");
    let run = flarebench(&[
        "convert",
        &data("ro_HoO-V2C18Ex27.zmx"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(
        err.contains("ro_HoO-V2C18Ex27.zmx:134:8: field `GLAS`: SURF 4 is a mirror"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
    assert!(!out.exists());
    tmp.close().unwrap();
}

#[test]
fn config_selects_a_zemax_configuration() {
    let file = data("fb_cooke_3config.zmx");
    // optiland 0.6.3 on ol_lens1.zmx with configuration 2's values set by hand (see
    // sdk/tests/zemax_pbrt.rs): 24.069300780076663 mm.
    let v = json(&["info", &file, "--config", "2", "--json"]);
    assert!((v["efl_mm"].as_f64().unwrap() - 24.069300780076663).abs() < SAME_GLASS_DATA_MM);
    assert!((v["entrance_pupil_diameter_mm"].as_f64().unwrap() - 7.5).abs() < EPD_TOL_MM);
    let run = flarebench(&["info", &file, "--config", "9"]);
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("configurations 1 to 3"));
    // The same option on trace and convert.
    let t = json(&[
        "trace",
        &file,
        "--config",
        "3",
        "--field-deg",
        "0",
        "--height-mm",
        "1",
        "--json",
    ]);
    assert_eq!(t["fate"], "sensor");
    let tmp = temp_dir("config");
    let dir = tmp.path();
    let out = dir.join("third.xml");
    let run = flarebench(&[
        "convert",
        &file,
        "--config",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success());
    let v = json(&["info", out.to_str().unwrap(), "--json"]);
    assert!((v["efl_mm"].as_f64().unwrap() - 23.13284498748535).abs() < SAME_GLASS_DATA_MM);
    tmp.close().unwrap();
}

#[test]
fn pbrt_convention_can_be_chosen() {
    let file = data("dgauss.dat");
    let detected = json(&["info", &file, "--json"]);
    let explicit = json(&[
        "info",
        &file,
        "--pbrt-convention",
        "separation-before",
        "--json",
    ]);
    assert_eq!(detected["efl_mm"], explicit["efl_mm"]);
    // Twice the 50 mm table's 50.358 mm (lenses-csv header).
    assert!((detected["efl_mm"].as_f64().unwrap() - 100.716).abs() < SCALED_PBRT_HEADER_EFL_TOL_MM);
    let other = json(&[
        "info",
        &file,
        "--pbrt-convention",
        "thickness-after",
        "--json",
    ]);
    assert_ne!(detected["efl_mm"], other["efl_mm"]);
    let run = flarebench(&[
        "info",
        "heliar-tronnier",
        "--pbrt-convention",
        "thickness-after",
    ]);
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("PBRT `.dat` tables only"));
}

#[test]
fn a_flaresim_lens_converts_to_xml_that_reads_back_the_same() {
    let tmp = temp_dir("lens");
    let nikkor = format!(
        "{}/../tests/data/flaresim-lenses/lens_files/AF_Nikkor_85mm_F1.4D_IF.lens",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = tmp.path().join("nikkor.xml");
    let run = flarebench(&["convert", &nikkor, "-o", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: ") && stderr.contains("semi_ap read as diameters (halved)"),
        "{stderr}"
    );
    let lens = json(&["info", &nikkor, "--json"]);
    let xml = json(&["info", out.to_str().unwrap(), "--json"]);
    for key in [
        "efl_mm",
        "bfl_mm",
        "entrance_pupil_diameter_mm",
        "f_number",
        "surfaces",
    ] {
        assert_eq!(lens[key], xml[key], "{key}");
    }
    let efl = lens["efl_mm"].as_f64().unwrap();
    assert!((efl - 85.0).abs() <= STATED_FOCAL_REL * 85.0, "EFL {efl}");
    tmp.close().unwrap();
}

#[test]
fn lens_aperture_and_lenient_apertures_are_options_for_lens_files() {
    // semi.lens: the stop's 12.5 read as a semi-diameter gives EPD 25 mm (f/4); forced to a
    // diameter, 12.5 mm (f/8).
    let detected = json(&["info", &data("semi.lens"), "--json"]);
    let forced = json(&[
        "info",
        &data("semi.lens"),
        "--lens-aperture",
        "diameter",
        "--json",
    ]);
    let epd = |v: &serde_json::Value| v["entrance_pupil_diameter_mm"].as_f64().unwrap();
    assert!(
        (epd(&detected) - 25.0).abs() < CLOSED_FORM_MM,
        "{}",
        epd(&detected)
    );
    assert!(
        (epd(&forced) - 12.5).abs() < CLOSED_FORM_MM,
        "{}",
        epd(&forced)
    );
    // A clear aperture beyond |R| whichever way: refused, or clamped when asked.
    let run = flarebench(&["info", &data("beyond-radius.lens")]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("beyond-radius.lens:13:")
            && stderr.contains("field `semi_ap`")
            && stderr.contains("--lenient-apertures clamps it"),
        "{stderr}"
    );
    let run = flarebench(&["info", &data("beyond-radius.lens"), "--lenient-apertures"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("clamped to 51.68 mm"), "{stderr}");
    // Neither option applies to another format.
    for option in [
        &["--lens-aperture", "semi"][..],
        &["--lenient-apertures"][..],
    ] {
        let mut args = vec!["info", "heliar-tronnier"];
        args.extend_from_slice(option);
        let run = flarebench(&args);
        assert!(!run.status.success(), "{option:?}");
        assert!(
            String::from_utf8_lossy(&run.stderr).contains("`.lens` files only"),
            "{option:?}"
        );
    }
}

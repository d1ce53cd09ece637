//! The bundled lens library (`lenses/*.xml`): every file loads without warnings, validates, is
//! in the canonical form our writer produces, and has the first-order properties its notes
//! state (computed independently by `lenses/sources/convert.py`).

use std::path::{Path, PathBuf};

use flarebench_sdk::io::{read_lens, write_xml};
use flarebench_sdk::paraxial;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::{LensSystem, SurfaceKind};

/// A library lens's EFL against its value quoted to 3 decimals (mm).
const QUOTED_EFL_TOL_MM: f64 = 1e-3;
/// Sensor of a pbrt lens against the paraxial focus (mm): the sensor distance as the lens file
/// writes it, rounded.
const FILE_FOCUS_TOL_MM: f64 = 1e-5;
/// An entrance pupil diameter against the source's figure quoted to 3 decimals (mm).
const QUOTED_EPD_TOL_MM: f64 = 2e-3;
/// The fisheye's f-number against f/4: f64 rounding.
const F_NUMBER_TOL: f64 = 1e-9;

fn lenses_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses")
}

fn library() -> Vec<(String, PathBuf)> {
    let mut files: Vec<(String, PathBuf)> = std::fs::read_dir(lenses_dir())
        .expect("lenses/ exists")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .map(|p| (p.file_stem().unwrap().to_string_lossy().into_owned(), p))
        .collect();
    files.sort();
    files
}

fn load(stem: &str) -> LensSystem {
    read_lens(&lenses_dir().join(format!("{stem}.xml")))
        .unwrap_or_else(|e| panic!("{e}"))
        .system
}

#[test]
fn every_library_lens_loads_validates_and_is_canonical() {
    let files = library();
    assert_eq!(
        files.len(),
        19,
        "{:?}",
        files.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for (stem, path) in &files {
        let lens = read_lens(path).unwrap_or_else(|e| panic!("{e}"));
        assert!(lens.warnings.is_empty(), "{stem}: {:?}", lens.warnings);
        let s = &lens.system;
        s.validate().unwrap_or_else(|e| panic!("{stem}: {e:?}"));
        assert_eq!(s.name, *stem);
        assert!(!s.source.is_empty() && !s.notes.is_empty(), "{stem}");
        let stops = s
            .surfaces
            .iter()
            .filter(|x| x.kind == SurfaceKind::ApertureStop);
        assert_eq!(stops.count(), 1, "{stem}");
        assert_eq!(
            s.surfaces.last().unwrap().kind,
            SurfaceKind::Sensor,
            "{stem}"
        );
        let text = std::fs::read_to_string(path).unwrap();
        assert_eq!(write_xml(s), text, "{stem} is not in canonical form");
    }
}

#[test]
fn masks_named_by_lenses_are_in_the_library() {
    for (stem, path) in library() {
        let s = read_lens(&path).unwrap().system;
        for mask in s
            .surfaces
            .iter()
            .flat_map(|x| [&x.mask, &x.mask_ft])
            .flatten()
        {
            assert!(
                lenses_dir().join("masks").join(mask).is_file(),
                "{stem}: mask {mask} missing from lenses/masks"
            );
        }
    }
}

#[test]
fn focal_lengths_agree_with_the_conversion_script() {
    // (lens, paraxial EFL at the d line from convert.py's own ynu trace, stated EFL)
    let cases = [
        ("heliar-tronnier", 99.236, Some(100.0)),
        ("nikon-zoom-short", 57.206, Some(80.0)),
        ("nikon-zoom-mid", 93.032, Some(140.0)),
        ("nikon-zoom-long", 143.076, Some(200.0)),
        ("kreitzer-tele", 400.927, Some(100.0)),
        ("itoh-zoom-mid", 118.568, Some(123.0)),
        ("double-gauss-50mm", 50.358, Some(50.0)),
        ("fisheye-10mm", 9.991, Some(10.0)),
        ("cooke-triplet-25mm", 24.991, None),
        ("laikin-wide-angle-100deg", 18.544, None),
    ];
    for (stem, efl, stated) in cases {
        let s = load(stem);
        let p = paraxial::analyse(&s, LAMBDA_D_NM).unwrap();
        assert!(
            (p.efl_mm - efl).abs() < QUOTED_EFL_TOL_MM,
            "{stem}: EFL {}",
            p.efl_mm
        );
        assert_eq!(s.stated_efl_mm, stated, "{stem}");
    }
}

#[test]
fn pbrt_lenses_have_the_sensor_at_the_paraxial_focus() {
    for stem in [
        "double-gauss-50mm",
        "wide-22mm",
        "telephoto-250mm",
        "fisheye-10mm",
    ] {
        let p = paraxial::analyse(&load(stem), LAMBDA_D_NM).unwrap();
        assert!(
            p.focus_error_mm.abs() < FILE_FOCUS_TOL_MM,
            "{stem}: {}",
            p.focus_error_mm
        );
    }
}

#[test]
fn stated_apertures_hold() {
    // The Cooke triplet's stop gives the file's entrance pupil, ENPD 8.333 mm.
    let p = paraxial::analyse(&load("cooke-triplet-25mm"), LAMBDA_D_NM).unwrap();
    assert!(
        (p.entrance_pupil_diameter_mm - 8.333).abs() < QUOTED_EPD_TOL_MM,
        "{p:?}"
    );
    // The Laikin lens's stop from the file gives its ENPD 0.36 in = 9.144 mm.
    let p = paraxial::analyse(&load("laikin-wide-angle-100deg"), LAMBDA_D_NM).unwrap();
    assert!(
        (p.entrance_pupil_diameter_mm - 9.144).abs() < QUOTED_EPD_TOL_MM,
        "{p:?}"
    );
    // The fisheye is f/4.
    let p = paraxial::analyse(&load("fisheye-10mm"), LAMBDA_D_NM).unwrap();
    assert!((p.f_number - 4.0).abs() < F_NUMBER_TOL, "{p:?}");
}

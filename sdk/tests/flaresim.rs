//! FlareSim `.lens` files as first-class lenses: the hand-made files of `tests/data/flaresim/`
//! (their values worked by hand in its README) — one per `semi_ap` convention, one per reason a
//! lens is refused —, the lenient and forced options, a real file of FlareSim's library
//! against its stated focal length, and `.lens` → our XML → the same lens.

use std::path::{Path, PathBuf};

use flarebench_sdk::io::{
    LensApertureConvention, LensFileError, LoadedLens, ReadOptions, parse_flaresim, parse_olf_xml,
    read_lens, read_lens_with, write_xml,
};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::system::CoatingLayer;
use flarebench_sdk::{Coating, Medium, SurfaceKind};

/// Paraxial values of the hand-worked singlet against their closed forms (EFL = R/(n − 1),
/// EPD = the stop's diameter): f64 rounding of a few matrix products (measured ≤ 3e-14).
const CLOSED_FORM_REL: f64 = 1e-12;

/// A stated focal length of FlareSim's library against the paraxial EFL: the issue's
/// measure, 1%.
const STATED_FOCAL_REL: f64 = 0.01;

fn data(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/flaresim")
        .join(file)
}

fn corpus(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/flaresim-lenses/lens_files")
        .join(file)
}

fn load(file: &str) -> LoadedLens {
    read_lens(&data(file)).unwrap_or_else(|e| panic!("{e}"))
}

fn with(aperture: Option<LensApertureConvention>, lenient: bool) -> ReadOptions {
    ReadOptions {
        lens_aperture: aperture,
        lenient_apertures: lenient,
        ..ReadOptions::default()
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

/// Line and column (1-based, characters) of `token`'s first appearance as a word on a line
/// that is not a comment: where an error about it must point.
fn position_of(path: &Path, token: &str) -> (usize, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with('#') {
            continue;
        }
        let data = line.split('#').next().unwrap();
        let mut offset = 0;
        for word in data.split_whitespace() {
            let at = offset + data[offset..].find(word).unwrap();
            if word == token {
                return (i + 1, data[..at].chars().count() + 1);
            }
            offset = at + word.len();
        }
    }
    panic!("`{token}` is not in {}", path.display())
}

#[test]
fn semi_diameters_are_told_by_the_stop_against_the_stated_f_number() {
    let lens = load("semi.lens");
    let s = &lens.system;
    let semis: Vec<f64> = s.surfaces.iter().map(|x| x.semi_diameter).collect();
    assert_eq!(semis[..3], [12.5, 14.0, 14.0]);
    let warning = lens
        .warnings
        .iter()
        .find(|w| w.contains("semi_ap read as semi-diameters, decided from the data (by the stop against the stated f-number)"))
        .unwrap_or_else(|| panic!("{:?}", lens.warnings));
    assert!(
        warning.contains("the stop gives f/4 as semi-diameters, f/8 as diameters (halved), against the stated f/4 (comment header)"),
        "{warning}"
    );
    assert!(
        s.notes
            .contains("read as semi-diameters, decided from the data (by the stop")
    );
    let p = analyse(s, LAMBDA_D_NM).unwrap();
    assert!(close(p.efl_mm, 100.0, CLOSED_FORM_REL), "{}", p.efl_mm);
    assert!(close(p.open_f_number, 4.0, CLOSED_FORM_REL));
    assert_eq!(s.f_number, Some(4.0));
    assert_eq!(s.stated_efl_mm, Some(100.0));
    assert_eq!(s.name, "Test plano-convex 100mm f/4 (semi-diameters)");
    // The glass from nd and Vd, as the other readers build it; one coating layer is
    // quarter-wave MgF2 at 550 nm; the sensor at the last row's thickness.
    assert_eq!(
        s.surfaces[1].medium,
        Medium::Model {
            nd: 1.5168,
            vd: Some(64.17)
        }
    );
    assert_eq!(
        s.surfaces[1].coating,
        Coating::SingleLayer {
            design_wavelength_nm: 550.0,
            index: 1.38
        }
    );
    assert_eq!(s.surfaces[0].kind, SurfaceKind::ApertureStop);
    assert_eq!(s.surfaces[2].thickness, 96.7036);
    assert_eq!(s.surfaces[3].kind, SurfaceKind::Sensor);
    // BFD = 96.7036 rounds the closed form to 1e-4 mm.
    assert!(p.focus_error_mm.abs() < 1e-4, "{}", p.focus_error_mm);
}

#[test]
fn diameters_are_told_by_a_semi_diameter_beyond_its_radius() {
    let lens = load("diameter.lens");
    let s = &lens.system;
    let semis: Vec<f64> = s.surfaces.iter().map(|x| x.semi_diameter).collect();
    assert_eq!(semis[..3], [12.5, 28.0, 28.0]);
    let warning = lens
        .warnings
        .iter()
        .find(|w| w.contains("semi_ap read as diameters (halved), decided from the data (by semi-diameters beyond |R|)"))
        .unwrap_or_else(|| panic!("{:?}", lens.warnings));
    let (line, _) = position_of(&data("diameter.lens"), "56.000");
    assert!(
        warning.contains(&format!(
            "as semi-diameters, 1 semi-diameter exceeds |R| (first: line {line}, 56 mm against \
             |R| = 51.68 mm)"
        )),
        "{warning}"
    );
    let p = analyse(s, LAMBDA_D_NM).unwrap();
    assert!(close(p.efl_mm, 100.0, CLOSED_FORM_REL));
    assert!(close(p.open_f_number, 4.0, CLOSED_FORM_REL));
    // Two layers: quarter-wave MgF2 on the air side over the layer designed for nd 1.5168.
    let high = 1.38 * 1.5168_f64.sqrt();
    assert_eq!(
        s.surfaces[1].coating,
        Coating::Stack(vec![
            CoatingLayer {
                index: 1.38,
                thickness_nm: 550.0 / (4.0 * 1.38)
            },
            CoatingLayer {
                index: high,
                thickness_nm: 550.0 / (4.0 * high)
            },
        ])
    );
}

#[test]
fn without_an_f_number_and_with_both_readings_possible_the_column_is_read_as_named() {
    let text = std::fs::read_to_string(data("semi.lens"))
        .unwrap()
        .replace(", f/4.0", "")
        .replace(" f/4", "");
    let lens = parse_flaresim(&text, "plain.lens", None, false).unwrap();
    assert_eq!(lens.system.surfaces[0].semi_diameter, 12.5);
    assert_eq!(lens.system.f_number, None);
    assert!(
        lens.warnings.iter().any(|w| w.contains(
            "the file states no f-number; the data allow both readings: the column is read as \
             it is named"
        )),
        "{:?}",
        lens.warnings
    );
}

/// Each refusal: the file, the token the error must point at, its field and a part of its
/// message.
const REFUSED: &[(&str, &str, &str, &str)] = &[
    ("no-stop.lens", "surfaces:", "radius", "no stop row"),
    (
        "infinite-thickness.lens",
        "inf",
        "thickness",
        "must be finite",
    ),
    ("afocal.lens", "inf", "focal_length", "afocal attachment"),
    (
        "cylindrical.lens",
        "cyl_y",
        "type",
        "anamorphic lenses are not supported",
    ),
    (
        "toric.lens",
        "toric",
        "type",
        "anamorphic lenses are not supported",
    ),
    (
        "malformed.lens",
        "1,51680",
        "ior",
        "expected a number, got `1,51680`",
    ),
    (
        "negative-thickness.lens",
        "-5.0000",
        "thickness",
        "a mirror lens",
    ),
    ("zero-aperture.lens", "0.000", "semi_ap", "must be > 0 mm"),
    (
        "beyond-radius.lens",
        "120.000",
        "semi_ap",
        "clear semi-diameter 60 mm (the column's 120 mm halved) exceeds |R| = 51.68 mm",
    ),
];

#[test]
fn each_refusal_names_file_line_column_and_field() {
    for &(file, token, field, says) in REFUSED {
        let path = data(file);
        let e: LensFileError = read_lens(&path).unwrap_err();
        let (line, column) = position_of(&path, token);
        assert_eq!(e.file, path.display().to_string());
        assert_eq!(
            (e.line, e.column, e.field.as_str()),
            (line, column, field),
            "{file}: {e}"
        );
        assert!(e.message.contains(says), "{file}: {e}");
    }
}

#[test]
fn lenient_apertures_clamp_what_is_still_impossible_each_with_a_warning() {
    let path = data("beyond-radius.lens");
    let lens = read_lens_with(&path, &with(None, true)).unwrap();
    let s = &lens.system;
    // |R|, or the float below it where c²r² would round above 1.
    assert!((s.surfaces[1].semi_diameter - 51.68).abs() < 1e-13);
    assert_eq!(s.surfaces[2].semi_diameter, 28.0);
    let (line, column) = position_of(&path, "120.000");
    let clamps: Vec<&String> = lens
        .warnings
        .iter()
        .filter(|w| w.contains("clamped"))
        .collect();
    assert_eq!(clamps.len(), 1, "{clamps:?}");
    assert!(
        clamps[0].contains(&format!(
            ":{line}:{column}: clear semi-diameter 60 mm clamped to 51.68 mm (|R| = 51.68 mm)"
        )),
        "{}",
        clamps[0]
    );
    assert!(
        s.notes
            .contains(&format!("line {line}: 60 → 51.68 mm (|R| = 51.68 mm)")),
        "{}",
        s.notes
    );
}

#[test]
fn a_forced_convention_is_read_as_asked() {
    use LensApertureConvention::{Diameter, Semi};
    let path = data("diameter.lens");
    // As semi-diameters the lens's 56 mm exceed |R|: refused, or clamped when lenient — to
    // |R|, then both faces to √933.6 mm where the 10 mm thick element's faces meet.
    let e = read_lens_with(&path, &with(Some(Semi), false)).unwrap_err();
    assert_eq!((e.line, e.column), position_of(&path, "56.000"));
    assert!(e.message.contains("56 mm exceeds |R| = 51.68 mm"), "{e}");
    let lens = read_lens_with(&path, &with(Some(Semi), true)).unwrap();
    let meet = 933.6_f64.sqrt();
    let s = &lens.system;
    assert_eq!(s.surfaces[0].semi_diameter, 25.0);
    for k in [1, 2] {
        assert!(
            (s.surfaces[k].semi_diameter - meet).abs() < 1e-9,
            "{}",
            s.surfaces[k].semi_diameter
        );
    }
    assert_eq!(
        lens.warnings
            .iter()
            .filter(|w| w.contains("clamped"))
            .count(),
        3,
        "{:?}",
        lens.warnings
    );
    assert!(lens.warnings.iter().any(|w| w.contains(
        "semi_ap read as semi-diameters as asked, although the data point to diameters"
    )));
    assert!(s.notes.contains("as asked (--lens-aperture semi)"));
    // Diameters forced on the semi-diameter file: half the apertures, f/8 wide open.
    let lens = read_lens_with(&data("semi.lens"), &with(Some(Diameter), false)).unwrap();
    assert_eq!(lens.system.surfaces[0].semi_diameter, 6.25);
    let p = analyse(&lens.system, LAMBDA_D_NM).unwrap();
    assert!(close(p.open_f_number, 8.0, CLOSED_FORM_REL));
    // Forced to what the data say: no warning about the convention.
    let lens = read_lens_with(&data("semi.lens"), &with(Some(Semi), false)).unwrap();
    assert!(
        lens.warnings.iter().all(|w| !w.contains("semi_ap read")),
        "{:?}",
        lens.warnings
    );
}

#[test]
fn lens_options_are_errors_for_other_formats() {
    let xml = Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml");
    let e = read_lens_with(&xml, &with(Some(LensApertureConvention::Semi), false)).unwrap_err();
    assert!(
        e.is_whole_file() && e.message.contains("`.lens` files only"),
        "{e}"
    );
    let e = read_lens_with(&xml, &with(None, true)).unwrap_err();
    assert!(
        e.is_whole_file() && e.message.contains("`.lens` files only"),
        "{e}"
    );
}

#[test]
fn a_coating_on_a_cemented_interface_is_left_out_with_a_warning() {
    // A cemented achromat-like doublet: the file marks all three glass-bound surfaces coated.
    let text = "name: doublet\nfocal_length: 100\nsurfaces:\n  stop 2 1 0 20 0\n  \
                61.5 6 1.5168 64.17 24 1\n  -44.2 2.5 1.6200 36.37 24 1\n  -128.0 95 1 0 24 0\n";
    let lens = parse_flaresim(
        text,
        "doublet.lens",
        Some(LensApertureConvention::Semi),
        false,
    )
    .unwrap();
    let s = &lens.system;
    assert!(matches!(s.surfaces[1].coating, Coating::SingleLayer { .. }));
    assert_eq!(s.surfaces[2].coating, Coating::None);
    assert!(
        lens.warnings
            .iter()
            .any(|w| w.contains("the coating on line 6 is left out")),
        "{:?}",
        lens.warnings
    );
}

#[test]
fn the_af_nikkor_85mm_f1_4d_traces_to_its_stated_85mm_within_one_percent() {
    let lens = read_lens(&corpus("AF_Nikkor_85mm_F1.4D_IF.lens")).unwrap_or_else(|e| panic!("{e}"));
    let s = &lens.system;
    assert_eq!(s.name, "Nikon AF Nikkor 85mm f/1.4D IF");
    assert_eq!(s.stated_efl_mm, Some(85.0));
    assert_eq!(s.f_number, Some(1.4));
    assert!(
        s.notes
            .contains("read as diameters (halved), decided from the data")
    );
    // The stop's column value 30.413, halved.
    assert_eq!(
        s.surfaces[s.stop_index().unwrap()].semi_diameter,
        30.413 / 2.0
    );
    let p = analyse(s, LAMBDA_D_NM).unwrap();
    assert!(close(p.efl_mm, 85.0, STATED_FOCAL_REL), "EFL {}", p.efl_mm);
    assert!(s.source.contains("Patent: US005640277"), "{}", s.source);
}

#[test]
fn a_lens_written_as_our_xml_reads_back_equal() {
    let files = [
        data("semi.lens"),
        data("diameter.lens"),
        corpus("AF_Nikkor_85mm_F1.4D_IF.lens"),
        corpus("AI_Nikkor_135mm_F2.lens"),
    ];
    for path in files {
        let original = read_lens(&path).unwrap().system;
        let xml = write_xml(&original);
        let back = parse_olf_xml(&xml, "converted.xml")
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .system;
        assert_eq!(back, original, "{}", path.display());
    }
}

/// The Zeiss Hologon 15 mm f/8's table as FlareSim gives it (DE01241637): its stop in a film
/// of air of no thickness between two flats of its middle element's glass.
const HOLOGON: &str = "\
name: Zeiss Hologon f8 15mm
focal_length: 15.00

surfaces:
  11.6400        7.9785       1.80518  25.46    21.800    1
  3.8430         2.7030       1.00000  0.00     7.630     0
  5.6685         4.1685       1.71300  53.89    7.190     1
  0              0.0000       1.00000  0.00     1.534     0
  stop           0.0000       1.00000  0.00     1000000.000 0
  0              3.4800       1.71300  53.89    1.534     1
  -5.5080        2.4045       1.00000  0.00     6.840     0
  -3.6285        5.2365       1.80518  25.46    7.257     1
  -8.9835        4.5420       1.00000  0.00     17.310    0
";

#[test]
fn a_stop_in_a_film_of_air_of_no_thickness_between_flats_of_one_glass_is_inside_the_glass() {
    let lens = parse_flaresim(HOLOGON, "hologon.lens", None, false).expect("the table reads");
    let s = &lens.system.surfaces;
    let glass = s[2].medium.clone();
    assert!(
        matches!(glass, Medium::Model { nd, .. } if nd == 1.713),
        "{glass:?}"
    );
    // The near flat and the stop lie in the glass; the far flat leaves it into the same glass.
    for (k, surface) in s.iter().enumerate().take(6).skip(3) {
        assert_eq!(surface.medium, glass, "surface {k}");
    }
    assert_eq!(s[5].coating, Coating::None);
    assert!(lens.system.notes.contains("the stop inside the glass"));
    // A film of air would reflect the chief ray at 49° totally at the near flat (the stop
    // crossing jumped from −0.45 to +0.03 mm over the rays it reflected); in the glass it
    // passes.
    let found = flarebench_sdk::starburst::chief_ray_landing(
        &lens.system,
        LAMBDA_D_NM,
        49f64.to_radians(),
        0.0,
    );
    assert!(found.is_ok(), "{found:?}");
}

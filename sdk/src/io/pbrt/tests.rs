//! Unit tests of the PBRT table reader: both conventions, the stop row, the film distance,
//! and errors at their line and column.

use proptest::prelude::*;

use super::{PbrtConvention, parse_pbrt};
use crate::io::LensFileError;
use crate::paraxial::analyse;
use crate::system::{Medium, SurfaceKind};

/// A biconvex n 1.5 lens (R ±50, 5 mm), a stop 10 mm behind, the film 40 mm further.
const AFTER: &str = "\
# test lens
# radius thickness n aperture
50 5 1.5 20
-50 10 1 20
0 40 0 12
";

/// The same lens with separations before each surface and the film left to focus.
const BEFORE: &str = "\
50 0 1.5 20
-50 5 1 20
0 10 0 12
";

fn expect_error(text: &str, field: &str, line: usize, column: usize) -> LensFileError {
    let e = parse_pbrt(text, "t.dat", None).expect_err("the table must be rejected");
    assert_eq!(
        (e.file.as_str(), e.field.as_str(), e.line, e.column),
        ("t.dat", field, line, column),
        "{e}"
    );
    e
}

#[test]
fn thickness_after_tables_read_as_pbrt_means_them() {
    let lens = parse_pbrt(AFTER, "lenses/test.25mm.dat", None).unwrap();
    assert!(lens.warnings.is_empty(), "{:?}", lens.warnings);
    let s = &lens.system;
    assert_eq!(s.name, "test.25mm");
    assert_eq!(s.stated_efl_mm, Some(25.0));
    assert_eq!(s.surfaces.len(), 4);
    assert_eq!(s.surfaces[0].curvature, 1.0 / 50.0);
    assert_eq!(s.surfaces[0].medium, Medium::Model { nd: 1.5, vd: None });
    assert_eq!(s.surfaces[1].medium, Medium::Air);
    assert_eq!(s.surfaces[2].kind, SurfaceKind::ApertureStop);
    assert_eq!(s.surfaces[2].medium, Medium::Air, "index 0 is air");
    // Diameters are halved.
    assert_eq!(
        [s.surfaces[0].semi_diameter, s.surfaces[2].semi_diameter],
        [10.0, 6.0]
    );
    // The last row's thickness is the film distance.
    assert_eq!(
        s.surfaces.iter().map(|x| x.thickness).collect::<Vec<_>>(),
        [5.0, 10.0, 40.0, 0.0]
    );
    assert!(
        s.notes
            .contains("Table header: test lens; radius thickness n aperture.")
    );
}

#[test]
fn separation_before_tables_shift_the_column_and_focus_the_film() {
    let lens = parse_pbrt(BEFORE, "t.dat", None).unwrap();
    assert!(
        lens.warnings[0].starts_with("t.dat:1:4: column 2 read as the separation before"),
        "{:?}",
        lens.warnings
    );
    let s = &lens.system;
    assert_eq!(s.surfaces[0].thickness, 5.0);
    assert_eq!(s.surfaces[1].thickness, 10.0);
    // The film is at the paraxial focus: no focus error.
    let p = analyse(s, 587.5618).unwrap();
    assert!(p.focus_error_mm.abs() < 1e-12, "{p:?}");
    assert!((s.surfaces[2].thickness - p.bfl_mm).abs() < 1e-12);
    // Forcing the convention gives the same lens without the warning.
    let forced = parse_pbrt(BEFORE, "t.dat", Some(PbrtConvention::SeparationBefore)).unwrap();
    assert!(forced.warnings.is_empty());
    assert_eq!(forced.system.surfaces, s.surfaces);
    // pbrt's own convention with the last thickness 0 also focuses the film.
    let zero = AFTER.replace("0 40 0 12", "0 0 0 12");
    let z = parse_pbrt(&zero, "t.dat", None).unwrap().system;
    let p = analyse(&z, 587.5618).unwrap();
    assert!(p.focus_error_mm.abs() < 1e-12, "{p:?}");
}

#[test]
fn an_ambiguous_table_asks_for_the_convention() {
    let both = AFTER
        .replace("50 5 1.5 20", "50 0 1.5 20")
        .replace("0 40 0", "0 0 0");
    let e = expect_error(&both, "thickness", 3, 4);
    assert!(e.message.contains("--pbrt-convention"), "{e}");
    // Neither zero: pbrt's own convention (AFTER gives its film distance).
    let neither = BEFORE.replace("50 0 1.5", "50 2 1.5");
    let auto = parse_pbrt(&neither, "t.dat", None).unwrap();
    let after = parse_pbrt(&neither, "t.dat", Some(PbrtConvention::ThicknessAfter)).unwrap();
    assert_eq!(auto.system.surfaces, after.system.surfaces);
    assert_eq!(after.system.surfaces[0].thickness, 2.0);
    let lens = parse_pbrt(&neither, "t.dat", Some(PbrtConvention::SeparationBefore)).unwrap();
    assert!(
        lens.warnings[0].contains("in front of the first surface (2 mm) is ignored"),
        "{:?}",
        lens.warnings
    );
}

#[test]
fn rows_are_checked_with_line_and_column() {
    expect_error(&AFTER.replace("-50 10 1 20", "-50 10 1"), "", 4, 1);
    expect_error(&AFTER.replace("-50 10 1 20", "-50 10 1 20 7"), "", 4, 13);
    let e = expect_error(
        &AFTER.replace("-50 10 1 20", "-50 1O 1 20"),
        "thickness",
        4,
        5,
    );
    assert!(e.message.contains("expected a number, got `1O`"), "{e}");
    expect_error(
        &AFTER.replace("-50 10 1 20", "-50 10 1 NaN"),
        "aperture",
        4,
        10,
    );
    expect_error(
        &AFTER.replace("-50 10 1 20", "-50 10 0.5 20"),
        "index",
        4,
        8,
    );
    expect_error(
        &AFTER.replace("-50 10 1 20", "-50 -10 1 20"),
        "thickness",
        4,
        5,
    );
    expect_error(
        &AFTER.replace("-50 10 1 20", "-50 10 1 0"),
        "aperture",
        4,
        10,
    );
    let e = expect_error(&AFTER.replace("0 40 0 12", "30 40 0 12"), "radius", 3, 1);
    assert!(e.message.contains("no aperture stop"), "{e}");
    // A semi-diameter larger than the radius is a validation issue at the aperture column.
    let e = expect_error(
        &AFTER.replace("50 5 1.5 20", "5 5 1.5 20"),
        "aperture",
        3,
        9,
    );
    assert!(e.message.contains("exceeds"), "{e}");
    let e = parse_pbrt("# only a comment\n", "t.dat", None).unwrap_err();
    assert!(e.message.contains("no lens rows"), "{e}");
}

#[test]
fn a_second_flat_row_is_a_clipping_surface() {
    let text = AFTER.replace("-50 10 1 20", "-50 5 1 20\n0 5 0 18");
    let lens = parse_pbrt(&text, "t.dat", None).unwrap();
    assert_eq!(lens.system.surfaces[2].kind, SurfaceKind::ApertureStop);
    assert_eq!(lens.system.surfaces[3].kind, SurfaceKind::Refracting);
    assert_eq!(lens.system.surfaces[3].semi_diameter, 6.0);
    assert!(
        lens.warnings[0].contains("a second row with radius 0"),
        "{:?}",
        lens.warnings
    );
}

#[test]
fn convention_names_parse_back() {
    for c in [
        PbrtConvention::ThicknessAfter,
        PbrtConvention::SeparationBefore,
    ] {
        assert_eq!(c.name().parse::<PbrtConvention>(), Ok(c));
    }
    assert!("sideways".parse::<PbrtConvention>().is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_tables_never_panic(text in "([0-9 .eE+\\-#a-z\t]{0,20}\n){0,12}") {
        if let Err(e) = parse_pbrt(&text, "t.dat", None) {
            prop_assert!(e.line >= 1, "{}", e);
        }
    }
}

//! Unit tests of the Zemax reader on small hand-written files: units, surface types, glasses,
//! the stop, apertures, configurations, and errors at their line and column.

use proptest::prelude::*;

use super::parse_zmx;
use crate::io::{LensFileError, LoadedLens};
use crate::paraxial::analyse;
use crate::system::{Medium, SurfaceKind};

/// A biconvex N-BK7 singlet (R ±50 mm, 5 mm thick) with a flat stop 10 mm behind it, image
/// 40 mm further; ENPD 10 mm, fields 0 and 10°, primary wavelength the d line.
const SINGLET: &str = "\
VERS 140730 201 26155
MODE SEQ
NAME test singlet
UNIT MM X W X CM MR CPMM
ENPD 10
GCAT SCHOTT
FTYP 0 0 2 1 0 0 0
XFLN 0 0
YFLN 0 10
WAVM 1 0.5875618 1
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0.0
  DISZ INFINITY
SURF 1
  TYPE STANDARD
  CURV 0.02
  DISZ 5
  GLAS N-BK7 0 0 1.5168 64.17
  DIAM 12 0 0 0 1 \"\"
SURF 2
  TYPE STANDARD
  CURV -0.02
  DISZ 10
  DIAM 12 0 0 0 1 \"\"
SURF 3
  STOP
  TYPE STANDARD
  CURV 0.0
  DISZ 40
SURF 4
  TYPE STANDARD
  CURV 0.0
  DISZ 0
";

fn parse(text: &str) -> Result<LoadedLens, LensFileError> {
    parse_zmx(text, "test.zmx", None)
}

/// SINGLET with `from` replaced by `to` (`from` must occur exactly once).
fn edited(from: &str, to: &str) -> String {
    assert_eq!(SINGLET.matches(from).count(), 1, "`{from}` must be unique");
    SINGLET.replacen(from, to, 1)
}

/// The line (1-based) of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).expect("needle in text")]
        .matches('\n')
        .count()
        + 1
}

fn expect_error(text: &str, field: &str, needle: &str) -> LensFileError {
    let e = parse(text).expect_err("the file must be rejected");
    assert_eq!(e.file, "test.zmx");
    assert_eq!(
        (e.field.as_str(), e.line),
        (field, line_of(text, needle)),
        "{e}"
    );
    assert!(e.column >= 1, "{e}");
    e
}

#[test]
fn the_singlet_reads_as_written() {
    let lens = parse(SINGLET).unwrap();
    let s = &lens.system;
    assert_eq!(s.name, "test singlet");
    assert_eq!(
        s.surfaces.len(),
        4,
        "object dropped, stop kept, image → sensor"
    );
    assert_eq!(
        s.surfaces.iter().map(|x| x.kind).collect::<Vec<_>>(),
        [
            SurfaceKind::Refracting,
            SurfaceKind::Refracting,
            SurfaceKind::ApertureStop,
            SurfaceKind::Sensor
        ]
    );
    assert_eq!(s.surfaces[0].curvature, 0.02);
    assert_eq!(s.surfaces[1].curvature, -0.02);
    assert_eq!(
        [
            s.surfaces[0].thickness,
            s.surfaces[1].thickness,
            s.surfaces[2].thickness
        ],
        [5.0, 10.0, 40.0]
    );
    assert!(matches!(&s.surfaces[0].medium, Medium::Glass { name, .. } if name == "SCHOTT:N-BK7"));
    assert_eq!(s.surfaces[1].medium, Medium::Air);
    assert_eq!(s.surfaces[0].semi_diameter, 12.0);
    assert_eq!(s.primary_wavelength_nm, Some(587.5618));
    // The stop behind the lens: its semi-diameter makes the entrance pupil 10 mm.
    let p = analyse(s, 587.5618).unwrap();
    assert!((p.entrance_pupil_diameter_mm - 10.0).abs() < 1e-12, "{p:?}");
    assert!(lens.warnings.is_empty(), "{:?}", lens.warnings);
}

#[test]
fn lens_units_are_converted_to_millimetres() {
    let base = parse(SINGLET).unwrap().system;
    for (unit, mm) in [("CM", 10.0), ("IN", 25.4), ("METER", 1000.0)] {
        let s = parse(&edited("UNIT MM", &format!("UNIT {unit}")))
            .unwrap()
            .system;
        assert_eq!(s.surfaces[0].curvature, 0.02 / mm, "{unit}");
        assert_eq!(s.surfaces[0].thickness, 5.0 * mm, "{unit}");
        assert_eq!(s.surfaces[0].semi_diameter, 12.0 * mm, "{unit}");
        let (p, q) = (
            analyse(&s, 587.5618).unwrap(),
            analyse(&base, 587.5618).unwrap(),
        );
        assert!((p.efl_mm - q.efl_mm * mm).abs() < 1e-9 * p.efl_mm, "{unit}");
        assert!(
            (p.entrance_pupil_diameter_mm - 10.0 * mm).abs() < 1e-9 * mm,
            "{unit}"
        );
    }
    let text = edited("UNIT MM", "UNIT FURLONG");
    let e = expect_error(&text, "UNIT", "UNIT FURLONG");
    assert_eq!(e.column, 6, "{e}");
}

#[test]
fn even_asphere_coefficients_scale_with_the_unit() {
    let asph = "  TYPE EVENASPH\n  CURV 0.02\n  PARM 1 0.001\n  PARM 2 1e-5\n  PARM 8 1e-20\n  CONI -1.5\n";
    let text = edited("  TYPE STANDARD\n  CURV 0.02\n", asph);
    let s = parse(&text).unwrap().system;
    assert_eq!(s.surfaces[0].conic, -1.5);
    assert_eq!(s.surfaces[0].aspheric[0], 0.001);
    assert_eq!(s.surfaces[0].aspheric[1], 1e-5);
    assert_eq!(s.surfaces[0].aspheric[7], 1e-20);
    let s = parse(&text.replace("UNIT MM", "UNIT CM")).unwrap().system;
    // z = Σ aᵢ r^(2i): in mm, aᵢ scales by 10^(1 − 2i).
    assert!((s.surfaces[0].aspheric[0] - 0.001 / 10.0).abs() < 1e-18);
    assert!((s.surfaces[0].aspheric[1] - 1e-5 / 1e3).abs() < 1e-20);
    assert!((s.surfaces[0].aspheric[7] / (1e-20 / 1e15) - 1.0).abs() < 1e-12);
    // The sag at a given height (in mm) is the same surface.
    let mm = parse(&text).unwrap().system.surfaces[0].sag(5.0).unwrap();
    let cm = s.surfaces[0].sag(50.0).unwrap();
    assert!((cm - 10.0 * mm).abs() < 1e-12, "{cm} vs {mm}");
}

#[test]
fn extended_asphere_terms_become_even_asphere_coefficients() {
    // α₁ (r/r0)² + α₂ (r/r0)⁴ with r0 = 2: coefficients α₁/4 and α₂/16.
    let xasph = "  TYPE XASPHERE\n  CURV 0.02\n  XDAT 1 2 0 0 1\n  XDAT 2 2 0 0 1\n  XDAT 3 0.004 0 0 1\n  XDAT 4 0.0032 0 0 1\n";
    let s = parse(&edited("  TYPE STANDARD\n  CURV 0.02\n", xasph))
        .unwrap()
        .system;
    assert_eq!(s.surfaces[0].aspheric[..3], [0.001, 0.0002, 0.0]);
    // A ninth term that is not zero cannot be represented.
    let nine = "  TYPE XASPHERE\n  CURV 0.02\n  XDAT 1 9 0\n  XDAT 2 1 0\n  XDAT 11 1e-30 0\n";
    let text = edited("  TYPE STANDARD\n  CURV 0.02\n", nine);
    let e = expect_error(&text, "XDAT", "XDAT 11");
    assert!(e.message.contains("r^18"), "{e}");
}

#[test]
fn unsupported_surface_types_name_the_surface_and_type() {
    let text = edited(
        "  TYPE STANDARD\n  CURV -0.02",
        "  TYPE TOROIDAL\n  CURV -0.02",
    );
    let e = expect_error(&text, "TYPE", "TOROIDAL");
    assert!(e.message.contains("SURF 2 has type TOROIDAL"), "{e}");
    assert!(e.message.contains("supported: STANDARD, EVENASPH"), "{e}");
}

#[test]
fn a_coordinate_break_without_decenter_or_tilt_is_only_a_gap() {
    // Split the 10 mm gap behind the lens into 4 mm + a coordinate break carrying 6 mm.
    let text = edited(
        "  DISZ 10\n",
        "  DISZ 4\nSURF 9\n  TYPE COORDBRK\n  PARM 1 0\n  PARM 2 0\n  DISZ 6\n",
    );
    let s = parse(&text).unwrap().system;
    assert_eq!(s.surfaces.len(), 4);
    assert_eq!(s.surfaces[1].thickness, 10.0);
    let tilted = text.replace("  PARM 2 0\n", "  PARM 2 0\n  PARM 3 5\n");
    let e = expect_error(&tilted, "PARM", "PARM 3 5");
    assert!(e.message.contains("tilt of 5"), "{e}");
}

#[test]
fn glasses_resolve_through_the_catalogue_honouring_gcat() {
    let glass = |g: &str, gcat: &str| {
        let text = edited("N-BK7 0 0 1.5168 64.17", g).replace("GCAT SCHOTT", gcat);
        parse(&text).map(|l| (l.system.surfaces[0].medium.clone(), l.warnings))
    };
    let name = |m: &Medium| match m {
        Medium::Glass { name, .. } => name.clone(),
        other => format!("{other:?}"),
    };
    // SF1 is in SCHOTT and HIKARI: the file's catalogue order decides, without a warning.
    let (m, w) = glass("SF1", "GCAT HIKARI SCHOTT").unwrap();
    assert_eq!((name(&m), w.len()), ("HIKARI:SF1".into(), 0), "{w:?}");
    let (m, _) = glass("SF1", "GCAT SCHOTT HIKARI").unwrap();
    assert_eq!(name(&m), "SCHOTT:SF1");
    // A legacy name resolves to its documented successor, with a warning at the name.
    let (m, w) = glass("BK7", "GCAT SCHOTT").unwrap();
    assert_eq!(name(&m), "SCHOTT:N-BK7");
    assert!(
        w[0].starts_with(&format!(
            "test.zmx:{}:8: glass `BK7`",
            line_of(SINGLET, "GLAS")
        )),
        "{w:?}"
    );
    assert!(w[0].contains("successor SCHOTT:N-BK7"), "{w:?}");
    // Ohara's older names take their S- successors.
    let (m, _) = glass("LAH79", "GCAT OHARA").unwrap();
    assert_eq!(name(&m), "OHARA:S-LAH79");
    // A glass outside the file's catalogues is found elsewhere, with a warning.
    let (m, w) = glass("L-BAL35", "GCAT SCHOTT").unwrap();
    assert_eq!(name(&m), "OHARA:L-BAL35");
    assert!(
        w[0].contains("not in the file's catalogues (GCAT SCHOTT)"),
        "{w:?}"
    );
    // Fused silica under Zemax's MISC name.
    let (m, w) = glass("SILICA", "GCAT SCHOTT MISC").unwrap();
    assert_eq!(name(&m), "SCHOTT:LITHOSIL-Q");
    assert!(w[0].contains("fused silica"), "{w:?}");
    // Catalogue version suffixes are dropped (OHARA_2021-04 is OHARA).
    let (m, w) = glass("S-LAH64", "GCAT OHARA_2021-04").unwrap();
    assert_eq!((name(&m), w.len()), ("OHARA:S-LAH64".into(), 0));
    // A model glass from nd and Vd; Vd 0 is non-dispersive.
    let (m, w) = glass("___BLANK 1 0 1.6 40 0 0", "GCAT SCHOTT").unwrap();
    assert_eq!(
        m,
        Medium::Model {
            nd: 1.6,
            vd: Some(40.0)
        }
    );
    assert!(w.is_empty());
    let (m, _) = glass("___BLANK 1 0 1.6 0 0 0", "GCAT SCHOTT").unwrap();
    assert_eq!(m, Medium::Model { nd: 1.6, vd: None });
    // A six-digit glass code: nd 1.517, Vd 64.2.
    let (m, w) = glass("517642", "GCAT SCHOTT").unwrap();
    assert_eq!(
        m,
        Medium::Model {
            nd: 1.517,
            vd: Some(64.2)
        }
    );
    assert!(w[0].contains("glass code 517642"), "{w:?}");
    // Unknown glasses are errors at the name, with suggestions.
    let text = edited("N-BK7 0 0", "N-BK8 0 0");
    let e = expect_error(&text, "GLAS", "N-BK8");
    assert_eq!(e.column, 8);
    assert!(
        e.message.contains("unknown glass `N-BK8` (did you mean"),
        "{e}"
    );
    let text = edited("N-BK7 0 0 1.5168 64.17", "___BLANK 1 0 0.9 40");
    let e = expect_error(&text, "GLAS", "___BLANK");
    assert!(e.message.contains("nd must be ≥ 1"), "{e}");
}

#[test]
fn a_substituted_glass_is_reported_once() {
    let text = edited(
        "  DISZ 40\n",
        "  DISZ 20\n  GLAS BK7\n  DIAM 10\nSURF 5\n  CURV 0\n  DISZ 20\n",
    )
    .replace("GLAS N-BK7", "GLAS BK7");
    let lens = parse(&text).unwrap();
    let n = lens.warnings.iter().filter(|w| w.contains("`BK7`")).count();
    assert_eq!(n, 1, "{:?}", lens.warnings);
    assert_eq!(lens.system.notes.matches("`BK7`").count(), 1);
}

#[test]
fn mirrors_are_refused_at_their_glass_record() {
    let text = edited("GLAS N-BK7 0 0 1.5168 64.17", "GLAS MIRROR 0 0 1.5 40");
    let e = expect_error(&text, "GLAS", "MIRROR");
    assert!(e.message.contains("SURF 1 is a mirror"), "{e}");
    assert!(e.message.contains("docs/formats.md"), "{e}");
}

#[test]
fn a_stop_on_a_lens_surface_gets_a_flat_stop_in_its_vertex_plane() {
    let text = edited("SURF 3\n  STOP\n", "SURF 3\n").replace(
        "SURF 1\n  TYPE STANDARD\n",
        "SURF 1\n  STOP\n  TYPE STANDARD\n",
    );
    let lens = parse(&text).unwrap();
    let s = &lens.system;
    assert_eq!(s.surfaces.len(), 5);
    assert_eq!(s.surfaces[0].kind, SurfaceKind::ApertureStop);
    assert_eq!(
        (s.surfaces[0].curvature, s.surfaces[0].thickness),
        (0.0, 0.0)
    );
    assert_eq!(s.surfaces[0].medium, Medium::Air);
    // Nothing in front of the stop: its semi-diameter is half the ENPD.
    assert_eq!(s.surfaces[0].semi_diameter, 5.0);
    // The old stop surface is now a flat air surface with a derived semi-diameter.
    assert_eq!(s.surfaces[3].kind, SurfaceKind::Refracting);
    assert!(
        lens.warnings
            .iter()
            .any(|w| w.contains("a flat aperture stop is inserted"))
    );
    // Without STOP, surface 1 is the stop (as in Zemax), with a warning.
    let none = edited("SURF 3\n  STOP\n", "SURF 3\n");
    let lens = parse(&none).unwrap();
    assert_eq!(lens.system.stop_index(), Some(0));
    assert!(
        lens.warnings.iter().any(|w| w.contains("no STOP")),
        "{:?}",
        lens.warnings
    );
    // Two stops are an error at the second.
    let two = edited("SURF 2\n", "SURF 2\n  STOP\n");
    let e = expect_error(&two, "STOP", "STOP\n  TYPE STANDARD\n  CURV 0.0");
    assert!(
        e.message
            .contains("a second STOP (SURF 3; the first is SURF 2)"),
        "{e}"
    );
}

#[test]
fn the_stop_is_sized_by_enpd_fnum_or_its_own_semi_diameter() {
    let fnum = parse(&edited("ENPD 10", "FNUM 4 0")).unwrap().system;
    let p = analyse(&fnum, 587.5618).unwrap();
    assert!((p.f_number - 4.0).abs() < 1e-12, "{p:?}");
    let float = parse(&edited("ENPD 10", "FLOA").replace("  DISZ 40\n", "  DISZ 40\n  DIAM 3.5\n"))
        .unwrap()
        .system;
    assert_eq!(float.surfaces[2].semi_diameter, 3.5);
    let text = edited("ENPD 10", "FLOA");
    let e = parse(&text).unwrap_err();
    assert!(e.message.contains("the stop cannot be sized"), "{e}");
    let text = edited("ENPD 10", "ENPD -3");
    let e = expect_error(&text, "ENPD", "ENPD -3");
    assert!(e.message.contains("must be positive"), "{e}");
}

#[test]
fn missing_semi_diameters_come_from_marginal_and_chief_rays() {
    let text = edited("  DIAM 12 0 0 0 1 \"\"\nSURF 2", "SURF 2");
    let lens = parse(&text).unwrap();
    let s = &lens.system;
    // Surface 0 is the first vertex: the marginal ray is at the pupil radius times the
    // stop's magnification a₀/a_stop = 1/a_stop, the chief ray is tan(10°)·(b₀ − a₀ b/a) with
    // b₀ = 0. Recompute with the paraxial module's entrance pupil: y = EPD/2 at surface 0,
    // chief height = −tan(10°)·(entrance pupil position).
    let p = analyse(s, 587.5618).unwrap();
    let marginal = p.entrance_pupil_diameter_mm / 2.0;
    let chief = 10f64.to_radians().tan() * p.entrance_pupil_z_mm;
    let expected = 1.05 * (marginal.abs() + chief.abs());
    assert!(
        (s.surfaces[0].semi_diameter - expected).abs() < 1e-12,
        "{} vs {expected}",
        s.surfaces[0].semi_diameter
    );
    assert!(
        lens.warnings
            .iter()
            .any(|w| w.contains("1 surface(s) without DIAM"))
    );
    assert!(s.notes.contains("1.05 × (|paraxial marginal ray height|"));
}

const CONFIGS: &str = "MNUM 3 1
THIC 2 1 10 0 0 0 1 1 1 0 0 \"\" 0
THIC 2 2 12 0 0 0 1 1 1 0 0 \"\" 0
THIC 2 3 14 0 0 0 1 1 1 0 0 \"\" 0
APER 0 1 10 0 0 0 1 1 1 0 0 \"\" 0
APER 0 2 8 0 0 0 1 1 1 0 0 \"\" 0
APER 0 3 6 0 0 0 1 1 1 0 0 \"\" 0
GLSS 1 2 N-SF6 0 0 0 1 1 1 0 0 \"\" 0
";

#[test]
fn configurations_are_selected_by_number() {
    let text = format!("{SINGLET}{CONFIGS}");
    let active = parse(&text).unwrap();
    assert!(
        active.warnings[0].contains("the file has 3 configurations; configuration 1"),
        "{:?}",
        active.warnings
    );
    let third = parse_zmx(&text, "test.zmx", Some(3)).unwrap();
    assert_eq!(third.system.surfaces[1].thickness, 14.0);
    let p = analyse(&third.system, 587.5618).unwrap();
    assert!((p.entrance_pupil_diameter_mm - 6.0).abs() < 1e-12);
    assert!(
        third
            .warnings
            .iter()
            .any(|w| w.contains("operand GLSS is not applied")),
        "{:?}",
        third.warnings
    );
    assert!(third.system.notes.contains("Configuration 3 of 3."));
    let first = parse_zmx(&text, "test.zmx", Some(1)).unwrap();
    assert_eq!(first.system.surfaces, active.system.surfaces);
    for bad in [0, 4] {
        let e = parse_zmx(&text, "test.zmx", Some(bad)).unwrap_err();
        assert_eq!(
            (e.field.as_str(), e.line),
            ("MNUM", line_of(&text, "MNUM")),
            "{e}"
        );
        assert!(e.message.contains("configurations 1 to 3"), "{e}");
    }
    let e = parse_zmx(SINGLET, "test.zmx", Some(2)).unwrap_err();
    assert!(e.message.contains("the file has one configuration"), "{e}");
}

#[test]
fn validation_issues_are_reported_at_their_records() {
    let text = edited("  DISZ 10\n", "  DISZ -10\n");
    let e = expect_error(&text, "DISZ", "DISZ -10");
    assert!(
        e.message
            .contains("surface 1: must be a finite length ≥ 0 mm"),
        "{e}"
    );
    let text = edited("  CURV 0.02\n  DISZ 5\n", "  CURV 0.2\n  DISZ 5\n");
    let e = expect_error(&text, "DIAM", "DIAM 12");
    assert!(e.message.contains("exceeds what the surface allows"), "{e}");
}

#[test]
fn malformed_records_are_errors_at_line_and_column() {
    let text = edited("CURV -0.02", "CURV -0.0x2");
    let e = expect_error(&text, "CURV", "-0.0x2");
    assert_eq!(e.column, 8);
    assert!(
        e.message.contains("expected a finite number, got `-0.0x2`"),
        "{e}"
    );
    let text = edited("SURF 2", "SURF two");
    expect_error(&text, "SURF", "SURF two");
    let text = edited("  DISZ 10\n", "  DISZ\n");
    let e = expect_error(&text, "DISZ", "DISZ\n");
    assert!(e.message.contains("needs a value"), "{e}");
    let text = edited("  DISZ 10\n", "  DISZ INFINITY\n");
    expect_error(&text, "DISZ", "DISZ INFINITY\n  DIAM");
    let text = edited("MODE SEQ", "MODE NSC");
    expect_error(&text, "MODE", "MODE NSC");
    let e = parse("VERS 1\nSURF 0\n  DISZ INFINITY\nSURF 1\n").unwrap_err();
    assert!(e.message.contains("the file has 2 SURF block(s)"), "{e}");
    assert_eq!(e.line, 4);
    let e = parse("").unwrap_err();
    assert!(e.message.contains("0 SURF block(s)"), "{e}");
    let e =
        parse("SURF 0\n  DISZ INFINITY\nSURF 1\n  TYPE COORDBRK\n  DISZ 5\nSURF 2\n").unwrap_err();
    assert!(e.message.contains("only coordinate breaks"), "{e}");
    assert_eq!(e.line, 6);
}

#[test]
fn a_finite_object_distance_is_kept_as_a_warning() {
    let text = edited("  DISZ INFINITY", "  DISZ 500");
    let lens = parse(&text).unwrap();
    assert!(
        lens.warnings
            .iter()
            .any(|w| w.contains("the object is 500 mm in front")),
        "{:?}",
        lens.warnings
    );
    let text = edited("  DISZ INFINITY", "  DISZ -5");
    expect_error(&text, "DISZ", "DISZ -5");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_text_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let text = String::from_utf8_lossy(&bytes);
        if let Err(e) = parse(&text) {
            prop_assert_eq!(e.file, "test.zmx");
        }
    }

    #[test]
    fn mutated_files_never_panic(cut in 0usize..1000, insert in "[A-Z0-9 .\\-\n]{0,12}") {
        let at = SINGLET.char_indices().map(|(i, _)| i).nth(cut % SINGLET.len()).unwrap_or(0);
        let text = format!("{}{insert}{}", &SINGLET[..at], &SINGLET[at..]);
        let _ = parse(&text);
        let truncated = &SINGLET[..at];
        if let Err(e) = parse(truncated) {
            prop_assert!(e.line <= truncated.lines().count().max(1) + 1, "{}", e);
        }
    }
}

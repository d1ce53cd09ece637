//! Tests of OpenLensFlare XML reading and writing, against OpenLensFlare's own example files
//! (copied to `lenses/sources/openlensflare/`) and hand-made bad inputs.

use std::path::{Path, PathBuf};

use proptest::prelude::*;

use super::read::parse_document;
use super::{parse_olf_xml, write_olf_xml, write_xml};
use crate::coating::{Coating, CoatingLayer};
use crate::glass::GlassCatalog;
use crate::io::{LensFileError, read_lens};
use crate::lens_kind::LensKind;
use crate::system::{LensSystem, Medium, Surface, SurfaceKind};

fn olf_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/sources/openlensflare")
}

/// OpenLensFlare's example systems: (file name, text).
fn olf_files() -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = std::fs::read_dir(olf_dir())
        .expect("lenses/sources/openlensflare exists")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&p).expect("readable"))
        })
        .collect();
    files.sort();
    files
}

#[test]
fn every_openlensflare_file_parses_without_warnings() {
    let files = olf_files();
    assert_eq!(files.len(), 10, "the ten OpenLensFlare example systems");
    for (name, text) in &files {
        let lens = parse_olf_xml(text, name).unwrap_or_else(|e| panic!("{e}"));
        assert!(lens.warnings.is_empty(), "{name}: {:?}", lens.warnings);
        let s = &lens.system;
        assert_eq!(
            s.surfaces.last().unwrap().kind,
            SurfaceKind::Sensor,
            "{name}"
        );
        assert!(s.stop_index().is_some(), "{name}");
        assert_eq!((s.film_width_mm, s.film_height_mm), (36.0, 24.0), "{name}");
    }
}

#[test]
fn heliar_tronnier_reads_as_openlensflare_means_it() {
    let text = std::fs::read_to_string(olf_dir().join("heliar-tronnier.xml")).unwrap();
    let s = parse_olf_xml(&text, "heliar-tronnier.xml").unwrap().system;
    assert_eq!(s.name, "heliar-tronnier");
    assert_eq!(s.f_number, Some(22.0));
    assert_eq!(s.stated_efl_mm, Some(100.0));
    assert_eq!(s.field_of_view_deg, Some(60.0));
    assert_eq!(s.surfaces.len(), 10);
    let first = &s.surfaces[0];
    assert_eq!(first.kind, SurfaceKind::Refracting);
    assert_eq!(first.curvature, 1.0 / 30.809999);
    assert_eq!(first.semi_diameter, 14.5);
    assert_eq!(first.thickness, 7.7);
    assert_eq!(
        first.medium,
        Medium::Model {
            nd: 1.652,
            vd: Some(58.57)
        }
    );
    assert_eq!(
        first.coating,
        Coating::SingleLayer {
            design_wavelength_nm: 620.0,
            index: 1.38
        }
    );
    assert_eq!(first.mask, None);
    // n = 1 with OpenLensFlare's dummy Abbe number 89.3 is air.
    assert_eq!(s.surfaces[2].medium, Medium::Air);
    let stop = &s.surfaces[5];
    assert_eq!(s.stop_index(), Some(5));
    assert_eq!(stop.semi_diameter, 11.6);
    assert_eq!(stop.mask.as_deref(), Some("apertureDist.bmp"));
    assert_eq!(stop.mask_ft.as_deref(), Some("apertureFT.bmp"));
    // Radius 0 is flat.
    assert_eq!(s.surfaces[6].curvature, 0.0);
    let sensor = &s.surfaces[9];
    assert_eq!(sensor.kind, SurfaceKind::Sensor);
    assert_eq!(sensor.semi_diameter, 18.0);
    assert_eq!(sensor.coating, Coating::None);
}

#[test]
fn every_openlensflare_file_round_trips_through_our_writer() {
    for (name, text) in olf_files() {
        let first = parse_olf_xml(&text, &name).unwrap().system;
        let written = write_xml(&first);
        let again = parse_olf_xml(&written, &name).unwrap_or_else(|e| panic!("{e}\n{written}"));
        assert!(again.warnings.is_empty(), "{name}: {:?}", again.warnings);
        assert_eq!(again.system, first, "{name}");
        // Writing is deterministic: the second write is the same text.
        assert_eq!(write_xml(&again.system), written, "{name}");
    }
}

#[test]
fn strict_openlensflare_export_has_only_openlensflare_tags() {
    let known = [
        "opticalSystem",
        "name",
        "fnumber",
        "effectiveFocalLength",
        "fieldOfView",
        "filmWidth",
        "filmHeight",
        "elements",
        "element",
        "type",
        "height",
        "thickness",
        "radius",
        "refractiveIndex",
        "abbeNumber",
        "coatingLambda",
        "coatingIor",
        "mask",
        "maskFT",
    ];
    for (name, text) in olf_files() {
        let mut first = parse_olf_xml(&text, &name).unwrap().system;
        first.notes = "a note -- with dashes & <angle brackets>".into();
        let olf = write_olf_xml(&first);
        let root = crate::io::xml_tree::parse(&olf).unwrap();
        let mut stack = vec![&root];
        while let Some(n) = stack.pop() {
            assert!(known.contains(&n.name.as_str()), "{name}: <{}>", n.name);
            stack.extend(&n.children);
        }
        // Back in: equal up to the radius ↔ curvature conversion and the dropped notes.
        let back = parse_olf_xml(&olf, &name).unwrap().system;
        assert_eq!(back.surfaces.len(), first.surfaces.len());
        for (a, b) in back.surfaces.iter().zip(&first.surfaces) {
            assert!((a.curvature - b.curvature).abs() <= 1e-15 * b.curvature.abs());
            assert_eq!((&a.medium, &a.coating), (&b.medium, &b.coating));
        }
        assert_eq!(back.notes, "");
    }
}

#[test]
fn our_extensions_round_trip() {
    let glass = GlassCatalog::bundled().find("N-BK7").unwrap();
    let mut s = small_system();
    s.notes = "line one & <two>\nline three".into();
    s.source = "hand made".into();
    s.surfaces[0].medium = Medium::Glass {
        name: glass.canonical_name(),
        dispersion: glass.dispersion.clone(),
    };
    s.surfaces[0].conic = -1.0;
    s.surfaces[0].aspheric = [0.0, 1e-7, -2.5e-11, 0.0, 0.0, 0.0, 0.0, 0.0];
    s.surfaces[1].medium = Medium::Model { nd: 1.6, vd: None };
    s.surfaces[1].coating = Coating::Stack(vec![
        CoatingLayer {
            index: 1.38,
            thickness_nm: 99.6,
        },
        CoatingLayer {
            index: 2.1,
            thickness_nm: 65.5,
        },
    ]);
    s.f_number = None;
    s.primary_wavelength_nm = Some(780.0);
    let text = write_xml(&s);
    assert!(text.contains("<glass>SCHOTT:N-BK7</glass>"), "{text}");
    assert!(
        text.contains(
            "<filmHeight>24</filmHeight>\n    <primaryWavelength>780</primaryWavelength>"
        ),
        "{text}"
    );
    assert!(text.contains("<abbeNumber>inf</abbeNumber>"), "{text}");
    assert!(
        text.contains("<aspheric>0 0.0000001 -0.000000000025</aspheric>"),
        "{text}"
    );
    assert!(text.contains("<type>lensAspherical</type>"), "{text}");
    // The glass's nd is written for OpenLensFlare.
    assert!(
        text.contains("<refractiveIndex>1.5168</refractiveIndex>"),
        "{text}"
    );
    let back = parse_olf_xml(&text, "ours.xml").unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    assert_eq!(back.system, s);
}

#[test]
fn maker_kind_and_nominal_focal_length_round_trip_after_the_name() {
    let mut s = small_system();
    s.maker = "Carl Zeiss & Co".into();
    s.kind = vec![LensKind::Zoom, LensKind::Cine];
    s.nominal_focal_mm = Some([24.0, 70.5]);
    let text = write_xml(&s);
    assert!(
        text.contains(
            "<name>test</name>\n    <maker>Carl Zeiss &amp; Co</maker>\n    \
             <kind>zoom cine</kind>\n    <nominalFocalLength>24 70.5</nominalFocalLength>\n"
        ),
        "{text}"
    );
    let back = parse_olf_xml(&text, "ours.xml").unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    assert_eq!(back.system, s);
    // A prime's is one number.
    s.nominal_focal_mm = Some([135.0, 135.0]);
    let text = write_xml(&s);
    assert!(
        text.contains("<nominalFocalLength>135</nominalFocalLength>"),
        "{text}"
    );
    assert_eq!(parse_olf_xml(&text, "ours.xml").unwrap().system, s);
    // OpenLensFlare's loader would refuse them: the strict export leaves them out.
    let strict = write_olf_xml(&s);
    for tag in ["<maker>", "<kind>", "<nominalFocalLength>"] {
        assert!(!strict.contains(tag), "{strict}");
    }
}

#[test]
fn a_file_without_maker_kind_or_nominal_focal_length_reads_as_before() {
    let s = small_system();
    assert_eq!(
        (s.maker.as_str(), s.kind.as_slice(), s.nominal_focal_mm),
        ("", &[][..], None)
    );
    let text = write_xml(&s);
    for tag in ["<maker>", "<kind>", "<nominalFocalLength>"] {
        assert!(!text.contains(tag), "{text}");
    }
}

#[test]
fn bad_kinds_and_nominal_focal_lengths_are_errors_at_their_tags() {
    let name = "<name>test</name>";
    let e = expect_error(name, "<name>test</name><kind>prime wide</kind>", "kind", 3);
    assert!(e.message.contains("unknown lens kind `wide`"), "{e}");
    let e = expect_error(name, "<name>test</name><kind>prime zoom</kind>", "kind", 3);
    assert!(e.message.contains("not both"), "{e}");
    for bad in ["70 24", "", "24 70 200", "0 35", "24 inf", "24 mm", "-50"] {
        let e = expect_error(
            name,
            &format!("<name>test</name><nominalFocalLength>{bad}</nominalFocalLength>"),
            "nominalFocalLength",
            3,
        );
        assert!(e.message.contains(&format!("got `{bad}`")), "{e}");
    }
}

#[test]
fn radius_is_the_shortest_decimal_whose_reciprocal_is_the_curvature() {
    let mut s = small_system();
    s.surfaces[0].curvature = 1.0 / 25.462532;
    s.surfaces[1].curvature = 1e-320;
    let text = write_xml(&s);
    assert!(text.contains("<radius>25.462532</radius>"), "{text}");
    // A radius too large to be finite is flat to OpenLensFlare; the curvature stays exact.
    assert!(
        text.contains("<radius>0</radius>\n            <curvature>0.00000"),
        "{text}"
    );
    assert_eq!(parse_document(&text, "r.xml").unwrap().system, s);
}

/// A valid four-surface system; the line numbers of [`SMALL`] are used by the error tests.
fn small_system() -> LensSystem {
    parse_olf_xml(SMALL, "test.xml").unwrap().system
}

/// A valid singlet with a stop and a sensor (unit tests across the crate use it).
pub(crate) const SMALL: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<opticalSystem>
    <name>test</name>
    <fnumber>4</fnumber>
    <filmWidth>36</filmWidth>
    <filmHeight>24</filmHeight>
    <elements>
        <element>
            <type>lensSpherical</type>
            <height>10</height>
            <thickness>5</thickness>
            <radius>50</radius>
            <refractiveIndex>1.5168</refractiveIndex>
            <abbeNumber>64.17</abbeNumber>
        </element>
        <element>
            <type>lensSpherical</type>
            <height>10</height>
            <thickness>2</thickness>
            <radius>-50</radius>
            <refractiveIndex>1</refractiveIndex>
        </element>
        <element>
            <type>apertureStop</type>
            <height>8</height>
            <thickness>45</thickness>
        </element>
        <element>
            <type>sensor</type>
            <height>21.6</height>
        </element>
    </elements>
</opticalSystem>
"#;

/// Parses SMALL with `from` replaced by `to` (which must occur exactly once).
fn parse_edited(from: &str, to: &str) -> Result<crate::io::LoadedLens, LensFileError> {
    assert_eq!(SMALL.matches(from).count(), 1, "`{from}` must be unique");
    parse_olf_xml(&SMALL.replacen(from, to, 1), "test.xml")
}

fn expect_error(from: &str, to: &str, field: &str, line: usize) -> LensFileError {
    let e = parse_edited(from, to).expect_err("the edit must be rejected");
    assert_eq!((e.field.as_str(), e.line), (field, line), "{e}");
    assert_eq!(e.file, "test.xml");
    assert!(e.column >= 1, "{e}");
    e
}

#[test]
fn the_small_system_is_valid_and_quiet() {
    let lens = parse_olf_xml(SMALL, "test.xml").unwrap();
    assert!(lens.warnings.is_empty(), "{:?}", lens.warnings);
    assert_eq!(lens.system.surfaces.len(), 4);
    assert_eq!(lens.system.surfaces[2].medium, Medium::Air);
}

#[test]
fn nan_is_reported_at_the_value() {
    let e = expect_error("<radius>50<", "<radius>NaN<", "radius", 12);
    assert_eq!(
        e.to_string(),
        "test.xml:12:21: field `radius`: must be finite, got NaN"
    );
    expect_error("<thickness>5<", "<thickness>inf<", "thickness", 11);
}

#[test]
fn non_numeric_values_are_errors() {
    let e = expect_error("<thickness>5<", "<thickness>5 mm<", "thickness", 11);
    assert!(e.message.contains("expected a number, got `5 mm`"), "{e}");
    expect_error("<filmWidth>36<", "<filmWidth>wide<", "filmWidth", 5);
    expect_error(
        "<thickness>5</thickness>",
        "<thickness>5</thickness><aspheric>1e-5 x</aspheric>",
        "aspheric",
        11,
    );
}

#[test]
fn unknown_element_type_is_an_error() {
    let e = expect_error("<type>apertureStop<", "<type>iris<", "type", 24);
    assert!(e.message.contains("unknown element type `iris`"), "{e}");
}

#[test]
fn unknown_glass_is_an_error_with_suggestions() {
    let e = expect_error(
        "<abbeNumber>64.17</abbeNumber>",
        "<abbeNumber>64.17</abbeNumber>\n            <glass>N-BK8</glass>",
        "glass",
        15,
    );
    assert_eq!(e.column, 20);
    assert!(e.message.contains("unknown glass `N-BK8`"), "{e}");
    assert!(e.message.contains("SCHOTT:N-BK7"), "{e}");
}

#[test]
fn negative_semi_diameter_is_an_error() {
    let e = expect_error("<height>8<", "<height>-8<", "height", 25);
    assert!(e.message.contains("negative"), "{e}");
}

#[test]
fn missing_stop_points_at_the_elements_tag() {
    let e = expect_error("<type>apertureStop<", "<type>lensSpherical<", "type", 7);
    assert!(e.message.contains("no aperture stop"), "{e}");
}

#[test]
fn sensor_before_the_end_points_at_its_type() {
    // Swap the stop and the sensor.
    let text = SMALL
        .replacen("<type>apertureStop</type>", "<type>TMP</type>", 1)
        .replacen("<type>sensor</type>", "<type>apertureStop</type>", 1)
        .replacen("<type>TMP</type>", "<type>sensor</type>", 1);
    let e = parse_olf_xml(&text, "test.xml").unwrap_err();
    assert_eq!(
        (e.field.as_str(), e.line, e.column),
        ("type", 24, 19),
        "{e}"
    );
    assert!(
        e.message.contains("the sensor must be the last element"),
        "{e}"
    );
    assert!(e.message.contains("and 1 more"), "{e}");
}

#[test]
fn validation_issues_map_to_their_fields() {
    // A semi-diameter larger than the radius of curvature.
    let e = expect_error(
        "<height>10</height>\n            <thickness>5<",
        "<height>60</height>\n            <thickness>5<",
        "height",
        10,
    );
    assert!(e.message.contains("exceeds"), "{e}");
    // A coating with a negative index.
    expect_error(
        "<thickness>45</thickness>",
        "<thickness>45</thickness><coatingLambda>550</coatingLambda><coatingIor>-1</coatingIor>",
        "coatingIor",
        26,
    );
    // A negative f-number is a system field.
    expect_error("<fnumber>4<", "<fnumber>-4<", "fnumber", 4);
    // So is the primary wavelength.
    let e = expect_error(
        "<fnumber>4</fnumber>",
        "<fnumber>4</fnumber><primaryWavelength>-550</primaryWavelength>",
        "primaryWavelength",
        4,
    );
    assert!(e.message.contains("positive wavelength"), "{e}");
    // A stop must be flat.
    expect_error(
        "<thickness>45</thickness>",
        "<thickness>45</thickness><radius>30</radius>",
        "radius",
        26,
    );
}

#[test]
fn malformed_and_truncated_xml_name_line_and_element() {
    let e = expect_error("<radius>50</radius>", "<radius>50</radiu>", "radius", 12);
    assert!(e.message.contains("malformed XML"), "{e}");
    let cut = &SMALL[..SMALL.find("<refractiveIndex>1.5168").unwrap() + 20];
    let e = parse_olf_xml(cut, "test.xml").unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("refractiveIndex", 13), "{e}");
    assert!(e.message.contains("unexpected end of file"), "{e}");
    let e = parse_olf_xml("", "empty.xml").unwrap_err();
    assert_eq!(e.line, 1);
    let e = parse_olf_xml("<lens/>", "other.xml").unwrap_err();
    assert!(e.message.contains("<opticalSystem>"), "{e}");
}

#[test]
fn unknown_tags_and_defaults_are_warnings() {
    let lens = parse_edited("<abbeNumber>64.17</abbeNumber>", "<colour>blue</colour>").unwrap();
    assert_eq!(lens.warnings.len(), 2, "{:?}", lens.warnings);
    assert!(
        lens.warnings[0].starts_with("test.xml:14:13: unknown tag <colour>"),
        "{:?}",
        lens.warnings
    );
    assert!(
        lens.warnings[1].contains("without <abbeNumber>"),
        "{:?}",
        lens.warnings
    );
    assert_eq!(
        lens.system.surfaces[0].medium,
        Medium::Model {
            nd: 1.5168,
            vd: None
        }
    );
    // Missing film size and a missing radius are defaults with warnings.
    let lens = parse_edited("<filmWidth>36</filmWidth>", "").unwrap();
    assert!(
        lens.warnings[0].contains("no <filmWidth>; using 36 mm"),
        "{:?}",
        lens.warnings
    );
    let lens = parse_edited("<radius>-50</radius>", "").unwrap();
    assert!(lens.warnings[0].contains("flat"), "{:?}", lens.warnings);
    assert_eq!(lens.system.surfaces[1].curvature, 0.0);
}

#[test]
fn curvature_takes_precedence_over_radius_and_disagreement_warns() {
    let lens = parse_edited(
        "<radius>50</radius>",
        "<radius>50</radius><curvature>0.025</curvature>",
    )
    .unwrap();
    assert_eq!(lens.system.surfaces[0].curvature, 0.025);
    assert!(
        lens.warnings[0].contains("disagrees"),
        "{:?}",
        lens.warnings
    );
}

#[test]
fn read_lens_dispatches_on_extension_and_names_the_file() {
    let e = read_lens(Path::new("lenses/example.zmx")).unwrap_err();
    assert!(e.is_whole_file());
    assert!(
        e.to_string()
            .starts_with("lenses/example.zmx: cannot read the file"),
        "{e}"
    );
    let e = read_lens(Path::new("lenses/example.obj")).unwrap_err();
    assert!(e.message.contains("`.obj` are not supported"), "{e}");
    let e = read_lens(Path::new("/nonexistent/flarebench/lens.xml")).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/flarebench/lens.xml: cannot read the file"),
        "{e}"
    );
    let ok = read_lens(&olf_dir().join("Lensbaby.xml")).unwrap();
    assert_eq!(ok.system.name, "lensbaby");
}

// --- property tests --------------------------------------------------------------------------

fn finite() -> impl Strategy<Value = f64> {
    any::<f64>().prop_filter("finite", |v| v.is_finite())
}

fn nonzero() -> impl Strategy<Value = f64> {
    finite().prop_filter("non-zero", |v| *v != 0.0)
}

fn text_strategy(pattern: &'static str) -> impl Strategy<Value = String> {
    pattern.prop_map(|s: String| s.trim().to_string())
}

fn medium() -> impl Strategy<Value = Medium> {
    const GLASSES: &[&str] = &[
        "SCHOTT:N-BK7",
        "SCHOTT:SF1",
        "OHARA:S-LAH79",
        "SCHOTT:N-LAK9",
    ];
    prop_oneof![
        Just(Medium::Air),
        (
            finite().prop_filter("not air", |n| *n != 1.0),
            proptest::option::of(finite())
        )
            .prop_map(|(nd, vd)| Medium::Model { nd, vd }),
        proptest::sample::select(GLASSES).prop_map(|g| {
            let e = GlassCatalog::bundled().find(g).unwrap();
            Medium::Glass {
                name: e.canonical_name(),
                dispersion: e.dispersion.clone(),
            }
        }),
    ]
}

fn coating() -> impl Strategy<Value = Coating> {
    prop_oneof![
        Just(Coating::None),
        (nonzero(), nonzero()).prop_map(|(design_wavelength_nm, index)| Coating::SingleLayer {
            design_wavelength_nm,
            index
        }),
        proptest::collection::vec(
            (finite(), finite()).prop_map(|(index, thickness_nm)| CoatingLayer {
                index,
                thickness_nm
            }),
            0..3
        )
        .prop_map(Coating::Stack),
    ]
}

fn surface() -> impl Strategy<Value = Surface> {
    let kind = proptest::sample::select(
        &[
            SurfaceKind::Refracting,
            SurfaceKind::ApertureStop,
            SurfaceKind::Sensor,
        ][..],
    );
    let mask = || {
        proptest::option::of(text_strategy("[a-zA-Z0-9_.&<>]{1,12}"))
            .prop_map(|m| m.filter(|s| !s.is_empty()))
    };
    (
        kind,
        finite(),
        finite(),
        proptest::array::uniform8(finite()),
        finite(),
        medium(),
        finite().prop_map(f64::abs),
        coating(),
        mask(),
        mask(),
    )
        .prop_map(
            |(
                kind,
                curvature,
                conic,
                aspheric,
                thickness,
                medium,
                semi_diameter,
                coating,
                mask,
                mask_ft,
            )| Surface {
                kind,
                curvature,
                conic,
                aspheric,
                thickness,
                medium,
                semi_diameter,
                coating,
                mask,
                mask_ft,
            },
        )
}

fn system() -> impl Strategy<Value = LensSystem> {
    let opt = || proptest::option::of(nonzero());
    (
        text_strategy("[a-zA-Z0-9][a-zA-Z0-9 &<>._-]{0,20}"),
        (opt(), opt(), opt(), opt()),
        (finite(), finite()),
        text_strategy("[a-zA-Z0-9 &<>\"'.,;:()/\n-]{0,60}"),
        text_strategy("[a-zA-Z0-9 &<>.,:/-]{0,40}"),
        proptest::collection::vec(surface(), 0..6),
        (
            text_strategy("[a-zA-Z0-9 &<>.-]{0,16}"),
            proptest::sample::subsequence(LensKind::ALL.to_vec(), 0..4),
            proptest::option::of((1e-3f64..1e4, prop_oneof![Just(1.0), 1.0f64..10.0])),
        ),
    )
        .prop_map(
            |(
                name,
                (f_number, stated_efl_mm, field_of_view_deg, primary_wavelength_nm),
                (w, h),
                notes,
                source,
                surfaces,
                (maker, mut kind, range),
            )| {
                if kind.contains(&LensKind::Prime) {
                    kind.retain(|k| *k != LensKind::Zoom);
                }
                LensSystem {
                    name,
                    maker,
                    kind,
                    nominal_focal_mm: range.map(|(a, k)| [a, a * k]),
                    f_number,
                    stated_efl_mm,
                    field_of_view_deg,
                    primary_wavelength_nm,
                    film_width_mm: w,
                    film_height_mm: h,
                    notes,
                    source,
                    surfaces,
                    sensor_stack: None,
                }
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn writing_then_reading_gives_the_same_system(s in system()) {
        let text = write_xml(&s);
        let back = parse_document(&text, "prop.xml")
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        prop_assert_eq!(back.system, s);
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let text = String::from_utf8_lossy(&bytes);
        if let Err(e) = parse_olf_xml(&text, "random.xml") {
            prop_assert!(e.line >= 1);
        }
    }

    #[test]
    fn random_xmlish_text_never_panics(text in "(<[a-zA-Z/]{0,12}>|[0-9 .eE+-]{0,6}|&[a-z#0-9]{0,5};?|\n){0,80}") {
        let _ = parse_olf_xml(&text, "xmlish.xml");
    }

    #[test]
    fn truncated_real_files_never_panic(file in 0usize..10, cut in 0.0f64..1.0) {
        let files = olf_files();
        let (name, text) = &files[file % files.len()];
        let mut at = ((text.len() as f64) * cut) as usize;
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        if let Err(e) = parse_olf_xml(&text[..at], name) {
            prop_assert!(e.line >= 1, "{}", e);
            prop_assert!(e.column >= 1, "{}", e);
        }
    }

    #[test]
    fn mutated_real_files_never_panic(
        file in 0usize..10,
        edits in proptest::collection::vec((0.0f64..1.0, 0x20u8..0x7f), 1..8),
    ) {
        let files = olf_files();
        let (name, text) = &files[file % files.len()];
        let mut bytes = text.clone().into_bytes();
        for (pos, byte) in edits {
            let i = ((bytes.len() as f64) * pos) as usize;
            if i < bytes.len() {
                bytes[i] = byte;
            }
        }
        let mutated = String::from_utf8_lossy(&bytes);
        let _ = parse_olf_xml(&mutated, name);
    }
}

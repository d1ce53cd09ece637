//! Cell parsing and validation of the editor: numbers, ranges, glass names (catalogue lookup,
//! completion), model glasses, coatings, header fields, and the cell editor's caret.

use flarebench::edit::cell::{
    CellEditor, Column, HeaderField, edit_text, glass_completions, parse_cell, parse_header,
    parse_medium, show,
};
use flarebench::edit::document::Header;
use flarebench_sdk::{Coating, Medium, Surface};

/// N-BK7's nd from its dispersion formula against Schott's catalogue value, printed to 4
/// decimals.
const CATALOGUE_ND_TOL: f64 = 1e-4;
/// N-BK7's Abbe number from its dispersion formula against Schott's printed 64.17.
const CATALOGUE_VD_TOL: f64 = 0.02;

fn lens_surface() -> Surface {
    Surface::spherical(
        50.0,
        4.0,
        Medium::Model {
            nd: 1.5,
            vd: Some(60.0),
        },
        10.0,
    )
}

#[test]
fn numbers_are_parsed_and_ranges_checked() {
    let s = lens_surface();
    assert_eq!(
        parse_cell(&s, Column::Thickness, " 7.25 ")
            .unwrap()
            .thickness,
        7.25
    );
    assert_eq!(
        parse_cell(&s, Column::Radius, "-20").unwrap().curvature,
        -0.05
    );
    assert_eq!(
        parse_cell(&s, Column::Radius, "flat").unwrap().curvature,
        0.0
    );
    assert_eq!(parse_cell(&s, Column::Radius, "0").unwrap().curvature, 0.0);
    assert_eq!(parse_cell(&s, Column::Conic, "-1").unwrap().conic, -1.0);
    assert_eq!(
        parse_cell(&s, Column::SemiDiameter, "12")
            .unwrap()
            .semi_diameter,
        12.0
    );
    for (col, text, needle) in [
        (Column::Thickness, "abc", "not a number"),
        (Column::Thickness, "-1", "≥ 0"),
        (Column::Thickness, "NaN", "not a number"),
        (Column::Radius, "inf2", "not a number"),
        (Column::SemiDiameter, "0", "> 0"),
        (Column::Nd, "0.9", "between 1 and 4"),
        (Column::Vd, "0", "(0, 200]"),
        (Column::Kind, "mirror", "refracting, stop or sensor"),
        (Column::Coating, "1.38", "INDEX@WAVELENGTH_NM"),
        (Column::Coating, "1.38@50", "200–2500"),
    ] {
        let err = parse_cell(&s, col, text).unwrap_err();
        assert!(err.contains(needle), "{col:?} `{text}`: {err}");
    }
}

#[test]
fn glass_cells_accept_catalogue_names_and_model_glasses() {
    let m = parse_medium("n-bk7").unwrap();
    let Medium::Glass { name, .. } = &m else {
        panic!("{m:?}")
    };
    assert_eq!(name, "SCHOTT:N-BK7");
    // Schott's catalogue value: nd = 1.5168, Vd = 64.17.
    assert!((m.nd() - 1.5168).abs() < CATALOGUE_ND_TOL, "{}", m.nd());
    assert!((m.vd().unwrap() - 64.17).abs() < CATALOGUE_VD_TOL);
    assert_eq!(
        parse_medium("1.62/36.4").unwrap(),
        Medium::Model {
            nd: 1.62,
            vd: Some(36.4)
        }
    );
    assert_eq!(
        parse_medium("1.7").unwrap(),
        Medium::Model { nd: 1.7, vd: None }
    );
    assert_eq!(parse_medium("AIR").unwrap(), Medium::Air);
    let err = parse_medium("N-BK77").unwrap_err();
    assert!(err.contains("N-BK7"), "suggests the close name: {err}");
    assert!(parse_medium("").is_err());
    assert!(parse_medium("1.5/-3").is_err());
}

#[test]
fn nd_and_vd_cells_turn_the_medium_into_a_model_glass() {
    let s = Surface {
        medium: parse_medium("N-BK7").unwrap(),
        ..lens_surface()
    };
    let edited = parse_cell(&s, Column::Nd, "1.6").unwrap();
    let Medium::Model { nd, vd: Some(vd) } = edited.medium else {
        panic!("{:?}", edited.medium)
    };
    assert_eq!(nd, 1.6);
    assert!(
        (vd - 64.17).abs() < CATALOGUE_VD_TOL,
        "keeps the glass's Abbe number"
    );
    let edited = parse_cell(&edited, Column::Vd, "-").unwrap();
    assert_eq!(edited.medium, Medium::Model { nd: 1.6, vd: None });
    let air = Surface::spherical(0.0, 1.0, Medium::Air, 5.0);
    assert!(
        parse_cell(&air, Column::Vd, "50")
            .unwrap_err()
            .contains("air")
    );
}

#[test]
fn completion_lists_catalogue_names() {
    let names = glass_completions("N-BK", 64);
    assert!(names.contains(&"SCHOTT:N-BK7".to_string()), "{names:?}");
    assert!(names.iter().all(|n| n.contains(":N-BK")), "{names:?}");
    assert!(
        glass_completions("1.5", 8).is_empty(),
        "numbers are not glass names"
    );
    assert_eq!(glass_completions("N-BK", 2).len(), 2);
}

#[test]
fn coatings_round_trip_through_their_cell_text() {
    let s = parse_cell(&lens_surface(), Column::Coating, "1.38@550").unwrap();
    assert_eq!(
        s.coating,
        Coating::SingleLayer {
            design_wavelength_nm: 550.0,
            index: 1.38
        }
    );
    assert_eq!(show(&s, Column::Coating), "1.38@550");
    assert_eq!(
        parse_cell(&s, Column::Coating, "none").unwrap().coating,
        Coating::None
    );
}

#[test]
fn every_cell_parses_back_to_itself() {
    let s = Surface {
        conic: -0.5,
        coating: Coating::SingleLayer {
            design_wavelength_nm: 620.0,
            index: 1.38,
        },
        ..lens_surface()
    };
    for col in Column::ALL {
        assert_eq!(
            parse_cell(&s, col, &edit_text(&s, col)).unwrap(),
            s,
            "{col:?}"
        );
    }
}

#[test]
fn header_fields() {
    let h = Header {
        name: "x".into(),
        f_number: Some(2.0),
        film_width_mm: 36.0,
        film_height_mm: 24.0,
    };
    assert_eq!(
        parse_header(&h, HeaderField::FNumber, "open")
            .unwrap()
            .f_number,
        None
    );
    assert_eq!(
        parse_header(&h, HeaderField::FNumber, "5.6")
            .unwrap()
            .f_number,
        Some(5.6)
    );
    assert!(parse_header(&h, HeaderField::FNumber, "0").is_err());
    assert!(parse_header(&h, HeaderField::FilmWidth, "-3").is_err());
    assert!(parse_header(&h, HeaderField::Name, "  ").is_err());
    assert_eq!(
        parse_header(&h, HeaderField::FilmHeight, "15.6")
            .unwrap()
            .film_height_mm,
        15.6
    );
}

#[test]
fn cell_editor_caret() {
    let mut e = CellEditor::new("1.5".into());
    assert_eq!(e.caret, 3);
    e.move_caret(-2);
    e.insert('2');
    assert_eq!(e.text, "12.5");
    e.backspace();
    e.backspace();
    assert_eq!((e.text.as_str(), e.caret), (".5", 0));
    e.move_caret(-5);
    e.backspace();
    assert_eq!(e.caret, 0);
    e.end();
    e.insert('μ');
    e.move_caret(-1);
    e.delete();
    assert_eq!(e.text, ".5");
    let names = vec!["A".to_string(), "B".to_string()];
    e.cycle(&names, 1);
    assert_eq!(e.text, "A");
    e.cycle(&names, 1);
    e.cycle(&names, 1);
    assert_eq!(e.text, "A");
    e.cycle(&names, -1);
    assert_eq!(e.text, "B");
}

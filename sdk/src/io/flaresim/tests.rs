//! Unit tests of the `.lens` reader's pieces: clear-aperture checks and clamps on geometry
//! worked by hand, and the syntax's errors at their line and column. The files of
//! `tests/data/flaresim/` are read in `sdk/tests/flaresim.rs`.

use super::clearance::{self, CROSSING_TOL_MM};
use super::*;
use crate::system::{Medium, Surface};

/// Equal up to f64 rounding of a square root and a 50-step bisection (1e-15 relative).
const EXACT_MM: f64 = 1e-12;

/// A biconvex lens, R = ±50 mm, 2 mm thick, of clear semi-diameter `sd`.
fn biconvex(sd: f64) -> Vec<Surface> {
    let glass = Medium::Model {
        nd: 1.5,
        vd: Some(60.0),
    };
    vec![
        Surface::spherical(50.0, 2.0, glass, sd),
        Surface::spherical(-50.0, 10.0, Medium::Air, sd),
    ]
}

#[test]
fn a_biconvex_lens_too_thin_for_its_aperture_crosses_itself_where_hand_worked() {
    // Each sag at r = 10 is 50 − √(2500 − 100); the edge thickness 2 − 2·sag is −0.0204 mm.
    // They meet where the sag is 1 mm: r = √(50² − 49²) = √99.
    let sag10 = 50.0 - (2500.0_f64 - 100.0).sqrt();
    let found = clearance::check(&biconvex(10.0));
    assert!(found.beyond_radius.is_empty());
    let [c] = found.crossings[..] else {
        panic!("{found:?}")
    };
    assert_eq!(c.first, 0);
    assert!((c.depth - (2.0 * sag10 - 2.0)).abs() < EXACT_MM, "{c:?}");
    assert!((c.height - 10.0).abs() < EXACT_MM);
    assert!((c.meet - 99.0_f64.sqrt()).abs() < 1e-9, "{c:?}");
    // At the meeting height they touch: no crossing.
    assert!(clearance::check(&biconvex(99.0_f64.sqrt())).is_empty());
    // A touch within the tolerance is not a crossing either.
    let just = (2500.0 - (50.0 - 1.0 - CROSSING_TOL_MM / 4.0).powi(2)).sqrt();
    assert!(clearance::check(&biconvex(just)).is_empty());
}

#[test]
fn clamping_limits_to_the_radius_then_to_where_surfaces_meet() {
    let mut s = biconvex(60.0);
    let found = clearance::check(&s);
    assert_eq!(found.beyond_radius.len(), 2);
    let (clamps, left) = clearance::clamp(&mut s);
    assert!(left.is_empty());
    // Both to |R| = 50 first, then both to √99 where the two spheres meet.
    assert_eq!(clamps.len(), 4, "{clamps:?}");
    assert_eq!((clamps[0].from, clamps[0].to), (60.0, 50.0));
    for surface in &s {
        assert!((surface.semi_diameter - 99.0_f64.sqrt()).abs() < 1e-9);
    }
    assert!(clearance::check(&s).is_empty());
    // Faces that cross from the axis out (thickness 0) cannot be clamped apart.
    let mut flat = biconvex(10.0);
    flat[0].thickness = 0.0;
    let (clamps, left) = clearance::clamp(&mut flat);
    assert!(clamps.is_empty());
    assert_eq!((left.len(), left[0].meet), (1, 0.0));
    assert_eq!(flat[0].semi_diameter, 10.0);
}

#[test]
fn syntax_errors_name_line_column_and_field() {
    let head = "name: t\nfocal_length: 100\nsurfaces:\n";
    let cases = [
        ("  stop 2 1 0 10 0\n  50 5 1.5x 60 12 1\n", 5, 8, "ior"),
        ("  stop 2 1 0 10 0\n  50 5 1.5 60 12\n", 5, 17, "coating"),
        ("  stop 2 1 0 10 0\n  50 5 1.5 60 12 3\n", 5, 18, "coating"),
        (
            "  stop 2 1 0 10 0\n  50 nan 1.5 60 12 1\n",
            5,
            6,
            "thickness",
        ),
        (
            "  stop 2 1 0 10 0\n  50 5 1.5 60 12 1 cyl_y\n",
            5,
            20,
            "type",
        ),
        (
            "  stop 2 1 0 10 0\n  50 5 1.5 60 12 1 toric 80\n",
            5,
            20,
            "type",
        ),
        (
            "  stop 2 1 0 10 0\n  50 5 1.5 60 12 1 sph 3\n",
            5,
            24,
            "radius_y",
        ),
    ];
    for (rows, line, column, field) in cases {
        let text = format!("{head}{rows}");
        let e = parse_flaresim(&text, "t.lens", None, false).unwrap_err();
        assert_eq!(
            (e.line, e.column, e.field.as_str()),
            (line, column, field),
            "{e}"
        );
    }
    let e = parse_flaresim("name: t\n", "t.lens", None, false).unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (2, "surfaces"), "{e}");
    let e = parse_flaresim("", "t.lens", None, false).unwrap_err();
    assert_eq!((e.line, e.column, e.field.as_str()), (1, 1, "surfaces"));
}

#[test]
fn inf_and_zero_radii_are_flat_and_stop_is_case_blind() {
    let text = "surfaces:\n  STOP 2 1 0 10 0\n  inf 5 1.5 60 12 1\n  0 90 1 0 12 0\n";
    let lens = parse_flaresim(text, "dir/plate.lens", None, false);
    // A plate has no power: refused as afocal.
    let e = lens.unwrap_err();
    assert_eq!(e.field, "surfaces", "{e}");
    assert!(e.message.contains("afocal"), "{e}");
    let text = "surfaces:\n  STOP 2 1 0 10 0\n  inf 5 1.5 60 12 1\n  -77.5 90 1 0 12 0\n";
    let lens = parse_flaresim(text, "dir/plano.lens", None, false).unwrap();
    let s = &lens.system;
    assert_eq!(s.name, "plano");
    assert_eq!(s.surfaces[0].kind, SurfaceKind::ApertureStop);
    assert_eq!(s.surfaces[1].curvature, 0.0);
    assert!(lens.warnings.iter().any(|w| w.contains("no `name:`")));
}

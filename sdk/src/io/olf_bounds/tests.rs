//! Tests of the OpenLensFlare ghost-bounds reader: the bundled Heliar-Tronnier file (counts and
//! spot values checked against the file by hand), conversions, and malformed input.

use super::*;

const HELIAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../tests/data/heliar-tronnier-bounds-full.xml"
);

/// Values are written with 6 significant digits; parsing them is exact to f64 rounding.
const EXACT: f64 = 1e-12;

fn heliar() -> OlfGhostBounds {
    read_olf_bounds(Path::new(HELIAR)).expect("the bundled bounds file reads")
}

fn rect(x: f64, y: f64, w: f64, h: f64) -> OlfRect {
    OlfRect { x, y, w, h }
}

fn assert_rect(got: &OlfRect, want: OlfRect) {
    for (g, w) in [
        (got.x, want.x),
        (got.y, want.y),
        (got.w, want.w),
        (got.h, want.h),
    ] {
        assert!((g - w).abs() < EXACT, "{got:?} vs {want:?}");
    }
}

#[test]
fn the_heliar_file_holds_181_angles_of_the_same_13_ghosts() {
    let b = heliar();
    assert_eq!(b.entries.len(), 181);
    let paths: Vec<[usize; 2]> = vec![
        [1, 0],
        [2, 0],
        [2, 1],
        [3, 0],
        [3, 1],
        [3, 2],
        [4, 0],
        [4, 1],
        [4, 2],
        [4, 3],
        [7, 6],
        [8, 6],
        [8, 7],
    ];
    for (i, e) in b.entries.iter().enumerate() {
        assert_eq!(e.angle_deg, i as f64 * 0.5);
        let got: Vec<[usize; 2]> = e.ghosts.iter().map(|g| g.interfaces).collect();
        assert_eq!(got, paths, "angle {}", e.angle_deg);
        for g in &e.ghosts {
            // OpenLensFlare never computed these: its defaults, or clamped to 1.
            assert_eq!(g.avg_intensity, 1.0);
            assert_eq!((g.min_channels, g.optimal_channels), (3, 3));
            assert_eq!(g.min_rays, g.optimal_rays);
            assert!([0, 5, 16, 32, 64, 128].contains(&g.min_rays));
        }
    }
    let visible: Vec<(f64, usize)> = b
        .entries
        .iter()
        .map(|e| {
            (
                e.angle_deg,
                e.ghosts.iter().filter(|g| g.is_visible()).count(),
            )
        })
        .collect();
    assert_eq!(visible.iter().map(|v| v.1).sum::<usize>(), 574);
    assert_eq!(visible[0], (0.0, 13));
    let last = visible.iter().rfind(|v| v.1 > 0).unwrap();
    assert_eq!(*last, (33.0, 1));
    // Invisible ghosts are all −1, as OpenLensFlare writes them.
    let hidden = &b.entries[20].ghosts[4];
    assert_eq!((b.entries[20].angle_deg, hidden.interfaces), (10.0, [3, 1]));
    assert!(!hidden.is_visible());
    assert_rect(&hidden.pupil, rect(-1.0, -1.0, -1.0, -1.0));
    assert_rect(&hidden.sensor, rect(-1.0, -1.0, -1.0, -1.0));
    assert_eq!(hidden.min_rays, 0);
}

#[test]
fn spot_values_match_the_file() {
    let b = heliar();
    let g = &b.entries[0].ghosts[0];
    assert_rect(&g.pupil, rect(-0.0905307, -0.0905307, 0.181061, 0.181061));
    assert_rect(&g.sensor, rect(-1.3624, -2.04361, 2.72481, 4.08722));
    assert_eq!(g.min_rays, 5);
    let g = &b.entries[1].ghosts[0];
    assert_rect(&g.pupil, rect(-0.0905307, -0.0905307, 0.187305, 0.181061));
    let g = &b.entries[20].ghosts[2];
    assert_eq!(g.interfaces, [2, 1]);
    assert_rect(&g.pupil, rect(-0.380148, -0.131416, 0.193548, 0.262831));
    assert_rect(&g.sensor, rect(0.489508, -0.853063, 0.851058, 1.70672));
    let g = &b.entries[0].ghosts[2];
    assert_eq!(g.min_rays, 128);
}

#[test]
fn bounds_convert_to_millimetres_in_our_meridional_frame() {
    let b = heliar();
    // Heliar-Tronnier: first semi-diameter 14.5 mm, film 36 × 24 mm.
    let g = &b.entries[0].ghosts[0];
    let e = g.entrance_mm(14.5).unwrap();
    assert!((e.x0 + 0.0905307 * 14.5).abs() < EXACT && (e.y1 - 0.0905303 * 14.5).abs() < 1e-5);
    // On axis the ghost is round: half the film width times x equals half the height times y
    // (24.5 mm, OpenLensFlare's sensor clip of 24 mm plus one grid cell).
    let s = g.sensor_mm(36.0, 24.0).unwrap();
    assert!((s.x0 - -2.04361 * 12.0).abs() < EXACT);
    assert!((s.y0 - -1.3624 * 18.0).abs() < EXACT);
    assert!((s.x0 - s.y0).abs() < 1e-3 && (s.width() - s.height()).abs() < 1e-3);
    // At 10° OpenLensFlare's x (the tilt) is our y.
    let g = &b.entries[20].ghosts[2];
    let e = g.entrance_mm(14.5).unwrap();
    assert!((e.y0 - -0.380148 * 14.5).abs() < EXACT);
    assert!((e.x0 - -0.131416 * 14.5).abs() < EXACT);
    assert!((e.height() - 0.193548 * 14.5).abs() < EXACT);
    assert_eq!(g.path().to_string(), "2-1");
    assert_eq!(b.entries[20].ghosts[4].entrance_mm(14.5), None);
    assert_eq!(b.entries[20].ghosts[4].sensor_mm(36.0, 24.0), None);
}

#[test]
fn nearest_picks_the_closest_angle() {
    let b = heliar();
    assert_eq!(b.nearest(10.2).unwrap().angle_deg, 10.0);
    assert_eq!(b.nearest(10.3).unwrap().angle_deg, 10.5);
    assert_eq!(b.nearest(10.25).unwrap().angle_deg, 10.0);
    assert_eq!(b.nearest(-5.0).unwrap().angle_deg, 0.0);
    assert_eq!(b.nearest(120.0).unwrap().angle_deg, 90.0);
    assert!(b.nearest(f64::NAN).is_none());
    assert!(OlfGhostBounds { entries: vec![] }.nearest(1.0).is_none());
}

/// A one-angle, one-ghost document with `ghost` as the ghost's body.
fn doc(angle: &str, ghost: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<ghostList>\n    <list>\n        <angle>{angle}</angle>\n        <ghosts>\n            <ghost>\n{ghost}            </ghost>\n        </ghosts>\n    </list>\n</ghostList>\n"
    )
}

const GOOD: &str =
    "                <interfaces><interface>2</interface><interface>1</interface></interfaces>
                <pupilBounds><x>-0.5</x><y>-0.5</y><w>1</w><h>1</h></pupilBounds>
                <sensorBounds><x>-1</x><y>-1</y><w>2</w><h>2</h></sensorBounds>
                <avgIntensity>0.25</avgIntensity>
                <minChannels>3</minChannels>
                <optimalChannels>3</optimalChannels>
                <minRays>16</minRays>
                <optimalRays>16.0</optimalRays>
";

fn parse_err(text: &str) -> String {
    parse_olf_bounds(text, "b.xml").unwrap_err().to_string()
}

#[test]
fn a_minimal_document_reads() {
    let b = parse_olf_bounds(&doc("1.5", GOOD), "b.xml").unwrap();
    assert_eq!(b.entries.len(), 1);
    let g = &b.entries[0].ghosts[0];
    assert_eq!(b.entries[0].angle_deg, 1.5);
    assert_eq!(g.interfaces, [2, 1]);
    assert_eq!(g.avg_intensity, 0.25);
    assert_eq!((g.min_rays, g.optimal_rays), (16, 16));
    let empty = parse_olf_bounds("<ghostList/>", "b.xml").unwrap();
    assert!(empty.entries.is_empty());
}

#[test]
fn malformed_input_is_reported_at_file_line_column_with_the_field() {
    // Line 13 of `doc` is `<minRays>`; its value starts at column 26.
    let bad = GOOD.replace("<minRays>16</minRays>", "<minRays>many</minRays>");
    assert_eq!(
        parse_err(&doc("0", &bad)),
        "b.xml:13:26: field `minRays`: expected a number, got `many`"
    );
    let bad = GOOD.replace("<minRays>16</minRays>", "<minRays>-2</minRays>");
    assert!(parse_err(&doc("0", &bad)).contains("field `minRays`: expected a whole number"));
    assert_eq!(
        parse_err(&doc("nan", GOOD)),
        "b.xml:4:16: field `angle`: must be finite, got nan"
    );
    // A missing field is reported at its <ghost>.
    let bad = GOOD.replace("                <avgIntensity>0.25</avgIntensity>\n", "");
    assert_eq!(
        parse_err(&doc("0", &bad)),
        "b.xml:6:13: field `avgIntensity`: <ghost> has no <avgIntensity>"
    );
    let bad = GOOD.replace("<h>1</h>", "");
    assert!(parse_err(&doc("0", &bad)).contains("field `h`: <pupilBounds> has no <h>"));
    let bad = GOOD.replace("<h>1</h>", "<h>1</h><z>0</z>");
    assert!(parse_err(&doc("0", &bad)).starts_with("b.xml:8:"));
    assert!(parse_err(&doc("0", &bad)).contains("unknown tag <z> in <pupilBounds>"));
    let bad = GOOD.replace("<w>1</w>", "<w>1</w><w>2</w>");
    assert!(parse_err(&doc("0", &bad)).contains("<w> appears twice in one <pupilBounds>"));
    let bad = GOOD.replace("<interface>1</interface>", "");
    assert!(parse_err(&doc("0", &bad)).contains("two-reflection ghosts only; this one lists 1"));
    let bad = GOOD.replace(
        "<interface>2</interface><interface>1</interface>",
        "<interface>1</interface><interface>2</interface>",
    );
    assert!(parse_err(&doc("0", &bad)).contains("got 1 then 2"));
    let bad = GOOD.replace("<interface>2</interface>", "<interface>-2</interface>");
    assert!(parse_err(&doc("0", &bad)).contains("field `interface`: expected an element index"));
    let bad = GOOD.replace("<minRays>", "stray<minRays>");
    assert!(parse_err(&doc("0", &bad)).contains("text in <ghost>"));
    // Not the right file at all.
    assert_eq!(
        parse_err("<opticalSystem/>"),
        "b.xml:1:1: field `opticalSystem`: not an OpenLensFlare ghost-bounds file: the root is <opticalSystem>, expected <ghostList>"
    );
    assert!(parse_err("<ghostList><ghost/></ghostList>").contains("expected <list>"));
    // Angles must increase.
    let two = doc("1", GOOD).replace(
        "</ghostList>",
        "<list><angle>1</angle><ghosts/></list></ghostList>",
    );
    assert!(
        parse_err(&two)
            .contains("field `angle`: angles must increase from list to list: 1 after 1")
    );
    // Truncated: reported at the end, naming the innermost open tag.
    let text = doc("0", GOOD);
    let cut = &text[..text.find("<minChannels>").unwrap() + 5];
    let e = parse_olf_bounds(cut, "b.xml").unwrap_err();
    assert!(e.line > 0, "{e}");
    assert!(
        e.to_string().contains("malformed XML") || e.to_string().contains("not closed"),
        "{e}"
    );
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let e = read_olf_bounds(Path::new("no/such/bounds.xml")).unwrap_err();
    assert!(e.is_whole_file());
    assert!(
        e.to_string()
            .starts_with("no/such/bounds.xml: cannot read the file"),
        "{e}"
    );
}

#[test]
fn truncated_or_corrupted_files_never_panic() {
    let full = std::fs::read_to_string(HELIAR).unwrap();
    let head = &full[..3000];
    for cut in 0..head.len() {
        if head.is_char_boundary(cut) {
            let _ = parse_olf_bounds(&head[..cut], "cut.xml");
        }
    }
    // Each ASCII byte of the first ghost replaced by a few troublemakers.
    let bytes = head.as_bytes();
    for i in 0..bytes.len().min(900) {
        for b in [b'<', b'>', b'/', b'-', b'x', b'&', b'9'] {
            let mut v = bytes.to_vec();
            v[i] = b;
            if let Ok(s) = std::str::from_utf8(&v) {
                let _ = parse_olf_bounds(s, "flip.xml");
            }
        }
    }
}

//! Zemax `.zmx` and PBRT `.dat` lens files as first-class lenses (`tests/data/zemax/`,
//! `tests/data/pbrt/`, sources and licences in their READMEs): every file loads or gives its
//! documented error, every focal length matches a value derived without our code, a converted
//! lens traces exactly like the original, and the readers' options work end to end.
//!
//! Independent values were computed offline and are written here with their derivation; no
//! test needs Python or the network. "optiland" means optiland 0.6.3 (PyPI, numpy backend):
//! `optiland.fileio.load_zemax_file(path).paraxial.f2()`, the paraxial EFL at the file's
//! primary wavelength with optiland's own glass data.

use std::path::{Path, PathBuf};

use flarebench_sdk::io::{
    LensFileError, LoadedLens, PbrtConvention, ReadOptions, parse_olf_xml, read_lens,
    read_lens_with, write_xml,
};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_sdk::trace::{Ray, Sequence};
use flarebench_sdk::{Dispersion, LensSystem, Medium, SurfaceKind};

fn data(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(dir)
}

fn files(dir: &str, ext: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(data(dir))
        .expect("the test data directory exists")
        .map(|e| {
            e.expect("directory entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|n| n.ends_with(ext))
        .collect();
    v.sort();
    v
}

fn load(dir: &str, name: &str) -> LoadedLens {
    read_lens(&data(dir).join(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn efl(s: &LensSystem, lambda_nm: f64) -> f64 {
    analyse(s, lambda_nm).unwrap().efl_mm
}

/// What each Zemax test file gives: `Ok` with the primary wavelength (nm), or the documented
/// error as (field, line, text in the message).
enum Expect {
    Loads { primary_nm: f64 },
    Refused(&'static str, usize, &'static str),
}

const ZEMAX: &[(&str, Expect)] = &[
    (
        "fb_cooke_3config.zmx",
        Expect::Loads {
            primary_nm: 587.5618,
        },
    ),
    (
        "ol_circular_aperture_example_with_aperture.zmx",
        Expect::Loads { primary_nm: 587.0 },
    ),
    (
        "ol_lens1.zmx",
        Expect::Loads {
            primary_nm: 587.5618,
        },
    ),
    ("ol_lens2.zmx", Expect::Loads { primary_nm: 587.6 }),
    (
        "ol_lens_thorlabs_iso_8859_1.zmx",
        Expect::Loads { primary_nm: 780.0 },
    ),
    // Q-type asphere (Forbes Qbfs, XDAT 1 = 0): not an even polynomial, not read.
    (
        "ro_ASL5040-UV-ZemaxZMX.zmx",
        Expect::Refused("TYPE", 76, "SURF 1 has type QED_TYPE (Q-type asphere)"),
    ),
    // Catadioptric: a primary mirror with a negative thickness after it.
    (
        "ro_HoO-V2C18Ex27.zmx",
        Expect::Refused("GLAS", 134, "SURF 4 is a mirror (GLAS MIRROR)"),
    ),
    ("ro_US05831776-1.zmx", Expect::Loads { primary_nm: 248.0 }),
    // Four-mirror off-axis system.
    (
        "ro_US08011793-1.zmx",
        Expect::Refused("GLAS", 88, "SURF 2 is a mirror (GLAS MIRROR)"),
    ),
    // Off-axis parabolic mirror behind a decentring coordinate break.
    (
        "ro_zmax_37992.zmx",
        Expect::Refused(
            "PARM",
            94,
            "SURF 2 is a coordinate break with a decenter of -190.6",
        ),
    ),
];

#[test]
fn every_zemax_file_loads_or_gives_its_documented_error() {
    let names = files("zemax", ".zmx");
    let listed: Vec<&str> = ZEMAX.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names, listed,
        "every file in tests/data/zemax needs an entry here"
    );
    for (name, expect) in ZEMAX {
        let path = data("zemax").join(name);
        match (read_lens(&path), expect) {
            (Ok(lens), Expect::Loads { primary_nm }) => {
                let s = &lens.system;
                s.validate().unwrap_or_else(|e| panic!("{name}: {e:?}"));
                assert_eq!(s.primary_wavelength_nm, Some(*primary_nm), "{name}");
                assert_eq!(s.surfaces.last().unwrap().kind, SurfaceKind::Sensor);
                assert!(!s.notes.is_empty() && s.source.contains(name), "{name}");
                for w in &lens.warnings {
                    assert!(w.starts_with(&path.display().to_string()), "{name}: {w}");
                }
            }
            (Err(e), Expect::Refused(field, line, text)) => {
                assert_eq!((e.field.as_str(), e.line), (*field, *line), "{name}: {e}");
                assert!(e.message.contains(text), "{name}: {e}");
                assert!(
                    e.to_string()
                        .starts_with(&format!("{}:{line}:", path.display()))
                );
            }
            (Ok(_), Expect::Refused(..)) => panic!("{name} should be refused"),
            (Err(e), Expect::Loads { .. }) => panic!("{name}: {e}"),
        }
    }
}

#[test]
fn every_pbrt_file_loads() {
    assert_eq!(
        files("pbrt", ".dat"),
        [
            "dgauss.50mm.dat",
            "dgauss.dat",
            "fisheye.10mm.dat",
            "wide.22mm.dat"
        ]
    );
    for name in files("pbrt", ".dat") {
        let lens = load("pbrt", &name);
        lens.system.validate().unwrap();
        // The film is at the paraxial focus (pbrt focuses it itself).
        let p = analyse(&lens.system, LAMBDA_D_NM).unwrap();
        assert!(p.focus_error_mm.abs() < PBRT_FOCUS_TOL_MM, "{name}: {p:?}");
    }
    // Only the separation-before table needs a guess, and says so.
    assert!(load("pbrt", "dgauss.50mm.dat").warnings.is_empty());
    let w = load("pbrt", "dgauss.dat").warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("separation before each surface"), "{w:?}");
}

// --- focal lengths against independent values -------------------------------------------------

/// Both codes use refractiveindex.info's glass formulas: measured agreement is ~1e-12 mm.
const SAME_GLASS_DATA_MM: f64 = 1e-6;

/// pbrt's film against the paraxial focus (mm): f64 rounding of where the loader focuses it.
const PBRT_FOCUS_TOL_MM: f64 = 1e-9;

/// EFL against a source CSV header written by its own converter at the d line with nd rounded
/// to 5 decimals (mm).
const CSV_HEADER_EFL_TOL_MM: f64 = 5e-4;

/// EFL against a catalogue's nominal focal length (mm).
const CATALOGUE_EFL_TOL_MM: f64 = 0.01;

/// EFL against R1 / (n − 1) with the maker's published nd, 5 decimals: ±5e-6 in n is ±2e-4 mm.
const PUBLISHED_ND_EFL_TOL_MM: f64 = 2e-4;

/// EFL with LITHOSIL-Q for SILICA against optiland's Malitson silica at 248 nm (mm): measured
/// 0.183 mm shorter through 21 silica elements.
const SILICA_FORMULA_EFL_TOL_MM: f64 = 0.25;

/// EFL against a pbrt table's header, stated to 3 decimals (mm).
const PBRT_HEADER_EFL_TOL_MM: f64 = 1e-3;

/// EFL of the 100 mm table against twice the 50 mm table's 3-decimal header (mm).
const SCALED_PBRT_HEADER_EFL_TOL_MM: f64 = 2e-3;

/// Curvature of the 50 mm pbrt table against twice the 100 mm one's (1/mm): f64 rounding.
const HALF_SCALE_CURVATURE_TOL: f64 = 1e-15;
/// Thickness of the 100 mm pbrt table against twice the 50 mm one's (mm): f64 rounding.
const HALF_SCALE_THICKNESS_TOL_MM: f64 = 1e-9;
/// Semi-diameter of the 100 mm pbrt table against twice the 50 mm one's (mm): f64 rounding.
const HALF_SCALE_SEMI_DIAMETER_TOL_MM: f64 = 1e-12;

/// The library lens's sensor distance, which convert.py rounds to 1e-6 mm: half of that.
const SENSOR_DISTANCE_ROUNDING_MM: f64 = 5e-7;

/// Entrance pupil diameter against optiland's (mm): f64 rounding.
const EPD_TOL_MM: f64 = 1e-9;

#[test]
fn cooke_triplet_efl_matches_optiland_and_its_source_csv() {
    let s = load("zemax", "ol_lens1.zmx").system;
    // optiland: 24.990670494950276 mm at the primary wavelength 0.5875618 µm (the d line).
    assert!((efl(&s, 587.5618) - 24.990670494950276).abs() < SAME_GLASS_DATA_MM);
    // lenses/sources/csv/zmx_optiland_cooke_triplet_lens1.csv header: "EFL=24.9908 mm"
    // (its own converter, d line, nd rounded to 5 decimals: allow 5e-4 mm).
    assert!((efl(&s, LAMBDA_D_NM) - 24.9908).abs() < CSV_HEADER_EFL_TOL_MM);
}

#[test]
fn laikin_wide_angle_efl_matches_optiland_and_its_source_csv() {
    let s = load("zemax", "ol_circular_aperture_example_with_aperture.zmx").system;
    // The file is in inches. optiland keeps lens units: 0.7300916303992044 in at the primary
    // wavelength 0.587 µm, × 25.4 = 18.54432741…  mm.
    let optiland_mm = 0.7300916303992044 * 25.4;
    assert!((efl(&s, 587.0) - optiland_mm).abs() < SAME_GLASS_DATA_MM);
    // lenses-csv/zmx_optiland_laikin_100deg_wide_angle.csv header: "EFL=18.5442 mm" at the
    // d line, nd rounded to 5 decimals.
    assert!((efl(&s, LAMBDA_D_NM) - 18.5442).abs() < CSV_HEADER_EFL_TOL_MM);
    // The CLAP on flat surface 10 of the file (0.45 in) is its clear semi-diameter.
    assert_eq!(s.surfaces[9].semi_diameter, 0.45 * 25.4);
}

#[test]
fn edmund_asphere_efl_matches_its_catalogue_and_the_plano_convex_formula() {
    let s = load("zemax", "ol_lens2.zmx").system;
    // Edmund Optics #47-728, "15mm Dia. x 22.5mm FL" (the file's DBDT record: 2.250E+01).
    assert!((efl(&s, 587.6) - 22.5).abs() < CATALOGUE_EFL_TOL_MM);
    // optiland: 22.499368205385874 mm at 0.5876 µm.
    assert!((efl(&s, 587.6) - 22.499368205385874).abs() < SAME_GLASS_DATA_MM);
    // Plano-convex with a flat back: EFL = R1 / (n − 1) whatever the thickness (the conic and
    // aspheric terms have no paraxial power). R1 = 1/CURV = 1/0.07544322897019992 mm; Ohara's
    // published nd of L-BAL35 is 1.58913 (5 decimals: ±5e-6 in n, ±2e-4 mm in EFL).
    let closed = (1.0 / 0.07544322897019992) / (1.58913 - 1.0);
    assert!(
        (efl(&s, LAMBDA_D_NM) - closed).abs() < PUBLISHED_ND_EFL_TOL_MM,
        "{closed}"
    );
}

#[test]
fn thorlabs_asphere_efl_matches_its_catalogue() {
    let s = load("zemax", "ol_lens_thorlabs_iso_8859_1.zmx").system;
    // Thorlabs AL1815-C: "f=15 mm" at its design wavelength 780 nm (the file's NAME, PWAV).
    assert!((efl(&s, 780.0) - 15.0).abs() < CATALOGUE_EFL_TOL_MM);
    // optiland: 14.995572148674018 mm at 0.78 µm.
    assert!((efl(&s, 780.0) - 14.995572148674018).abs() < SAME_GLASS_DATA_MM);
    // The ISO-8859-1 "Ø" of the NAME survives decoding.
    assert!(s.name.starts_with("AL1815-C  Ø18 mm"), "{}", s.name);
}

/// Malitson (1965) fused silica, refractiveindex.info's "Malitson" entry (CC0):
/// n² − 1 = Σ Bᵢ λ²/(λ² − Cᵢ²), λ in µm — the formula optiland uses for `SILICA`.
fn malitson_silica() -> Medium {
    Medium::Glass {
        name: "Malitson fused silica".into(),
        dispersion: Dispersion::Sellmeier {
            c0: 0.0,
            terms: vec![
                (0.6961663, 0.0684043),
                (0.4079426, 0.1162414),
                (0.8974794, 9.896161),
            ],
        },
    }
}

#[test]
fn lithography_lens_efl_matches_optiland_up_to_the_silica_formula() {
    let s = load("zemax", "ro_US05831776-1.zmx").system;
    // optiland: 494.02032877703374 mm at 0.248 µm, with Malitson's silica. With the same
    // formula our geometry gives the same EFL.
    let mut malitson = s.clone();
    for surf in &mut malitson.surfaces {
        if matches!(&surf.medium, Medium::Glass { name, .. } if name == "SCHOTT:LITHOSIL-Q") {
            surf.medium = malitson_silica();
        }
    }
    assert!((efl(&malitson, 248.0) - 494.02032877703374).abs() < SAME_GLASS_DATA_MM);
    // We read SILICA as SCHOTT:LITHOSIL-Q, whose formula (valid from 250 nm) gives n 2.2e-5
    // lower than Malitson's at 248 nm; through 21 silica elements that shortens the EFL by
    // 0.183 mm (measured: 493.837 mm). Allow 0.25 mm.
    assert!((efl(&s, 248.0) - 494.02032877703374).abs() < SILICA_FORMULA_EFL_TOL_MM);
}

#[test]
fn pbrt_efls_match_their_tables_headers() {
    // lenses-csv/pbrt_*.csv headers ("Paraxial check … EFL=…", 3 decimals: allow 1e-3 mm).
    for (name, stated) in [
        ("dgauss.50mm.dat", 50.358),
        ("wide.22mm.dat", 22.023),
        ("fisheye.10mm.dat", 9.991),
    ] {
        let s = load("pbrt", name).system;
        assert!(
            (efl(&s, LAMBDA_D_NM) - stated).abs() < PBRT_HEADER_EFL_TOL_MM,
            "{name}"
        );
    }
    // dgauss.dat is the same design at 100 mm ("Scaled to 50 mm from 100 mm" in the 50 mm
    // table's header): every length is exactly twice, so its EFL is 2 × 50.358.
    let s = load("pbrt", "dgauss.dat").system;
    assert!((efl(&s, LAMBDA_D_NM) - 2.0 * 50.358).abs() < SCALED_PBRT_HEADER_EFL_TOL_MM);
}

#[test]
fn both_pbrt_conventions_give_the_same_double_gauss() {
    let half = load("pbrt", "dgauss.50mm.dat").system;
    let full = load("pbrt", "dgauss.dat").system;
    assert_eq!(half.surfaces.len(), full.surfaces.len());
    for (i, (a, b)) in half.surfaces.iter().zip(&full.surfaces).enumerate() {
        assert_eq!(a.kind, b.kind, "{i}");
        assert!(
            (a.curvature - 2.0 * b.curvature).abs() <= HALF_SCALE_CURVATURE_TOL,
            "{i}"
        );
        assert!(
            (2.0 * a.thickness - b.thickness).abs() <= HALF_SCALE_THICKNESS_TOL_MM,
            "{i}"
        );
        assert_eq!(a.medium, b.medium, "{i}");
        if a.kind != SurfaceKind::Sensor {
            assert!(
                (2.0 * a.semi_diameter - b.semi_diameter).abs() <= HALF_SCALE_SEMI_DIAMETER_TOL_MM,
                "{i}"
            );
        }
    }
}

#[test]
fn the_pbrt_double_gauss_is_the_library_lens() {
    // lenses/double-gauss-50mm.xml was made from the same table by lenses/sources/convert.py
    // (sensor distance rounded to 1e-6 mm there).
    let ours = load("pbrt", "dgauss.50mm.dat").system;
    let lib =
        read_lens(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/double-gauss-50mm.xml"))
            .unwrap()
            .system;
    assert_eq!(ours.surfaces.len(), lib.surfaces.len());
    let last = ours.surfaces.len() - 2;
    for (i, (a, b)) in ours.surfaces.iter().zip(&lib.surfaces).enumerate() {
        assert_eq!(
            (a.kind, a.curvature, &a.medium),
            (b.kind, b.curvature, &b.medium),
            "{i}"
        );
        if a.kind != SurfaceKind::Sensor {
            // convert.py rounds the sensor's semi-diameter up to 21.7 mm; ours is the film's
            // half diagonal, 21.633 mm.
            assert_eq!(a.semi_diameter, b.semi_diameter, "{i}");
        }
        let tol = if i == last {
            SENSOR_DISTANCE_ROUNDING_MM
        } else {
            0.0
        };
        assert!((a.thickness - b.thickness).abs() <= tol, "{i}");
    }
    assert_eq!(ours.stated_efl_mm, Some(50.0));
}

#[test]
fn zemax_configurations_match_optiland() {
    let path = data("zemax").join("fb_cooke_3config.zmx");
    // optiland, ol_lens1.zmx with the configuration's values set by hand
    // (set_thickness(t, 4), set_thickness(t, 7), set_radius(1/c, 6), set_aperture('EPD', d)):
    let expected = [
        (1, 24.990670494950276, 8.333333969116211),
        (2, 24.069300780076663, 7.5),
        (3, 23.13284498748535, 6.25),
    ];
    for (config, efl_mm, epd) in expected {
        let opts = ReadOptions {
            zemax_config: Some(config),
            ..ReadOptions::default()
        };
        let s = read_lens_with(&path, &opts).unwrap().system;
        let p = analyse(&s, 587.5618).unwrap();
        assert!(
            (p.efl_mm - efl_mm).abs() < SAME_GLASS_DATA_MM,
            "config {config}"
        );
        assert!(
            (p.entrance_pupil_diameter_mm - epd).abs() < EPD_TOL_MM,
            "config {config}"
        );
    }
    // Without --config: the active configuration, with a warning that there are others.
    let lens = read_lens(&path).unwrap();
    assert!(lens.warnings.iter().any(|w| w.contains("3 configurations")));
    assert_eq!(
        efl(&lens.system, 587.5618),
        efl(&load("zemax", "ol_lens1.zmx").system, 587.5618)
    );
}

#[test]
fn truncated_and_edited_real_files_never_panic() {
    use flarebench_sdk::io::{parse_pbrt, parse_zmx};
    for name in files("zemax", ".zmx") {
        let bytes = std::fs::read(data("zemax").join(&name)).unwrap();
        let text = match bytes.strip_prefix(b"\xFF\xFE") {
            Some(rest) => String::from_utf16_lossy(
                &rest
                    .chunks_exact(2)
                    .map(|c| u16::from_le_bytes([c[0], c[1]]))
                    .collect::<Vec<_>>(),
            ),
            None => String::from_utf8_lossy(&bytes).into_owned(),
        };
        // About 60 cuts per file, at character boundaries spread over the whole file.
        let boundaries: Vec<usize> = text.char_indices().map(|(i, _)| i).collect();
        let step = (boundaries.len() / 60).max(1);
        let cuts: Vec<usize> = boundaries.into_iter().step_by(step).collect();
        for &cut in &cuts {
            let (head, tail) = text.split_at(cut);
            for candidate in [head.to_string(), format!("{head}x{tail}")] {
                if let Err(e) = parse_zmx(&candidate, &name, None) {
                    assert!(e.line >= 1 && e.column >= 1, "{name} cut at {cut}: {e}");
                }
            }
        }
    }
    for name in files("pbrt", ".dat") {
        let text = std::fs::read_to_string(data("pbrt").join(&name)).unwrap();
        for cut in (0..text.len())
            .filter(|&i| text.is_char_boundary(i))
            .step_by(3)
        {
            let (head, tail) = text.split_at(cut);
            let _ = parse_pbrt(head, &name, None);
            let _ = parse_pbrt(&format!("{head}-{tail}"), &name, None);
        }
    }
}

// --- conversion -------------------------------------------------------------------------------

/// A fan of collimated rays over the entrance pupil at three field angles.
fn rays(s: &LensSystem, lambda_nm: f64) -> Vec<Ray> {
    let p = analyse(s, lambda_nm).unwrap();
    let r = p.entrance_pupil_diameter_mm / 2.0;
    let mut out = Vec::new();
    for field_deg in [0.0, 3.0, 7.0] {
        for k in -4..=4 {
            let h = r * f64::from(k) / 4.0;
            // Aim at the entrance pupil: height at the first vertex for a ray through the
            // pupil point h.
            let u = f64::to_radians(field_deg);
            let y0 = h - u.tan() * p.entrance_pupil_z_mm;
            out.push(Ray::collimated(u, 0.3, y0));
        }
    }
    out
}

#[test]
fn zemax_to_xml_to_trace_gives_identical_intercepts() {
    for (name, expect) in ZEMAX {
        if !matches!(expect, Expect::Loads { .. }) {
            continue;
        }
        let original = load("zemax", name).system;
        let xml = write_xml(&original);
        let back = parse_olf_xml(&xml, "converted.xml").unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(back.warnings.is_empty(), "{name}: {:?}", back.warnings);
        assert_eq!(back.system, original, "{name}");
        let lambda = original.default_wavelength_nm();
        let (a, b) = (
            Sequence::forward(&original, lambda),
            Sequence::forward(&back.system, lambda),
        );
        let mut reached = 0;
        for ray in rays(&original, lambda) {
            let (ra, rb) = (a.trace(&ray), b.trace(&ray));
            assert_eq!(ra, rb, "{name}");
            reached += usize::from(ra.completed);
        }
        assert!(reached > 0, "{name}: no ray reached the sensor");
    }
}

#[test]
fn utf16_big_endian_and_utf8_copies_read_the_same() {
    let bytes = std::fs::read(data("zemax").join("ol_lens2.zmx")).unwrap();
    // The original is UTF-16LE with a byte-order mark.
    assert_eq!(&bytes[..2], b"\xFF\xFE");
    let units: Vec<u16> = bytes[2..]
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    let text = String::from_utf16(&units).unwrap();
    let tmp = tempfile::Builder::new()
        .prefix("flarebench-zmx-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let be: Vec<u8> = b"\xFE\xFF"
        .iter()
        .copied()
        .chain(text.encode_utf16().flat_map(u16::to_be_bytes))
        .collect();
    let original = load("zemax", "ol_lens2.zmx").system;
    for (file, content) in [("be.zmx", be), ("utf8.zmx", text.clone().into_bytes())] {
        let p = dir.join(file);
        std::fs::write(&p, content).unwrap();
        let s = read_lens(&p).unwrap().system;
        assert_eq!(s.surfaces, original.surfaces, "{file}");
        assert_eq!(s.name, original.name, "{file}");
    }
    tmp.close().unwrap();
}

#[test]
fn options_that_do_not_fit_the_format_are_errors() {
    let xml = Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml");
    let config = ReadOptions {
        zemax_config: Some(2),
        ..ReadOptions::default()
    };
    let e: LensFileError = read_lens_with(&xml, &config).unwrap_err();
    assert!(e.is_whole_file() && e.message.contains("Zemax"), "{e}");
    let conv = ReadOptions {
        pbrt_convention: Some(PbrtConvention::ThicknessAfter),
        ..ReadOptions::default()
    };
    let e = read_lens_with(&data("zemax").join("ol_lens1.zmx"), &conv).unwrap_err();
    assert!(e.message.contains("PBRT"), "{e}");
    // Forcing pbrt's convention on the separation table gives another (unfocused) lens.
    let forced = read_lens_with(&data("pbrt").join("dgauss.dat"), &conv).unwrap();
    assert!(forced.warnings.is_empty());
    let guessed = load("pbrt", "dgauss.dat").system;
    assert_ne!(
        forced.system.surfaces[0].thickness,
        guessed.surfaces[0].thickness
    );
}

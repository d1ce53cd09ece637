//! `flarebench gallery`: lenses chosen by name and by filter, each rendered once into the
//! folder and reused while its file and the settings stay the same, an interrupted run
//! resumed, the pages written, and a lens that fails reported without stopping the others.

use crate::common;

use std::path::Path;

use serde_json::Value;

/// The lenses of the first run: two by name (one by a part of its name), three by filter.
const NAMED: [&str; 2] = ["heliar-tronnier", "hologon"];
const FILTER: [&str; 4] = ["--maker", "samsung", "--focal", "..20"];
const EXPECTED: [&str; 5] = [
    "heliar-tronnier",
    "zeiss/zeiss-hologon-f8-15mm",
    "samsung/samsung-10mm-f3.5-fisheye",
    "samsung/samsung-16mm-f2.4",
    "samsung/samsung-20mm-f2.8",
];

fn gallery(dir: &Path, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec!["gallery"];
    args.extend_from_slice(&NAMED);
    args.extend_from_slice(&FILTER);
    args.extend_from_slice(&["--quality", "fast", "-o", dir.to_str().unwrap()]);
    args.extend_from_slice(extra);
    let out = common::flarebench(&args);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn record(dir: &Path, name: &str) -> Value {
    let slug = name.replace('/', "--");
    let text = std::fs::read_to_string(dir.join("lenses").join(format!("{slug}.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn a_gallery_renders_each_lens_once_and_again_only_what_changed() {
    let tmp = common::temp_dir("gallery");
    let dir = tmp.path();
    let small = ["--size", "96x54"];
    let (ok, stdout, stderr) = gallery(dir, &small);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("gallery of 5 lenses") && stdout.contains("5 rendered, 0 up to date"),
        "{stdout}"
    );
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    for name in EXPECTED {
        let r = record(dir, name);
        assert_eq!(r["name"], name);
        // The light at 60% of the way to the field's edge, in every lens's frame.
        let (theta, edge) = (
            r["light_theta_deg"].as_f64().unwrap(),
            r["field_edge_deg"].as_f64().unwrap(),
        );
        assert!(edge > 0.0 && (theta - 0.6 * edge).abs() < 1e-9, "{r}");
        assert!(r["ghosts_drawn"].as_u64().unwrap() > 0, "{r}");
        assert!(
            r["ghosts_drawn"].as_u64() <= r["ghosts_total"].as_u64(),
            "{r}"
        );
        let png = image::open(dir.join("lenses").join(r["image"].as_str().unwrap())).unwrap();
        assert_eq!((png.width(), png.height()), (96, 54), "{name}");
        let svg = std::fs::read_to_string(dir.join("lenses").join(r["section"].as_str().unwrap()))
            .unwrap();
        assert!(
            svg.starts_with("<svg ") && svg.contains("<polygon "),
            "{name}"
        );
        assert!(
            html.contains(&format!("<h2>{name}</h2>"))
                && html.contains(r["image"].as_str().unwrap()),
            "{name} is not on the page"
        );
    }
    assert!(html.contains("flarebench gallery: 5 lenses"));
    let sheet = image::open(dir.join("contact.png")).unwrap();
    assert!(sheet.width() >= 5 * 96 && sheet.height() >= 54, "{sheet:?}");

    // The same again: nothing rendered, the files untouched.
    let before = std::fs::read(dir.join("lenses/heliar-tronnier.json")).unwrap();
    let (ok, stdout, stderr) = gallery(dir, &small);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("0 rendered, 5 up to date"), "{stdout}");
    assert_eq!(
        std::fs::read(dir.join("lenses/heliar-tronnier.json")).unwrap(),
        before
    );

    // A run cut short before a lens's record was written: that lens alone is rendered.
    std::fs::remove_file(dir.join("lenses/samsung--samsung-16mm-f2.4.json")).unwrap();
    let (ok, stdout, stderr) = gallery(dir, &small);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("1 rendered, 4 up to date"), "{stdout}");

    // Other settings: every lens again.
    let (ok, stdout, stderr) = gallery(dir, &["--size", "64x36"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("5 rendered, 0 up to date"), "{stdout}");
    let r = record(dir, "heliar-tronnier");
    let png = image::open(dir.join("lenses").join(r["image"].as_str().unwrap())).unwrap();
    assert_eq!((png.width(), png.height()), (64, 36));
}

#[test]
fn a_gallery_needs_lenses_and_reports_one_that_fails_without_stopping() {
    let tmp = common::temp_dir("gallery-errors");
    let dir = tmp.path();
    let out = common::flarebench(&["gallery", "-o", dir.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--all"),
        "{stderr}"
    );

    // A file that is not a lens beside one that is.
    let bad = dir.join("bad.xml");
    std::fs::write(&bad, "<opticalSystem><elements></elements></opticalSystem>").unwrap();
    let out = common::flarebench(&[
        "gallery",
        bad.to_str().unwrap(),
        "cooke-triplet-25mm",
        "--size",
        "64x36",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "-o",
        dir.join("g").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a failed lens fails the run");
    assert!(
        stderr.contains("bad.xml") && stderr.contains("1 lenses failed"),
        "{stderr}"
    );
    let html = std::fs::read_to_string(dir.join("g/index.html")).unwrap();
    assert!(html.contains("<h2>cooke-triplet-25mm</h2>"));
    assert!(html.contains("ghosts only"));
}

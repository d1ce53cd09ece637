//! `flarebench stability`: the quick suite passes on the lenses CI checks, every kind of check
//! is there, and the command's exit code and JSON say what the findings say.

mod common;

use common::{flarebench, temp_dir};
use flarebench::lens_library;
use flarebench::stability::{self, Finding, SuiteOptions};
use serde_json::Value;

/// The quick suite on three lenses (a slow classic, a zoom of 210 ghosts, a fisheye with a
/// 155.9° field) and the synthetic lenses, as CI runs it.
#[test]
fn the_quick_suite_passes_with_every_kind_of_check() {
    let lenses: Vec<_> = ["heliar-tronnier", "nikon-zoom-short", "fisheye-10mm"]
        .iter()
        .map(|n| (n.to_string(), lens_library::load(n, true).unwrap().system))
        .collect();
    let report = stability::run(&lenses, SuiteOptions::quick(), &|_| {});
    let failed: Vec<&Finding> = report.findings.iter().filter(|f| !f.pass).collect();
    assert!(failed.is_empty(), "{failed:#?}");
    assert_eq!(report.failed, 0);
    for check in [
        "chief-ray",
        "chief-ray-height",
        "non-finite",
        "f32-vs-f64",
        "f32-vs-f64-energy",
        "pupil-flux",
        "pupil-flux-mc",
        "plate-energy",
        "near-flat",
        "ghost-energy-mc",
        "scale-flux",
        "scale-image",
    ] {
        assert!(
            report.findings.iter().any(|f| f.check == check),
            "no {check} finding"
        );
    }
    // Every lens is checked at grazing incidence, and the fisheye far past 60°.
    for (name, _) in &lenses {
        assert!(
            report
                .findings
                .iter()
                .any(|f| &f.lens == name && f.case.starts_with("θ 89.0°")),
            "{name} not checked at 89°"
        );
    }
    let fisheye_edge = report
        .findings
        .iter()
        .find(|f| f.lens == "fisheye-10mm" && f.check == "chief-ray")
        .unwrap();
    assert!(
        fisheye_edge.note.contains("found at 0–") && !fisheye_edge.note.contains("found at 0–5"),
        "{}",
        fisheye_edge.note
    );
}

#[test]
fn a_finding_passes_only_within_its_limit() {
    let f = |v| Finding::measured("x", "lens", String::new(), v, 1.0, String::new());
    assert!(f(1.0).pass && f(0.0).pass);
    assert!(!f(1.5).pass);
    assert!(!f(f64::NAN).pass, "a NaN figure must fail");
    assert!(!Finding::failed("x", "lens", String::new(), "why".into()).pass);
}

#[test]
fn the_command_prints_json_exits_0_and_exports_the_synthetic_lenses() {
    let tmp = temp_dir("stability");
    let dir = tmp.path().join("lenses");
    let out = flarebench(&[
        "stability",
        "cooke-triplet-25mm",
        "--quick",
        "--no-synthetic",
        "--json",
        "--export",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["failed"], 0);
    let findings = v["findings"].as_array().unwrap();
    assert!(findings.len() > 10);
    assert!(findings.iter().all(|f| f["lens"] == "cooke-triplet-25mm"));
    // The exported lenses load, and run through the suite themselves.
    for name in ["plate", "plate-near-flat", "near-tir", "thin-air-gap"] {
        let path = dir.join(format!("{name}.xml"));
        assert!(path.is_file(), "{} missing", path.display());
        lens_library::load(path.to_str().unwrap(), true).unwrap();
    }
}

/// A lens with a figure outside its limit makes the command exit 1 with the count, after the
/// table: here the synthetic plate on its own, which has no focal length, so no chief ray
/// can be aimed through it, nor a pupil found at f/64.
#[test]
fn a_failing_finding_makes_the_command_exit_1_naming_the_count() {
    let tmp = temp_dir("stability-fail");
    let lens = tmp.path().join("plate.xml");
    std::fs::write(
        &lens,
        flarebench_sdk::io::write_xml(&stability::synthetic::plate(0.0)),
    )
    .unwrap();
    let out = flarebench(&[
        "stability",
        lens.to_str().unwrap(),
        "--quick",
        "--no-synthetic",
        "--failures-only",
    ]);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("chief-ray") && stdout.contains("FAIL") && !stdout.contains(" ok "),
        "{stdout}"
    );
    assert!(
        stderr.contains("stability findings are outside their limits"),
        "{stderr}"
    );
}

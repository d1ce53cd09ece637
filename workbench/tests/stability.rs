//! `flarebench stability`: the quick suite passes on the lenses CI checks, every kind of check
//! is there, and the command's exit code and JSON say what the findings say.

use crate::common;

use common::{flarebench, temp_dir};
use flarebench::lens_library;
use flarebench::stability::{self, Finding, SuiteOptions};
use flarebench_sdk::aperture::Aperture;
use ghost_raytrace::ghosts::{RenderOptions, render_with};
use ghost_raytrace::plan::plan;
use ghost_raytrace::scene::LightSpec;
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

fn once_failed_options() -> SuiteOptions {
    SuiteOptions {
        width: 16,
        synthetic: false,
        ..SuiteOptions::quick()
    }
}

fn find(findings: &[Finding], check: &str) -> Finding {
    findings
        .iter()
        .find(|f| f.check == check)
        .unwrap_or_else(|| panic!("no {check} finding"))
        .clone()
}

/// Library lenses on which the suite's own scan once failed, in tiny frames (only the chief
/// ray matters here): the Fujinon XF33 at 43° (every ray that completes its path there passes
/// outside its front element, once counted as light crossing the stop) and the Ricoh 18.3 mm
/// on 36 × 24 mm (its image height turns over at 57°, short of the corner).
#[test]
#[ignore = "slow tier: two lenses' field checks with their renders; by default the scan and the \
            field's edge in the quick suite on three lenses"]
fn the_scan_holds_on_lenses_it_once_failed() {
    let options = once_failed_options();
    let xf33 = lens_library::load("fujifilm-fujinon-xf33-f1.4-r-lm-wr", true)
        .unwrap()
        .system;
    let f = stability::field::check_lens("xf33", &xf33, options);
    let chief = find(&f, "chief-ray");
    assert!(chief.pass, "{chief:?}");
    assert!(chief.note.contains("found at 0–39°"), "{}", chief.note);

    let ricoh = lens_library::load("ricoh-18.3mm-f2.5-a12", true)
        .unwrap()
        .system;
    assert_eq!(stability::field::edge_deg(&ricoh), 57.0);
    let f = stability::field::check_lens("ricoh", &ricoh, options);
    let height = find(&f, "chief-ray-height");
    assert!(height.pass && height.case == "0–57°", "{height:?}");
}

/// The Hasselblad HC 50 mm at f/64, on which the Monte-Carlo pupil flux check once failed: an
/// estimate with a 4.6% standard error, held to 0.5% alone.
#[test]
#[ignore = "slow tier: the pupil flux's Monte-Carlo estimates at f/64 on a lens its sampler \
            cannot zoom onto; by default the quick suite's pupil-flux checks on three lenses"]
fn the_monte_carlo_pupil_flux_holds_on_the_lens_it_once_failed() {
    let hasselblad = lens_library::load("hasselblad-hc-3.5-50-fujinon", true)
        .unwrap()
        .system;
    let s = stability::stops::check_lens("hc50", &hasselblad, once_failed_options());
    let mc = find(&s, "pupil-flux-mc");
    // Its limit grows by three of its standard errors (4.6%), and the estimate is within it.
    assert!(mc.limit > 0.1, "{mc:?}");
    assert!(mc.pass, "{mc:?}");
    // The renderer's own pupil flux, with no sampling error, keeps the fixed limit.
    let bounds = find(&s, "pupil-flux");
    assert_eq!(bounds.limit, stability::stops::PUPIL_FLUX_LIMIT);
    assert!(bounds.pass, "{bounds:?}");
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

/// Nikon zoom mid past the edge of its field (1.15 × 11.93°, a case of the quick suite): a
/// corner of one of ghost 14-0's triangles grazes out of the lens in f64 (not in f32) and
/// stretches it into a sliver 1e-9 of a pixel thin across the frame. Grown to the Airy disc's
/// area about its centroid, that sliver became a needle of metres crossing the frame, and the
/// f64 image put 12 times the Monte-Carlo's light in the frame in one band (f32 against f64:
/// 42% RMSE, 2.6% energy). A sliver is now widened across its longest edge instead.
#[test]
fn a_grazing_sliver_triangle_is_drawn_alike_in_f32_and_f64() {
    let sys = lens_library::load("nikon-zoom-mid", true).unwrap().system;
    let frame = stability::frame_of(&sys, 160);
    let light = LightSpec {
        theta_deg: 13.717316952,
        phi_deg: 30.0,
        ..LightSpec::parse("0,0").unwrap()
    };
    let mut plans = plan(&sys, &[light], &frame, &stability::default_plan()).unwrap();
    plans[0].ghosts.retain(|g| g.path.to_string() == "14-0");
    assert_eq!(plans[0].ghosts.len(), 1, "14-0 is drawn");
    let (a, b) = (
        sampled(&sys, frame, &plans, false),
        sampled(&sys, frame, &plans, true),
    );
    let cmp = a.compare(&b).unwrap();
    assert!(cmp.relative_rmse < stability::F32_RMSE_LIMIT, "{cmp:?}");
    assert!(
        cmp.energy_error.abs() < stability::F32_ENERGY_LIMIT,
        "{cmp:?}"
    );
}

/// The Goerz Dagor 240 mm past the edge of its field (1.15 × 5.1°, a case of the quick suite,
/// 160 × 107 px): the shared edge of two triangles of ghost 8-0, where the ghost folds and the
/// two carry irradiances 2.5 times apart, passes within a thousandth of a pixel of a pixel's
/// centre. Point-sampled, that pixel belongs to whichever triangle covers its centre, which f32
/// and f64 decide differently (relative RMSE 7.5e-3); the suite draws its pairs with exact
/// coverage, where the pixel takes both triangles' shares of its area in either precision.
#[test]
fn a_pixel_centre_on_a_fold_does_not_decide_f32_against_f64() {
    let sys = lens_library::load("goerz-dagor-anastigmat-240mm-f6.8", true)
        .unwrap()
        .system;
    let frame = stability::frame_of(&sys, 160);
    let theta = 1.15 * stability::field::edge_deg(&sys);
    let pair = stability::render_pair(
        &sys,
        &Aperture::Circular,
        frame,
        theta,
        30.0,
        &stability::default_plan(),
    )
    .unwrap();
    for f in stability::precision_findings("dagor", "edge", &pair) {
        assert!(f.pass, "{f:?}");
    }
    // Drawn as the renderer draws (point-sampled), the two images differ in a few pixels at
    // most: the trace agrees; which pixels the fold's edge gives to which triangle does not.
    let light = LightSpec {
        theta_deg: theta,
        phi_deg: 30.0,
        ..LightSpec::parse("0,0").unwrap()
    };
    let plans = plan(&sys, &[light], &frame, &stability::default_plan()).unwrap();
    let (a, b) = (
        sampled(&sys, frame, &plans, false),
        sampled(&sys, frame, &plans, true),
    );
    let peak = b.pixels.iter().flatten().fold(0.0_f32, |m, v| m.max(*v));
    let differing = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3 * peak))
        .count();
    assert!(
        differing <= 4,
        "{differing} pixels differ by more than 1e-3 of the peak"
    );
}

/// The ghosts of `plans` as the renderer draws them (its triangles point-sampled), traced in
/// f64 or f32.
fn sampled(
    sys: &flarebench_sdk::LensSystem,
    frame: flarebench_sdk::frame::Frame,
    plans: &[ghost_raytrace::plan::LightPlan],
    trace_f64: bool,
) -> flarebench_sdk::image::HdrImage {
    let options = RenderOptions {
        trace_f64,
        ..Default::default()
    };
    render_with(sys, &Aperture::Circular, frame, plans, options)
        .unwrap()
        .0
}

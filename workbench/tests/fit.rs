//! `flarebench fit` end to end: a rendered flare fitted back, the files it writes, and bad
//! input refused with the flag named.

use crate::common::{flarebench, json, temp_dir};

/// The Heliar's flare rendered (ghosts only, its own MgF₂ coatings), then fitted with its
/// surfaces' single layers free: the fit recovers the file's layers, reproduces the image,
/// and writes a lens file that loads, the fitted and residual images and its report.
#[test]
fn a_rendered_flare_is_fitted_back() {
    let dir = temp_dir("fit");
    let image = dir.path().join("flare.exr");
    let out = flarebench(&[
        "render",
        "heliar-tronnier",
        "--light",
        "12,30,40",
        "--size",
        "240x160",
        "--starburst",
        "off",
        "-o",
        image.to_str().unwrap(),
        "-q",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fitted = dir.path().join("fitted");
    let report = json(&[
        "fit",
        "heliar-tronnier",
        image.to_str().unwrap(),
        "--light",
        "12,30,40",
        "--fit-width",
        "60",
        "--passes",
        "1",
        "--spread-starts",
        "0",
        "-o",
        fitted.to_str().unwrap(),
        "--json",
    ]);
    // Within 2%: the renderer applies a ray's angle factor at its band's centre to the whole
    // band, the fit's basis its reflectances' at every 5 nm (docs/coatings.md).
    assert!(report["relative_rmse"].as_f64().unwrap() < 0.02, "{report}");
    // The file's coatings: MgF₂ (1.38) on every air–glass surface.
    let params = report["params"].as_array().unwrap();
    for p in params {
        let name = p["name"].as_str().unwrap();
        if name.ends_with(" index") {
            let v = p["value"].as_f64().unwrap();
            assert!((v - 1.38).abs() < 0.01, "{name}: {v}");
        }
    }
    assert_eq!(report["light"]["source"], "given");
    assert!(report["ghosts"].as_array().unwrap().len() >= 10, "{report}");
    for f in [
        "fitted.xml",
        "fitted.exr",
        "residual.exr",
        "target.exr",
        "fit.json",
    ] {
        assert!(fitted.join(f).is_file(), "{f} missing");
    }
    let info = json(&[
        "info",
        fitted.join("fitted.xml").to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(info["name"], report["lens"], "{info}");
}

/// Bad options name the flag and what it wants.
#[test]
fn bad_fit_options_are_refused_by_name() {
    let dir = temp_dir("fit-bad");
    let image = dir.path().join("flare.exr");
    let out = flarebench(&[
        "render",
        "heliar-tronnier",
        "--light",
        "12,30",
        "--size",
        "64x48",
        "--starburst",
        "off",
        "-o",
        image.to_str().unwrap(),
        "-q",
    ]);
    assert!(out.status.success());
    let o = dir.path().join("o");
    for (extra, wanted) in [
        (&["--model", "gold"][..], "unknown coating model `gold`"),
        (
            &["--surface", "1=single"][..],
            "surface 1 is not between air and glass",
        ),
        (&["--surface", "x"][..], "--surface wants SURFACE=MODEL"),
        (&["--exclude", "1,2,3"][..], "--exclude wants X0,Y0,X1,Y1"),
        (&["--light-at", "5"][..], "--light-at wants X,Y"),
    ] {
        let mut args = vec![
            "fit",
            "heliar-tronnier",
            image.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = flarebench(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(wanted),
            "{extra:?}: {err}"
        );
    }
}

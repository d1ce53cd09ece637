//! `flarebench sweep`: the files it writes, what they hold, and resuming from its cache.

use crate::common;

use common::{flarebench, temp_dir};
use serde_json::Value;

fn sweep(dir: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "sweep",
        "cooke-triplet-25mm",
        "--light",
        "8,60",
        "--size",
        "64x36",
        "--runs",
        "1",
        "--backend",
        "cpu",
        "--algo",
        "ghost-raytrace:quality=default",
        "--algo",
        "ghost-matrix",
        "--vary",
        "grid_scale=0.5,1",
        "-o",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    flarebench(&args)
}

#[test]
fn a_sweep_writes_tables_plots_sheets_and_a_page_and_resumes_from_its_cache() {
    let tmp = temp_dir("sweep");
    let dir = tmp.path();
    let out = sweep(dir, &["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cells_run"], 4);
    assert_eq!(v["references_rendered"], 1);
    let case = &v["cases"][0];
    assert_eq!(case["case"]["lens"], "cooke-triplet-25mm");
    let cells = case["cells"].as_array().unwrap();
    // Two algorithms, and grid_scale varied on the one that has it (ghost-matrix has not).
    let labels: Vec<&str> = cells.iter().map(|c| c["label"].as_str().unwrap()).collect();
    assert_eq!(
        labels,
        [
            "ghost-raytrace:quality=default",
            "ghost-matrix",
            "grid_scale=0.5",
            "grid_scale=1"
        ]
    );
    for c in cells {
        assert!(c["failure"].is_null(), "{c}");
        let rmse = c["relative_rmse"].as_f64().unwrap();
        assert!(rmse > 0.0 && rmse.is_finite(), "{c}");
        assert_eq!(c["times_ms"].as_array().unwrap().len(), 1);
    }
    // The paraxial baseline is far off; the ray tracer is not.
    assert!(cells[1]["relative_rmse"].as_f64().unwrap() > 0.2);
    assert!(cells[3]["relative_rmse"].as_f64().unwrap() < 0.2);
    // Ghost by ghost for the built-in renderer: shares of the reference summing to one, the
    // ghosts drawn at the full grid close to the reference's energy.
    let ghosts = cells[3]["ghosts"].as_array().unwrap();
    assert!(ghosts.len() >= 10, "{}", ghosts.len());
    let share: f64 = ghosts
        .iter()
        .map(|g| g["reference_share"].as_f64().unwrap())
        .sum();
    assert!((share - 1.0).abs() < 1e-3, "{share}");
    let big = ghosts
        .iter()
        .filter(|g| g["reference_share"].as_f64().unwrap() > 0.05)
        .collect::<Vec<_>>();
    assert!(!big.is_empty());
    for g in big {
        assert_eq!(g["drawn"], true, "{g}");
        assert!(g["energy_error"].as_f64().unwrap().abs() < 0.1, "{g}");
        assert!(g["centroid_shift_px"].as_f64().unwrap() < 1.0, "{g}");
    }
    assert!(cells[1]["ghosts"].as_array().unwrap().is_empty());

    let text = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let csv = text("results.csv");
    assert_eq!(csv.lines().count(), 1 + 4, "{csv}");
    assert!(
        csv.lines().skip(1).any(|l| l.contains(",true,")),
        "no Pareto point: {csv}"
    );
    assert!(text("per_ghost.csv").lines().count() > 3 * 10);
    let html = text("index.html");
    for needle in [
        "plot-cooke-triplet-25mm-8-60.png",
        "plot-cooke-triplet-25mm-8-60.svg",
        "contact-cooke-triplet-25mm-8-60.png",
        "results.csv",
        "grid_scale=0.5",
    ] {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
    assert!(!html.contains("http://") && !html.contains("https://") && !html.contains("<script"));
    assert!(text("plot-cooke-triplet-25mm-8-60.svg").contains("<svg"));
    let plot = image::open(dir.join("plot-cooke-triplet-25mm-8-60.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(plot.dimensions(), (960, 600));
    // Text and series were drawn: far from a blank white page.
    let dark = plot
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c < 128))
        .count();
    assert!(dark > 2000, "{dark} dark pixels");
    let sheet = image::open(dir.join("contact-cooke-triplet-25mm-8-60.png")).unwrap();
    assert!(sheet.width() > 5 * 64 && sheet.height() > 36);

    // Run again: every cell and the reference come from the cache.
    let v2: Value = serde_json::from_slice(&sweep(dir, &["--json"]).stdout).unwrap();
    assert_eq!(v2["cells_run"], 0);
    assert_eq!(v2["cells_reused"], 4);
    assert_eq!(v2["references_rendered"], 0);
    assert_eq!(
        v2["cases"][0]["cells"][3]["relative_rmse"],
        cells[3]["relative_rmse"]
    );
    // Another value: only its cell runs.
    let out = sweep(dir, &["--vary", "dim_budget=0", "--json"]);
    let v3: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v3["cells_run"],
        1,
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(v3["cells_reused"], 4);
}

#[test]
fn a_sweep_refuses_an_unknown_parameter_or_value_before_running_anything() {
    let tmp = temp_dir("sweep-bad");
    let dir = tmp.path();
    let out = flarebench(&[
        "sweep",
        "cooke-triplet-25mm",
        "--vary",
        "grid_sclae=1,2",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("grid_sclae") && err.contains("grid_scale"),
        "{err}"
    );
    let out = flarebench(&[
        "sweep",
        "cooke-triplet-25mm",
        "--vary",
        "dim_budget=lots",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("dim_budget=lots"), "{err}");
    assert!(!dir.join("results.csv").exists());
}

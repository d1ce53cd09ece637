//! End-to-end tests of `flarebench render` and `flarebench precompute`.

use crate::common;

use common::{flarebench, json, temp_dir};

use serde_json::Value;

/// Relative RMSE of the default preset against the reference: the issue's budget (measured
/// 0.89%).
const RMSE_BUDGET: f64 = 0.02;
/// Energy error of the default preset against the reference (measured −0.13%).
const ENERGY_ERROR_TOL: f64 = 0.005;
/// Image energy with precomputed bounds against bounds traced at the light's angle (relative).
const PRECOMPUTED_ENERGY_TOL: f64 = 0.05;
/// Ghosts drawn with looked-up bounds against traced bounds: how many may differ.
const PRECOMPUTED_GHOSTS_DRAWN_SLACK: i64 = 2;
/// Where the chief ray of a light placed by `--light-at` lands against the requested pixel.
const LIGHT_AT_TOL_PX: f64 = 0.01;
/// The bounded-out ghosts' shares summed against the reported total (relative): f64 rounding.
const SHARE_SUM_REL_TOL: f64 = 1e-9;
/// Largest energy share of one four-reflection ghost the bound leaves out.
const BOUNDED_OUT_MAX_SHARE: f64 = 1e-5;
/// Image energy with OpenLensFlare's distance map of the octagon against the octagon's mask
/// (relative).
const DISTANCE_MAP_ENERGY_TOL: f64 = 0.01;
/// Colour sums drawn band by band against fringed (relative; measured within 0.004%).
const BAND_BY_BAND_COLOUR_SUM_TOL: f64 = 1e-3;

#[test]
fn render_writes_an_image_and_reports_what_it_did() {
    let tmp = temp_dir("render");
    let out = tmp.path().join("heliar.exr");
    let v = json(&[
        "render",
        "heliar-tronnier",
        "--light",
        "8,30",
        "--size",
        "192x108",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.is_file());
    let light = &v["lights"][0];
    let traced = light["ghosts_traced"].as_u64().unwrap();
    let dropped = light["ghosts_dropped"].as_u64().unwrap();
    assert_eq!(
        traced + dropped,
        28,
        "the Heliar has 28 two-reflection ghosts"
    );
    assert!(traced > 5);
    let f = light["dropped_energy_fraction"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&f));
    let sum: Vec<f64> = v["image_sum_rgb"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    assert!(sum.iter().all(|&c| c > 0.0), "{sum:?}");
    // The Heliar's coatings are quarter-wave layers for 620 nm: its ghosts are blue.
    assert!(sum[2] > sum[1] && sum[2] > sum[0], "{sum:?}");
    for key in ["load_ms", "plan_ms", "render_ms", "write_ms"] {
        assert!(v["timings"][key].as_f64().unwrap() >= 0.0, "{key}");
    }
    assert!(v["error"].is_null());
}

/// The fast preset splats the Nikon zoom's near-focus ghosts on a small frame (their
/// triangles land under a quarter pixel), and the report says which ghosts it splatted and
/// what the plan predicted, in JSON and in text.
#[test]
fn the_report_gives_each_ghost_s_drawing_method_and_prediction() {
    let tmp = temp_dir("methods");
    let out = tmp.path().join("nikon.exr");
    let args = [
        "render",
        "nikon-zoom-short",
        "--light",
        "10,30",
        "--size",
        "320x180",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "-o",
        out.to_str().unwrap(),
    ];
    let v = json(&[&args[..], &["--json"]].concat());
    let ghosts = v["lights"][0]["ghosts"].as_array().unwrap();
    let splatted: Vec<&Value> = ghosts.iter().filter(|g| g["method"] == "splat").collect();
    assert!(!splatted.is_empty(), "no ghost splatted");
    assert!(splatted.len() < ghosts.len(), "every ghost splatted");
    for g in &splatted {
        let p = &g["prediction"];
        assert!(p["triangle_px"].as_f64().unwrap() < 0.25, "{g}");
        assert!(
            p["splat_ns"].as_f64().unwrap() < p["mesh_ns"].as_f64().unwrap(),
            "{g}"
        );
        assert!(p["frame_error2"].as_f64().unwrap() > 0.0, "{g}");
    }
    let added: f64 = splatted
        .iter()
        .map(|g| g["prediction"]["frame_error2"].as_f64().unwrap())
        .sum::<f64>()
        .sqrt();
    assert!(
        added <= 0.03,
        "predicted {added} over the fast preset's budget"
    );
    let text = flarebench(&[&args[..], &["--report"]].concat());
    let report =
        String::from_utf8_lossy(&text.stderr).to_string() + &String::from_utf8_lossy(&text.stdout);
    assert!(
        report.contains(&format!("{} ghosts splatted", splatted.len())),
        "{report}"
    );
}

#[test]
fn reference_error_is_reported_and_small() {
    let tmp = temp_dir("render-ref");
    let dir = tmp.path();
    let out = dir.join("ref.png");
    let saved = dir.join("reference.exr");
    let _ = std::fs::remove_file(&saved);
    let (out, saved_s) = (out.to_str().unwrap(), saved.to_str().unwrap());
    let args = |light| {
        [
            "render",
            "heliar-tronnier",
            "--light",
            light,
            "--size",
            "160x90",
            "-o",
            out,
            "--reference-file",
            saved_s,
            "--json",
        ]
    };
    let v = json(&args("5,0"));
    assert!(saved.is_file(), "the reference was saved");
    // The second run reads the saved reference: the same figures.
    let again = json(&args("5,0"));
    assert_eq!(v["error"], again["error"]);
    // Another scene refuses the file rather than comparing against the wrong picture.
    let o = flarebench(&args("5,10"));
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("reference of another scene"), "{err}");
    let e = &v["error"];
    let rmse = e["relative_rmse"].as_f64().unwrap();
    let energy = e["energy_error"].as_f64().unwrap();
    // Measured for the default preset: RMSE 0.89%, energy −0.13%. The issue's budget is 2%.
    assert!(rmse > 0.0 && rmse < RMSE_BUDGET, "relative RMSE {rmse}");
    assert!(energy.abs() < ENERGY_ERROR_TOL, "energy error {energy}");
    assert!(v["timings"]["reference_ms"].as_f64().is_some());
}

#[test]
fn precomputed_bounds_give_the_same_ghosts() {
    let tmp = temp_dir("render");
    let dir = tmp.path();
    let table = dir.join("heliar-bounds.json");
    precompute_heliar_to_12_degrees(&table);
    let run = |extra: &[&str]| -> Value {
        let o = dir.join("p.exr");
        let mut a = vec![
            "render",
            "heliar-tronnier",
            "--light",
            "6.25,10",
            "--size",
            "160x90",
            "--quality",
            "fast",
            "--json",
            "-o",
            o.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let direct = run(&[]);
    let pre = run(&["--precomputed", table.to_str().unwrap()]);
    assert_eq!(
        direct["lights"][0]["ghosts_total"],
        pre["lights"][0]["ghosts_total"]
    );
    let (a, b) = (
        direct["image_sum_rgb"][1].as_f64().unwrap(),
        pre["image_sum_rgb"][1].as_f64().unwrap(),
    );
    assert!(
        (a / b - 1.0).abs() < PRECOMPUTED_ENERGY_TOL,
        "image energy {a} vs {b}"
    );
    // A table for another lens is refused.
    let out = flarebench(&[
        "render",
        "nikon-zoom-short",
        "--light",
        "5,0",
        "-o",
        dir.join("x.exr").to_str().unwrap(),
        "--precomputed",
        table.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not this prescription"));
}

#[test]
fn bad_render_arguments_are_refused() {
    let tmp = temp_dir("render");
    let o = tmp.path().join("bad.exr");
    let o = o.to_str().unwrap();
    for args in [
        vec!["render", "heliar-tronnier", "--light", "95,0", "-o", o],
        vec!["render", "heliar-tronnier", "--light", "5", "-o", o],
        vec![
            "render",
            "heliar-tronnier",
            "--light",
            "5,0",
            "--size",
            "0x10",
            "-o",
            o,
        ],
        vec![
            "render",
            "heliar-tronnier",
            "--light",
            "5,0",
            "--iris-blades",
            "2",
            "-o",
            o,
        ],
    ] {
        let out = flarebench(&args);
        assert!(!out.status.success(), "{args:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }
}

#[test]
fn bench_times_each_preset_and_reports_what_it_drew() {
    let v = json(&[
        "bench",
        "heliar-tronnier",
        "--size",
        "96x54",
        "--runs",
        "2",
        "--quality",
        "fast,high",
        "--json",
    ]);
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, q) in rows.iter().zip(["fast", "high"]) {
        assert_eq!(row["quality"], q);
        assert_eq!(row["ghosts_total"], 28);
        let drawn = row["ghosts_drawn"].as_u64().unwrap();
        assert!(drawn > 0 && drawn <= 28);
        for key in ["plan_ms", "render_ms", "frame_ms"] {
            assert!(row[key].as_f64().unwrap() > 0.0, "{key}");
        }
        assert!(row["relative_rmse"].is_null(), "no --error, no error");
    }
    // A finer preset keeps at least as many ghosts (its energy threshold is lower).
    assert!(rows[1]["ghosts_drawn"].as_u64() >= rows[0]["ghosts_drawn"].as_u64());
}

/// With a precomputed table the plan looks the bounds up: the same ghosts are drawn, and a
/// table is refused for more than one lens.
#[test]
fn bench_plans_from_a_precomputed_table() {
    let tmp = temp_dir("bench-table");
    let table = tmp.path().join("heliar.json");
    precompute_heliar_to_12_degrees(&table);
    let t = table.to_str().unwrap();
    let base = [
        "bench",
        "heliar-tronnier",
        "--size",
        "96x54",
        "--runs",
        "1",
        "--quality",
        "default",
        "--json",
    ];
    let traced = json(&base);
    let looked_up = json(&[&base[..], &["--precomputed", t]].concat());
    assert_eq!(traced[0]["precomputed"], false);
    assert_eq!(looked_up[0]["precomputed"], true);
    assert_eq!(looked_up[0]["ghosts_total"], 28);
    let (a, b) = (
        traced[0]["ghosts_drawn"].as_i64().unwrap(),
        looked_up[0]["ghosts_drawn"].as_i64().unwrap(),
    );
    assert!(
        (a - b).abs() <= PRECOMPUTED_GHOSTS_DRAWN_SLACK,
        "traced {a}, looked up {b}"
    );
    let out = flarebench(&[
        "bench",
        "heliar-tronnier",
        "double-gauss-50mm",
        "--precomputed",
        t,
        "--runs",
        "1",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("exactly one lens"));
}

#[test]
fn a_light_placed_by_its_image_position_images_there() {
    let tmp = temp_dir("render");
    let out = tmp.path().join("at.exr");
    let v = json(&[
        "render",
        "heliar-tronnier",
        "--light-at",
        "1500,250,2,3200",
        "--size",
        "1920x1080",
        "--quality",
        "fast",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let light = &v["lights"][0];
    let (theta, phi) = (
        light["theta_deg"].as_f64().unwrap(),
        light["phi_deg"].as_f64().unwrap(),
    );
    assert!(theta > 5.0 && theta < 20.0, "θ {theta}");
    assert_eq!(light["intensity"].as_f64(), Some(2.0));
    // The starburst sits where the chief ray lands: the requested pixel.
    let at = &v["starbursts"][0]["position_px"];
    let (x, y) = (at[0].as_f64().unwrap(), at[1].as_f64().unwrap());
    assert!(
        (x - 1500.0).abs() < LIGHT_AT_TOL_PX && (y - 250.0).abs() < LIGHT_AT_TOL_PX,
        "({x}, {y}), φ {phi}"
    );
    // Nonsense is refused with the option named.
    for bad in ["1500", "a,b", "1,2,-1", "1,2,3,1:2"] {
        let o = flarebench(&[
            "render",
            "heliar-tronnier",
            "--light-at",
            bad,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{bad}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("light"),
            "{bad}"
        );
    }
}

/// `--reflections 4` adds the Heliar's 658 four-reflection paths: the report counts them,
/// lists those the energy bound left out (reason `bound`, written a-b-c-d) and their share,
/// and the two-reflection part of the render is what `--reflections 2` gives.
#[test]
fn four_reflection_ghosts_are_rendered_and_reported() {
    let tmp = temp_dir("render");
    let dir = tmp.path();
    let run = |extra: &[&str]| -> Value {
        let o = dir.join("four.exr");
        let mut a = vec![
            "render",
            "heliar-tronnier",
            "--light",
            "10,30",
            "--size",
            "192x108",
            "--quality",
            "fast",
            "--starburst",
            "off",
            "--report",
            "--json",
            "-o",
            o.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let two = run(&[]);
    let four = run(&["--reflections", "4"]);
    let (l2, l4) = (&two["lights"][0], &four["lights"][0]);
    assert!(l2.get("four_reflections").is_none(), "{l2}");
    assert_eq!(l2["ghosts_total"].as_u64(), Some(28));
    assert_eq!(l4["ghosts_total"].as_u64(), Some(28 + 658));
    let s = &l4["four_reflections"];
    assert_eq!(s["paths"].as_u64(), Some(658));
    let bounded = s["bounded_out"].as_u64().unwrap();
    assert!(bounded > 0 && bounded < 658, "{s}");
    assert_eq!(
        s["bounded_out"].as_u64().unwrap()
            + s["dropped_after_bounds"].as_u64().unwrap()
            + s["traced"].as_u64().unwrap(),
        658
    );
    let dropped = l4["dropped"].as_array().unwrap();
    let by_bound: Vec<&Value> = dropped.iter().filter(|d| d["reason"] == "bound").collect();
    assert_eq!(by_bound.len() as u64, bounded);
    let share: f64 = by_bound
        .iter()
        .map(|d| d["energy_share"].as_f64().unwrap())
        .sum();
    let want = s["bounded_out_energy_share"].as_f64().unwrap();
    assert!(
        (share / want - 1.0).abs() < SHARE_SUM_REL_TOL,
        "{share} vs {want}"
    );
    for d in &by_bound {
        let name = d["ghost"].as_str().unwrap();
        assert_eq!(name.split('-').count(), 4, "{name}");
        assert!(
            d["energy_share"].as_f64().unwrap() < BOUNDED_OUT_MAX_SHARE,
            "{d}"
        );
    }
    // More ghost energy in all, and more of it left out (the bounds).
    let e = |l: &Value, k: &str| l[k].as_f64().unwrap();
    assert!(e(l4, "ghost_energy_share") > e(l2, "ghost_energy_share"));
    assert!(e(l4, "dropped_energy_fraction") > e(l2, "dropped_energy_fraction"));
    // The four-reflection ghosts only add light.
    for c in 0..3 {
        let (a, b) = (
            two["image_sum_rgb"][c].as_f64().unwrap(),
            four["image_sum_rgb"][c].as_f64().unwrap(),
        );
        assert!(b >= a, "channel {c}: {b} < {a}");
    }
    // The text report says it too.
    let o = dir.join("four.exr");
    let out = flarebench(&[
        "render",
        "heliar-tronnier",
        "--light",
        "10,30",
        "--size",
        "192x108",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "--reflections",
        "4",
        "--report",
        "-o",
        o.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("four-reflection ghosts: 658 paths"), "{text}");
    // Only 2 and 4.
    let out = flarebench(&[
        "render",
        "heliar-tronnier",
        "--light",
        "10,30",
        "--reflections",
        "3",
        "-o",
        o.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("reflections must be 2"));
}

/// `precompute --reflections 4` writes a version-2 table with the four-reflection ghosts
/// that pass the bound; `render --reflections 4 --precomputed` uses it, and gives about the
/// same image as without a table.
#[test]
fn precomputed_four_reflection_tables() {
    let tmp = temp_dir("render");
    let dir = tmp.path();
    let table = dir.join("heliar-bounds-4.json");
    let v = json(&[
        "precompute",
        "heliar-tronnier",
        "-o",
        table.to_str().unwrap(),
        "--max-angle-deg",
        "2",
        "--reflections",
        "4",
        "--bound-threshold",
        "1e-5",
        "--json",
    ]);
    assert_eq!(v["four_reflection_paths"].as_u64(), Some(658));
    let kept = v["four_reflection_ghosts"].as_u64().unwrap();
    assert!(kept > 0 && kept < 658, "{v}");
    assert_eq!(v["ghosts"].as_u64(), Some(28 + kept));
    let text = std::fs::read_to_string(&table).unwrap();
    assert!(text.contains(r#""version":4"#));
    let run = |extra: &[&str]| -> Value {
        let o = dir.join("p4.exr");
        let mut a = vec![
            "render",
            "heliar-tronnier",
            "--light",
            "1.25,10",
            "--size",
            "160x90",
            "--quality",
            "fast",
            "--starburst",
            "off",
            "--reflections",
            "4",
            "--json",
            "-o",
            o.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let direct = run(&[]);
    let pre = run(&["--precomputed", table.to_str().unwrap()]);
    assert_eq!(
        direct["lights"][0]["four_reflections"]["bounded_out"],
        pre["lights"][0]["four_reflections"]["bounded_out"]
    );
    let (a, b) = (
        direct["image_sum_rgb"][1].as_f64().unwrap(),
        pre["image_sum_rgb"][1].as_f64().unwrap(),
    );
    assert!(
        (a / b - 1.0).abs() < PRECOMPUTED_ENERGY_TOL,
        "image energy {a} vs {b}"
    );
}

/// `--aperture-mask`: the octagon of `lenses/masks/aperture.bmp` (open area 2.984 against the
/// circle's π) dims the ghosts by about its area, and OpenLensFlare's distance map of the same
/// octagon gives the same image.
#[test]
fn an_aperture_mask_shapes_the_ghosts() {
    let tmp = temp_dir("render-mask");
    let dir = tmp.path();
    let out = dir.join("m.exr");
    let sum = |mask: Option<&str>| -> f64 {
        let mut args = vec![
            "render",
            "heliar-tronnier",
            "--light",
            "5,30",
            "--size",
            "192x108",
            "--starburst",
            "off",
            "-o",
            out.to_str().unwrap(),
            "--json",
        ];
        if let Some(m) = mask {
            args.extend(["--aperture-mask", m]);
        }
        let v = json(&args);
        v["image_sum_rgb"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap())
            .sum()
    };
    let lenses = concat!(env!("CARGO_MANIFEST_DIR"), "/../lenses/masks/");
    let circle = sum(None);
    let octagon = sum(Some(&format!("{lenses}aperture.bmp")));
    let distance_map = sum(Some(&format!("{lenses}apertureDist.bmp")));
    let ratio = octagon / circle;
    assert!(
        (0.85..0.99).contains(&ratio),
        "octagon / circle energy {ratio} (areas: {})",
        2.984 / std::f64::consts::PI
    );
    assert!(
        ((distance_map - octagon) / octagon).abs() < DISTANCE_MAP_ENERGY_TOL,
        "{distance_map} vs {octagon}"
    );
}

/// OpenLensFlare's bounds file for the Heliar-Tronnier, as bundled for the tests.
/// `flarebench precompute heliar-tronnier` over 0–12° into `table`.
fn precompute_heliar_to_12_degrees(table: &std::path::Path) {
    let out = flarebench(&[
        "precompute",
        "heliar-tronnier",
        "-o",
        table.to_str().unwrap(),
        "--max-angle-deg",
        "12",
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn olf_bounds_file() -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/heliar-tronnier-bounds-full.xml")
        .to_str()
        .unwrap()
        .to_string()
}

/// Renders the Heliar's ghosts (no starburst) at `light` into `dir/name.exr` with `extra`
/// arguments; returns the report and the image.
fn render_heliar(
    dir: &std::path::Path,
    name: &str,
    light: &str,
    extra: &[&str],
) -> (Value, flarebench_sdk::image::HdrImage) {
    let out = dir.join(format!("{name}.exr"));
    let mut a = vec![
        "render",
        "heliar-tronnier",
        "--light",
        light,
        "--size",
        "320x180",
        "--starburst",
        "off",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ];
    a.extend_from_slice(extra);
    let v = json(&a);
    (v, flarebench::output::read_exr(&out).unwrap())
}

#[test]
fn openlensflare_bounds_render_the_heliar_as_our_own_bounds_do() {
    let tmp = temp_dir("render-olf");
    let dir = tmp.path();
    let olf = olf_bounds_file();
    let table = dir.join("heliar-bounds.json");
    precompute_heliar_to_12_degrees(&table);
    for light in ["5,0", "10,30"] {
        let (plain, img_plain) = render_heliar(dir, "plain", light, &[]);
        let (ours, img_ours) = render_heliar(
            dir,
            "ours",
            light,
            &["--precomputed", table.to_str().unwrap()],
        );
        let (from_olf, img_olf) = render_heliar(dir, "olf", light, &["--precomputed", &olf]);
        let l = &from_olf["lights"][0];
        // Every ghost of the lens is accounted for: the 13 of the file looked up, the 15 that
        // straddle the stop traced and listed.
        assert_eq!(l["ghosts_total"], 28);
        assert_eq!(l["bounds_not_in_table"].as_array().unwrap().len(), 15);
        assert!(plain["lights"][0]["bounds_not_in_table"].is_null());
        assert!(ours["lights"][0]["bounds_not_in_table"].is_null());
        let c_ours = img_ours.compare(&img_plain).unwrap();
        let c_olf = img_olf.compare(&img_plain).unwrap();
        let c_olf_ours = img_olf.compare(&img_ours).unwrap();
        eprintln!(
            "light {light}: ours/plain rmse {:.4} E {:+.4}; olf/plain rmse {:.4} L1 {:.4} E {:+.4}; olf/ours rmse {:.4} E {:+.4}",
            c_ours.relative_rmse,
            c_ours.energy_error,
            c_olf.relative_rmse,
            c_olf.relative_l1,
            c_olf.energy_error,
            c_olf_ours.relative_rmse,
            c_olf_ours.energy_error
        );
        assert!(c_ours.relative_rmse < OLF_MAX_RMSE, "{light}: {c_ours:?}");
        for c in [c_olf, c_olf_ours] {
            assert!(c.relative_rmse < OLF_MAX_RMSE, "{light}: {c:?}");
            // Cut rectangles only lose light.
            assert!(
                (-OLF_MAX_ENERGY_LOSS..OLF_MAX_ENERGY_GAIN).contains(&c.energy_error),
                "{light}: {c:?}"
            );
        }
    }
}

/// The image with OpenLensFlare's bounds against ours (none, or our JSON table), at 320×180,
/// default quality, lights 5,0 and 10,30. Measured: relative RMSE 4.4% and
/// 5.6% against the render without a table (6.5% against our table at 10,30; our own table
/// against no table: 0.4% and 3.6%), energy −1.8% and −1.2%. The difference is the file's
/// rectangles cutting ghosts (372 of its 574 entries with light: OpenLensFlare clips at a
/// sensor radius of 24 mm and traces flat surfaces unrefracted), not its grid sizes (our grid
/// rule instead changes the figures by < 0.1%). With OpenLensFlare's x and y not swapped the
/// RMSE is 28% and 74%, so the bounds below catch a wrong conversion.
const OLF_MAX_RMSE: f64 = 0.08;
/// Energy: cut rectangles lose light (−1.8% at worst above), they cannot add any beyond the
/// run-to-run noise of the two renders (our table against none: +0.35%).
const OLF_MAX_ENERGY_LOSS: f64 = 0.03;
const OLF_MAX_ENERGY_GAIN: f64 = 0.005;

#[test]
fn openlensflare_bounds_for_another_lens_or_corrupted_are_refused_with_their_place() {
    let tmp = temp_dir("render-olf-bad");
    let dir = tmp.path();
    let o = dir.join("x.exr");
    let render = |lens: &str, file: &str| {
        flarebench(&[
            "render",
            lens,
            "--light",
            "5,0",
            "--size",
            "64x36",
            "--starburst",
            "off",
            "-o",
            o.to_str().unwrap(),
            "--precomputed",
            file,
        ])
    };
    let olf = olf_bounds_file();
    // The Heliar's file with the Nikon zoom: its ghosts are not the Nikon's.
    let out = render("nikon-zoom-short", &olf);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("heliar-tronnier-bounds-full.xml"), "{err}");
    assert!(
        err.contains("the file's 13 ghosts are not those of lens `nikon-zoom-short`"),
        "{err}"
    );
    // A corrupted value: reported at its file, line, column and field. Line 14 of the file
    // is the first ghost's pupil `<w>`, its value at column 24.
    let text = std::fs::read_to_string(&olf).unwrap();
    let line = text.lines().nth(13).unwrap();
    assert_eq!(line.trim(), "<w>0.181061</w>");
    let bad = dir.join("bad-bounds.xml");
    std::fs::write(&bad, text.replacen("<w>0.181061</w>", "<w>0.18q061</w>", 1)).unwrap();
    let out = render("heliar-tronnier", bad.to_str().unwrap());
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let want = format!(
        "{}:14:24: field `w`: expected a number, got `0.18q061`",
        bad.display()
    );
    assert!(err.contains(&want), "{err}");
    // A broken JSON table: file, line, column and the key.
    let bad = dir.join("bad-bounds.json");
    std::fs::write(
        &bad,
        "{\"format\":\"flarebench-ghost-bounds\",\"version\":1,\n\"angles_deg\":[0.0,\"x\"]}",
    )
    .unwrap();
    let out = render("heliar-tronnier", bad.to_str().unwrap());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains(&format!("{}:2:", bad.display())), "{err}");
    assert!(err.contains("field `angles_deg`"), "{err}");
    // Neither kind.
    std::fs::write(&bad, "angle,ghost\n").unwrap();
    let err = String::from_utf8_lossy(&render("heliar-tronnier", bad.to_str().unwrap()).stderr)
        .to_string();
    assert!(err.contains("neither a flarebench bounds table"), "{err}");
}

/// `--band-by-band` draws each wavelength band on its own; the default fringed groups give
/// the same light per colour (measured when written at this size: within 0.004%).
#[test]
fn band_by_band_and_fringed_bands_give_the_same_light() {
    let tmp = temp_dir("render-bands");
    let dir = tmp.path();
    let out = dir.join("bands.exr");
    let out = out.to_str().unwrap();
    let args = |extra: Option<&'static str>| {
        let mut a = vec![
            "render",
            "heliar-tronnier",
            "--light",
            "10,30",
            "--size",
            "640x360",
            "--starburst",
            "off",
            "-o",
            out,
            "--json",
        ];
        a.extend(extra);
        a
    };
    let fringed = json(&args(None));
    let bands = json(&args(Some("--band-by-band")));
    for c in 0..3 {
        let (a, b) = (
            fringed["image_sum_rgb"][c].as_f64().unwrap(),
            bands["image_sum_rgb"][c].as_f64().unwrap(),
        );
        assert!(
            (a / b - 1.0).abs() < BAND_BY_BAND_COLOUR_SUM_TOL,
            "channel {c}: {a} against {b}"
        );
    }
}

/// Without `--reference-file`, a scene's reference is kept in the cache directory and read back
/// while the scene stays the same: the same figures, "read from the cache"; a damaged file is
/// rendered over; `FLAREBENCH_REFERENCE_CACHE` set empty keeps nothing.
#[test]
fn the_reference_is_cached_per_scene_and_a_damaged_file_rendered_over() {
    let tmp = temp_dir("reference-cache");
    let dir = tmp.path();
    // The Lensbaby (two elements): its reference takes seconds.
    let cache = dir.join("cache");
    let run_with = |cache: &std::path::Path, json: bool, reference: &[&str]| {
        let mut c = common::command();
        c.args([
            "render",
            "lensbaby",
            "--light",
            "2,0",
            "--size",
            "64x36",
            "-o",
            dir.join("out.exr").to_str().unwrap(),
        ])
        .args(reference)
        .env("FLAREBENCH_REFERENCE_CACHE", cache)
        .env("XDG_CACHE_HOME", dir.join("xdg"));
        c.arg(if json { "--json" } else { "--report" });
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let run = |cache: &std::path::Path, json: bool| run_with(cache, json, &["--reference"]);
    let files = |d: &std::path::Path| -> Vec<std::path::PathBuf> {
        std::fs::read_dir(d)
            .map(|r| r.map(|e| e.unwrap().path()).collect())
            .unwrap_or_default()
    };
    let first: Value = serde_json::from_slice(&run(&cache, true).stdout).unwrap();
    let kept = files(&cache);
    assert_eq!(kept.len(), 1, "{kept:?}");
    assert!(kept[0].extension().is_some_and(|e| e == "exr"));
    let bytes = std::fs::read(&kept[0]).unwrap();

    let again = run(&cache, false);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("reference read from the cache"), "{err}");
    let second: Value = serde_json::from_slice(&run(&cache, true).stdout).unwrap();
    assert_eq!(first["error"], second["error"]);
    assert!(
        first["error"]["relative_rmse"].as_f64().is_some(),
        "{first}"
    );

    std::fs::write(&kept[0], b"not an image").unwrap();
    let redone = run(&cache, false);
    let err = String::from_utf8_lossy(&redone.stderr);
    assert!(err.contains("reference rendered and cached"), "{err}");
    assert_eq!(std::fs::read(&kept[0]).unwrap(), bytes);

    let _ = run(std::path::Path::new(""), true);
    assert!(files(&dir.join("xdg")).is_empty());
    assert_eq!(files(&cache).len(), 1);

    // A `--reference-file` that does not exist yet is written from the cache, not rendered…
    let file = dir.join("saved.exr");
    let saved = run_with(&cache, false, &["--reference-file", file.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&saved.stderr);
    assert!(
        err.contains("reference read from the cache") && err.contains("and saved to"),
        "{err}"
    );
    assert_eq!(std::fs::read(&file).unwrap(), bytes);
    // …and one rendered for a file is kept in the cache too.
    let other_cache = dir.join("cache2");
    std::fs::remove_file(&file).unwrap();
    let rendered = run_with(
        &other_cache,
        false,
        &["--reference-file", file.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&rendered.stderr);
    assert!(err.contains("reference rendered and saved to"), "{err}");
    assert_eq!(files(&other_cache).len(), 1);
    assert_eq!(std::fs::read(&files(&other_cache)[0]).unwrap(), bytes);
}

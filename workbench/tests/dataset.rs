//! End-to-end tests of `flarebench dataset`: samples the same bytes whether rendered by one
//! process, by shards in parallel processes, as a range or with any thread count; a killed
//! or damaged run resumed; the layers the ordinary render of the scene; `dataset verify` catching a missing and a corrupted file; annotations that
//! match the images; the sampler's ranges; bad sampler files refused with their position.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{command, flarebench, temp_dir};
use flarebench::dataset::layers::{layer_image, read_channels};
use flarebench::dataset::sample::render_whole;
use flarebench::dataset::{Sampler, render_sample};
use flarebench_sdk::color::srgb::luminance;
use serde_json::Value;

/// Where a light's chief ray lands against the pixel it was aimed at (pixels): the aim
/// (`sources::direction_of`) stops within 1e-6 mm of the target's height, under 1e-4 px at
/// 64 px across 36 mm; the landing is then rounded to f32 pixels (6e-6 px at 64 px).
const AIM_TOL_PX: f64 = 1e-3;
/// The ghosts' layer's luminance against the sum of the ghosts' energies, each ghost drawn
/// alone (relative): the same triangles, the f32 additions in another order.
const GHOST_SUM_REL_TOL: f64 = 1e-4;
/// The flare against its ghosts' and starbursts' layers added, per pixel (relative to the
/// flare's largest value): f32 additions of several lights' starbursts in another order.
const LAYER_SUM_REL_TOL: f32 = 1e-5;

/// The flare and ghost layers (each ghost drawn alone, the windows summed) against
/// `Flare::render` of the same scene (all ghosts at once): relative RMSE and energy error.
/// The same triangles, the f32 additions in another order (a coarse ghost upsampled alone,
/// not with its level); measured at most 1.3e-7 (ghosts) and 3.4e-12 (flare) on the samples of
/// `the_layers_are_the_ordinary_render_of_the_scene`.
const WHOLE_REL_TOL: f64 = 1e-6;

/// A tiny, fast sampler: two lenses, 64×48, per-light layers.
const TINY: &str = r#"
size = [64, 48]
quality = "fast"
starburst_texels = 64

[lenses]
names = ["heliar-tronnier", "double-gauss-50mm"]

[lights]
count = [1, 2]

[layers]
per_light = true
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs `dataset` into `out` and asserts it succeeded; returns its last line.
fn dataset(config: &Path, out: &Path, count: &str, extra: &[&str]) -> String {
    let mut args = vec![
        "dataset",
        "--count",
        count,
        "--seed",
        "11",
        "--config",
        config.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = flarebench(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// Every file of a dataset but its records' directory, by relative path.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for name in ["dataset.json", "manifest.jsonl"] {
        out.insert(name.to_string(), std::fs::read(dir.join(name)).unwrap());
    }
    for e in std::fs::read_dir(dir.join("samples")).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        out.insert(format!("samples/{name}"), std::fs::read(&p).unwrap());
    }
    out
}

fn assert_same(a: &BTreeMap<String, Vec<u8>>, b: &BTreeMap<String, Vec<u8>>) {
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the same files"
    );
    for (k, v) in a {
        assert!(v == &b[k], "`{k}` differs");
    }
}

#[test]
fn shards_in_parallel_processes_thread_counts_and_ranges_give_the_same_bytes() {
    let tmp = temp_dir("dataset-shards");
    let config = write(tmp.path(), "tiny.toml", TINY);
    let one = tmp.path().join("one");
    dataset(&config, &one, "4", &["--threads", "1"]);
    let reference = files(&one);
    // 4 samples × (EXR, PNG, JSON) and the two top files.
    assert_eq!(reference.len(), 4 * 3 + 2);

    // Two shards at once, writing into one directory, on two threads each.
    let sharded = tmp.path().join("sharded");
    let children: Vec<_> = (0..2)
        .map(|i| {
            command()
                .args([
                    "dataset",
                    "--count",
                    "4",
                    "--seed",
                    "11",
                    "--config",
                    config.to_str().unwrap(),
                    "-o",
                    sharded.to_str().unwrap(),
                    "--shard",
                    &format!("{i}/2"),
                    "--threads",
                    "2",
                ])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains(": 2 rendered, 0 done already"));
    }
    // The last shard to finish may have merged before another wrote its last record.
    let o = flarebench(&["dataset", "merge", sharded.to_str().unwrap()]);
    assert!(o.status.success());
    assert_same(&reference, &files(&sharded));

    // A range renders only its samples, the same bytes.
    let part = tmp.path().join("part");
    let line = dataset(&config, &part, "4", &["--range", "2..2"]);
    assert!(line.contains("samples 2..2: 1 rendered"), "{line}");
    let part = files(&part);
    for name in ["00000002.exr", "00000002.json", "00000002.png"] {
        let k = format!("samples/{name}");
        assert!(reference[&k] == part[&k], "{k}");
    }
    assert!(!part.contains_key("samples/00000000.exr"));
    assert!(!part.contains_key("samples/00000003.exr"));
    let o = flarebench(&["dataset", "--count", "4", "--range", "2..4", "-o", "x"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("beyond the dataset's 4 samples"));
}

#[test]
fn verify_lists_a_missing_and_a_corrupted_file_and_a_rerun_redoes_only_those() {
    let tmp = temp_dir("dataset-verify");
    let config = write(tmp.path(), "tiny.toml", TINY);
    let dir = tmp.path().join("d");
    dataset(&config, &dir, "3", &[]);
    let before = files(&dir);
    let d = dir.to_str().unwrap();
    let o = flarebench(&["dataset", "verify", d]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("3 samples, every file matches"));

    std::fs::remove_file(dir.join("samples/00000001.exr")).unwrap();
    let png = dir.join("samples/00000002.png");
    let mut bytes = std::fs::read(&png).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&png, bytes).unwrap();

    let o = flarebench(&["dataset", "verify", d]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(
        lines[0].starts_with("samples/00000001.exr: missing"),
        "{out}"
    );
    assert!(
        lines[1].starts_with("samples/00000002.png: SHA-256 differs"),
        "{out}"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("2 bad files"));

    let line = dataset(&config, &dir, "3", &[]);
    assert!(line.contains("2 rendered, 1 done already"), "{line}");
    assert_same(&before, &files(&dir));
    assert!(flarebench(&["dataset", "verify", d]).status.success());

    // A manifest that lacks a sample.
    let manifest = dir.join("manifest.jsonl");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("{\"index\":2,"))
        .collect();
    std::fs::write(&manifest, kept.join("\n") + "\n").unwrap();
    let o = flarebench(&["dataset", "verify", d]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        "missing: sample 2"
    );
}

#[test]
fn a_killed_run_resumes_to_the_same_bytes() {
    let tmp = temp_dir("dataset-kill");
    let config = write(tmp.path(), "tiny.toml", TINY);
    let reference = tmp.path().join("reference");
    dataset(&config, &reference, "6", &["--threads", "2"]);

    let dir = tmp.path().join("killed");
    let mut child = command()
        .args([
            "dataset",
            "--count",
            "6",
            "--seed",
            "11",
            "--config",
            config.to_str().unwrap(),
            "-o",
            dir.to_str().unwrap(),
            "--threads",
            "1",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Kill it once two samples are done (or when it has finished, if it was that quick): two
    // records written, not counting a record's temporary file before its rename.
    let records = dir.join("records");
    let done_records = || {
        std::fs::read_dir(&records).map_or(0, |r| {
            r.filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".json"))
            })
            .count()
        })
    };
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(120) {
        let done = done_records();
        if done >= 2 || child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    child.wait().unwrap();
    assert!(done_records() >= 2);

    let line = dataset(&config, &dir, "6", &["--threads", "2"]);
    let rendered: usize = line
        .split(": ")
        .nth(2)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!(rendered <= 6 - 2, "{line}");
    // Temporary files a kill left behind are not part of the dataset.
    let mut resumed = files(&dir);
    resumed.retain(|k, _| !k.ends_with(".tmp"));
    assert_same(&files(&reference), &resumed);
}

#[test]
fn annotations_match_the_images() {
    let tmp = temp_dir("dataset-annotations");
    let config = write(tmp.path(), "tiny.toml", TINY);
    let dir = tmp.path().join("d");
    dataset(&config, &dir, "3", &[]);
    let mut ghosts_seen = 0;
    for i in 0..3 {
        let a: Value = serde_json::from_slice(
            &std::fs::read(dir.join(format!("samples/{i:08}.json"))).unwrap(),
        )
        .unwrap();
        let ((w, h), ch) = read_channels(&dir.join(format!("samples/{i:08}.exr"))).unwrap();
        assert_eq!((w, h), (64, 48));
        let names: Vec<&str> = a["channels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .collect();
        assert_eq!(names, ch.keys().map(String::as_str).collect::<Vec<_>>());

        // Lights: the chief ray lands where the light was aimed.
        let lights = a["lights"].as_array().unwrap();
        assert_eq!(
            lights.len(),
            a["sample"]["lights"].as_array().unwrap().len()
        );
        for (l, s) in lights.iter().zip(a["sample"]["lights"].as_array().unwrap()) {
            let p = &l["position_px"];
            let t = &s["target_px"];
            for k in 0..2 {
                let d = p[k].as_f64().unwrap() - t[k].as_f64().unwrap();
                assert!(d.abs() < AIM_TOL_PX, "sample {i}: {p} against {t}");
            }
            let (x, y) = (t[0].as_f64().unwrap(), t[1].as_f64().unwrap());
            let inside = (0.0..=64.0).contains(&x) && (0.0..=48.0).contains(&y);
            assert_eq!(l["inside_frame"].as_bool().unwrap(), inside);
        }

        // Ghosts: each box holds ≥ 99% of its energy and lies in its extent; every pixel
        // the ID layer gives a ghost lies in that ghost's extent; the energies add up to
        // the ghosts' layer.
        let ids = &ch["ghost_id"];
        let ghosts = a["ghosts"].as_array().unwrap();
        let mut energy_sum = 0.0;
        for (n, g) in ghosts.iter().enumerate() {
            assert_eq!(g["id"].as_u64().unwrap(), n as u64 + 1);
            let energy = g["energy"].as_f64().unwrap();
            energy_sum += energy;
            if g["box_px"].is_null() {
                assert_eq!(energy, 0.0);
                assert!(!ids.contains(&(n as f64 + 1.0)));
                continue;
            }
            ghosts_seen += 1;
            assert!(g["box_share"].as_f64().unwrap() >= 0.99, "{g}");
            let b: Vec<usize> = serde_json::from_value(g["box_px"].clone()).unwrap();
            let e: Vec<usize> = serde_json::from_value(g["extent_px"].clone()).unwrap();
            assert!(
                e[0] <= b[0] && e[1] <= b[1] && b[2] <= e[2] && b[3] <= e[3],
                "{g}"
            );
            for (p, &id) in ids.iter().enumerate() {
                if id == n as f64 + 1.0 {
                    let (x, y) = (p % w, p / w);
                    assert!(
                        e[0] <= x && x < e[2] && e[1] <= y && y < e[3],
                        "{g}: ({x}, {y})"
                    );
                }
            }
        }
        let ghost_layer = layer_image((w, h), &ch, "ghosts").unwrap();
        let layer_energy = luminance(ghost_layer.sum());
        assert!(
            (layer_energy - energy_sum).abs() <= GHOST_SUM_REL_TOL * layer_energy,
            "sample {i}: layer {layer_energy}, ghosts {energy_sum}"
        );

        // The flare is its ghosts and starbursts; each light's layer is part of it.
        let flare = layer_image((w, h), &ch, "").unwrap();
        let starburst = layer_image((w, h), &ch, "starburst").unwrap();
        let tol = LAYER_SUM_REL_TOL * flare.max();
        for ((f, g), s) in flare
            .pixels
            .iter()
            .zip(&ghost_layer.pixels)
            .zip(&starburst.pixels)
        {
            for c in 0..3 {
                assert!((f[c] - g[c] - s[c]).abs() <= tol, "{f:?} {g:?} {s:?}");
            }
        }
        let per_light: Vec<_> = (0..lights.len())
            .map(|k| layer_image((w, h), &ch, &format!("light{k}")).unwrap())
            .collect();
        let light_sum: f64 = per_light.iter().map(|l| luminance(l.sum())).sum();
        assert!((light_sum - luminance(flare.sum())).abs() <= 1e-4 * luminance(flare.sum()));
    }
    assert!(ghosts_seen > 10, "{ghosts_seen} ghosts lit the frames");
}

#[test]
fn the_library_renders_what_the_command_writes() {
    let tmp = temp_dir("dataset-library");
    let config = write(tmp.path(), "tiny.toml", TINY);
    let dir = tmp.path().join("d");
    dataset(&config, &dir, "1", &[]);
    let sampler = Sampler::from_toml_str(TINY, "tiny", tmp.path()).unwrap();
    let spec = sampler.sample(11, 0).unwrap();
    assert_eq!(spec, sampler.sample(11, 0).unwrap());
    let out = render_sample(&spec).unwrap();
    let ((w, h), ch) = read_channels(&dir.join("samples/00000000.exr")).unwrap();
    let flare = layer_image((w, h), &ch, "").unwrap();
    assert_eq!(flare.pixels, out.flare.pixels);
    let written = std::fs::read_to_string(dir.join("samples/00000000.json")).unwrap();
    assert_eq!(
        written,
        serde_json::to_string_pretty(&out.annotation).unwrap() + "\n"
    );
}

#[test]
fn the_layers_are_the_ordinary_render_of_the_scene() {
    // Two lights, and a frame large enough for coarse levels and full-resolution ghosts.
    let text = r#"
size = [160, 120]
starburst_texels = 64
[lenses]
names = ["heliar-tronnier"]
[lights]
count = [2, 2]
"#;
    let sampler = Sampler::from_toml_str(text, "whole", Path::new(".")).unwrap();
    for index in 0..2 {
        let spec = sampler.sample(3, index).unwrap();
        let out = render_sample(&spec).unwrap();
        let (flare, ghosts) = render_whole(&spec).unwrap();
        assert!(ghosts.max() > 0.0, "sample {index} draws ghosts");
        for (name, layer, whole) in [
            ("ghosts", &out.ghosts, &ghosts),
            ("flare", &out.flare, &flare),
        ] {
            let rmse = layer.relative_rmse(whole).unwrap();
            let energy = layer.energy_error(whole).unwrap().abs();
            eprintln!("sample {index} {name}: rmse {rmse:e}, energy {energy:e}");
            assert!(rmse <= WHOLE_REL_TOL, "sample {index} {name}: {rmse}");
            assert!(energy <= WHOLE_REL_TOL, "sample {index} {name}: {energy}");
        }
    }
}

#[test]
fn samples_respect_the_sampler_ranges() {
    let text = r#"
f_number = [2.8, 8]
[lenses]
names = ["heliar-tronnier", "double-gauss-50mm"]
weights = { "heliar-tronnier" = 3 }
[aperture]
circle_probability = 0.0
blades = [6, 7]
roundness = [0.1, 0.3]
[lights]
count = [2, 3]
outside_probability = 0.5
outside_margin = 0.1
ev = [-1, 1]
kelvin = [3000, 4000]
"#;
    let sampler = Sampler::from_toml_str(text, "ranges", Path::new(".")).unwrap();
    let n = 400;
    let mut heliar = 0;
    let mut outside = 0;
    let mut lights = 0;
    for i in 0..n {
        let s = sampler.sample(5, i).unwrap();
        assert!((2.8..=8.0).contains(&s.f_number));
        match s.aperture {
            flarebench::dataset::sampler::ApertureSpec::Iris {
                blades,
                rotation_deg,
                roundness,
            } => {
                assert!((6..=7).contains(&blades));
                assert!((0.1..=0.3).contains(&roundness));
                assert!((0.0..=360.0 / f64::from(blades)).contains(&rotation_deg));
            }
            a => panic!("no circle or mask was asked for: {a:?}"),
        }
        assert!((2..=3).contains(&s.lights.len()));
        for l in &s.lights {
            lights += 1;
            assert!((-1.0..=1.0).contains(&l.ev));
            assert_eq!(l.intensity, l.ev.exp2());
            assert!((3000.0..=4000.0).contains(&l.kelvin));
            let [x, y] = l.target_px;
            let inside = (0.0..=512.0).contains(&x) && (0.0..=512.0).contains(&y);
            assert_eq!(inside, !l.outside_frame);
            assert!((-51.2..=563.2).contains(&x) && (-51.2..=563.2).contains(&y));
            outside += usize::from(l.outside_frame);
        }
        heliar += usize::from(s.lens == "heliar-tronnier");
    }
    // Binomial shares: 3/4 of n = 400 samples (σ 0.022) and 1/2 of ~1000 lights (σ 0.016),
    // allowed 5σ.
    let share = heliar as f64 / n as f64;
    assert!((share - 0.75).abs() < 0.11, "{share}");
    let share = outside as f64 / lights as f64;
    assert!((share - 0.5).abs() < 0.08, "{share}");
}

#[test]
fn a_bad_sampler_names_the_file_line_and_field() {
    let tmp = temp_dir("dataset-bad");
    let out = tmp.path().join("d");
    let cases = [
        (
            "[lights]\ncount = [1, 2]\nev = [4, 1]\n",
            "line 3, column 6, field `lights.ev`: the range [4, 1] is empty",
        ),
        (
            "size = [64, 48]\n\n[aperture]\nbladez = [5, 7]\n",
            "line 4, column 1, field `aperture.bladez`: unknown field `bladez`",
        ),
        (
            "quality = \"best\"\n",
            "line 1, column 11, field `quality`: `best` is not a quality preset",
        ),
        (
            "[lenses]\n\nnames = [\"no-such-lens-xyz\"]\n",
            "line 3, column 1, field `lenses.names`: no lens file `no-such-lens-xyz`",
        ),
    ];
    for (text, expected) in cases {
        let config = write(tmp.path(), "sampler.toml", text);
        let o = flarebench(&[
            "dataset",
            "--count",
            "1",
            "--config",
            config.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("sampler.toml"), "{err}");
        assert!(err.contains(expected), "{err}");
    }
    assert!(!out.exists(), "nothing is written for a bad sampler");
}

#[test]
fn the_defaults_and_the_library_filters_choose_the_lenses() {
    let defaults = Sampler::with_defaults().unwrap();
    let core = flarebench::lens_library::core_names();
    let names: Vec<&str> = defaults.lenses().iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, core.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(defaults.lenses().iter().all(|l| l.weight == 1.0));
    let s = defaults.sample(0, 0).unwrap();
    assert_eq!(s.size, [512, 512]);
    assert!((1.4..=16.0).contains(&s.f_number));
    assert!((1..=3).contains(&s.lights.len()));

    // Core lenses of 90–110 mm: the two Heliars (100 mm), not the 50 mm double Gauss nor the
    // 10 mm fisheye.
    let text = "[lenses]\nfocal_mm = [90, 110]\n";
    let near_100 = Sampler::from_toml_str(text, "focal", Path::new(".")).unwrap();
    let names: Vec<&str> = near_100.lenses().iter().map(|l| l.name.as_str()).collect();
    assert!(names.contains(&"heliar-tronnier"), "{names:?}");
    assert!(!names.contains(&"double-gauss-50mm"), "{names:?}");
    assert!(!names.contains(&"fisheye-10mm"), "{names:?}");

    let err = Sampler::from_toml_str("[lenses]\nfocal_mm = [1, 2]\n", "none", Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no lens matches the filters"), "{err}");
    let err = Sampler::from_toml_str(
        "[lenses]\nnames = [\"heliar-tronnier\"]\nweights = { \"fisheye-10mm\" = 2 }\n",
        "weights",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("line 3, column 1, field `lenses.weights`: `fisheye-10mm` is not one of"),
        "{err}"
    );
}

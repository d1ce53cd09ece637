//! End-to-end tests of `flarebench render --frames A..B --light-path FILE`: numbered frames,
//! lights where their paths put them, keyframes met by both interpolations, shards equal to
//! the full run bit for bit, one exposure for PNG frames, bad path files refused; and `apply`
//! over a numbered image sequence: the same bytes as `apply` frame by frame with the
//! sequence's exposure and table, shards equal to the full run, a missing plate named.

use crate::common;

use std::path::Path;

use common::{flarebench, json, temp_dir};
use flarebench::output::{ToneMap, save_image};
use flarebench_sdk::image::HdrImage;
use serde_json::Value;

/// Where a keyframe's chief ray lands in a sequence against `render --light` of the same
/// direction (pixels): both aim the same f64 chief ray, so they agree to rounding.
const CHIEF_RAY_TOL_PX: f64 = 1e-9;
/// The sequence's automatic exposure against a single render of its brightest frame (stops):
/// the single render plans without a warm start, so its ghosts may differ in the last bits.
const EXPOSURE_TOL_EV: f32 = 0.01;

/// A light moving right (φ 90°) from 2° to 10° over frames 1..5.
const RIGHTWARD: &str = r#"
[[light]]
interpolation = "linear"
key = [
  { frame = 1, theta = 2, phi = 90 },
  { frame = 5, theta = 10, phi = 90 },
]
"#;

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

fn sequence(dir: &Path, path: &str, frames: &str, output: &str, extra: &[&str]) -> Value {
    let out = dir.join(output);
    let mut args = vec![
        "render",
        "heliar-tronnier",
        "--frames",
        frames,
        "--light-path",
        path,
        "--size",
        "160x90",
        "--quality",
        "fast",
        "--starburst-texels",
        "64",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    json(&args)
}

fn frame_files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("seq."))
        .collect();
    names.sort();
    names
}

#[test]
fn a_sequence_is_numbered_and_its_light_moves_as_the_path_says() {
    let tmp = temp_dir("sequence");
    let path = write(tmp.path(), "path.toml", RIGHTWARD);
    let v = sequence(tmp.path(), &path, "1..5", "seq.####.exr", &[]);
    assert_eq!(
        frame_files(tmp.path()),
        [
            "seq.0001.exr",
            "seq.0002.exr",
            "seq.0003.exr",
            "seq.0004.exr",
            "seq.0005.exr"
        ]
    );
    let frames = v["frames"].as_array().unwrap();
    let mut last_x = f64::NEG_INFINITY;
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"].as_u64().unwrap(), i as u64 + 1);
        let theta = f["lights"][0]["theta_deg"].as_f64().unwrap();
        assert_eq!(theta, 2.0 + 2.0 * i as f64, "linear from 2° to 10°");
        assert_eq!(f["lights"][0]["phi_deg"].as_f64().unwrap(), 90.0);
        // φ 90°: the light's image lies right of the centre, further for a larger θ.
        let [x, y] = [0, 1].map(|k| f["starbursts"][0]["position_px"][k].as_f64().unwrap());
        assert!(x > 80.0 && x > last_x, "frame {}: x {x}", i + 1);
        assert!((y - 45.0).abs() < 1.0, "frame {}: y {y}", i + 1);
        last_x = x;
        assert!(f["ghosts_drawn"].as_u64().unwrap() > 0);
    }
    // Frame 3 is the light at 6°, 90°: its chief ray lands where `render --light 6,90` puts it.
    let single = json(&[
        "render",
        "heliar-tronnier",
        "--light",
        "6,90",
        "--size",
        "160x90",
        "--quality",
        "fast",
        "--starburst-texels",
        "64",
        "-o",
        tmp.path().join("single.exr").to_str().unwrap(),
        "--json",
    ]);
    for k in 0..2 {
        let a = frames[2]["starbursts"][0]["position_px"][k]
            .as_f64()
            .unwrap();
        let b = single["starbursts"][0]["position_px"][k].as_f64().unwrap();
        assert!((a - b).abs() <= CHIEF_RAY_TOL_PX, "{a} against {b}");
    }
}

#[test]
fn linear_and_smooth_paths_meet_their_keyframes() {
    let tmp = temp_dir("sequence-keys");
    let keys = "key = [\n  { frame = 0, theta = 1, phi = 0, intensity = 1 },\n  \
                { frame = 2, theta = 9, phi = 40, intensity = 4 },\n  \
                { frame = 6, theta = 3, phi = 200, intensity = 2, },\n]\n";
    let mut thetas = Vec::new();
    for how in ["linear", "smooth"] {
        let path = write(
            tmp.path(),
            &format!("{how}.toml"),
            &format!("[[light]]\ninterpolation = \"{how}\"\n{keys}"),
        );
        let v = sequence(
            tmp.path(),
            &path,
            "0..6",
            &format!("{how}.####.exr"),
            &["--starburst", "only"],
        );
        let light = |f: usize, field: &str| v["frames"][f]["lights"][0][field].as_f64().unwrap();
        for (f, theta, phi, intensity) in [
            (0, 1.0, 0.0, 1.0),
            (2, 9.0, 40.0, 4.0),
            (6, 3.0, 200.0, 2.0),
        ] {
            assert_eq!(light(f, "theta_deg"), theta, "{how}, frame {f}");
            assert_eq!(light(f, "phi_deg"), phi, "{how}, frame {f}");
            assert_eq!(light(f, "intensity"), intensity, "{how}, frame {f}");
        }
        thetas.push((0..=6).map(|f| light(f, "theta_deg")).collect::<Vec<_>>());
    }
    // Linear: half way at frame 1; smooth: a flat top at the peak (θ at frame 1 above the
    // line's, as the curve's slope at frame 2 is 0), never past the keyframes.
    assert_eq!(thetas[0][1], 5.0);
    assert!(thetas[1][1] > 5.0 && thetas[1][1] < 9.0, "{:?}", thetas[1]);
    assert!(thetas[1].iter().all(|&t| (1.0..=9.0).contains(&t)));
}

#[test]
fn shards_together_equal_the_full_run_bit_for_bit() {
    let tmp = temp_dir("sequence-shards");
    let path = write(tmp.path(), "path.toml", RIGHTWARD);
    let run = |dir: &str, frames: &str, extra: &[&str]| {
        let d = tmp.path().join(dir);
        std::fs::create_dir_all(&d).unwrap();
        sequence(&d, &path, frames, "seq.####.exr", extra);
        d
    };
    let full = run("full", "1..5", &[]);
    let shards = run("shards", "1..5", &["--shard", "0/2"]);
    run("shards", "1..5", &["--shard", "1/2"]);
    let alone = run("alone", "4..4", &[]);
    assert_eq!(frame_files(&shards), frame_files(&full));
    for name in frame_files(&full) {
        let a = std::fs::read(full.join(&name)).unwrap();
        assert!(
            a == std::fs::read(shards.join(&name)).unwrap(),
            "{name}: a shard's frame differs from the full run's"
        );
    }
    assert_eq!(frame_files(&alone), ["seq.0004.exr"]);
    assert!(
        std::fs::read(alone.join("seq.0004.exr")).unwrap()
            == std::fs::read(full.join("seq.0004.exr")).unwrap(),
        "frame 4 rendered alone differs from frame 4 of the full run"
    );
}

#[test]
fn png_frames_share_one_exposure_from_the_brightest_frame() {
    let tmp = temp_dir("sequence-png");
    // The same direction, brighter frame by frame: with one exposure the frames brighten.
    let path = write(
        tmp.path(),
        "path.toml",
        "[[light]]\nkey = [\n  { frame = 1, theta = 8, phi = 60, intensity = 1 },\n  \
         { frame = 3, theta = 8, phi = 60, intensity = 4 },\n]\n",
    );
    let v = sequence(tmp.path(), &path, "1..3", "seq.####.png", &[]);
    assert_eq!(
        v["exposure_frame"].as_u64(),
        Some(3),
        "frame 3 is the brightest"
    );
    let ev = v["exposure_ev"].as_f64().unwrap() as f32;
    let single = json(&[
        "render",
        "heliar-tronnier",
        "--light",
        "8,60,4",
        "--size",
        "160x90",
        "--quality",
        "fast",
        "--starburst-texels",
        "64",
        "-o",
        tmp.path().join("single.png").to_str().unwrap(),
        "--json",
    ]);
    let single_ev = single["exposure_ev"].as_f64().unwrap() as f32;
    assert!(
        (ev - single_ev).abs() < EXPOSURE_TOL_EV,
        "{ev} against {single_ev}"
    );
    let mean = |n: u64| {
        let img = image::open(tmp.path().join(format!("seq.{n:04}.png")))
            .unwrap()
            .to_rgb8();
        img.pixels()
            .map(|p| p.0.iter().map(|&c| c as f64).sum::<f64>())
            .sum::<f64>()
    };
    let (m1, m2, m3) = (mean(1), mean(2), mean(3));
    assert!(m1 < m2 && m2 < m3, "frames do not brighten: {m1} {m2} {m3}");
}

#[test]
fn bad_path_files_and_patterns_are_refused_with_where_and_what() {
    let tmp = temp_dir("sequence-bad");
    let out = tmp.path().join("seq.####.exr");
    let out = out.to_str().unwrap();
    let run = |path: &str, output: &str| {
        let o = flarebench(&[
            "render",
            "heliar-tronnier",
            "--frames",
            "1..2",
            "--light-path",
            path,
            "--size",
            "32x18",
            "-o",
            output,
        ]);
        assert_eq!(o.status.code(), Some(1));
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!e.contains("panicked"), "{e}");
        e
    };
    let theta = write(
        tmp.path(),
        "theta.toml",
        "[[light]]\nkey = [\n  { frame = 1, theta = 4, phi = 0 },\n  { frame = 2, theta = 95, phi = 0 },\n]\n",
    );
    let e = run(&theta, out);
    assert!(
        e.contains("theta.toml:4:") && e.contains("`theta`") && e.contains("95"),
        "{e}"
    );
    let colour = write(
        tmp.path(),
        "colour.toml",
        "[[light]]\n[[light.key]]\nframe = 1\ntheta = 4\nphi = 0\ncolour = \"warm\"\n",
    );
    let e = run(&colour, out);
    assert!(
        e.contains("colour.toml:6:") && e.contains("`colour`"),
        "{e}"
    );
    let syntax = write(
        tmp.path(),
        "syntax.toml",
        "[[light]]\nkey = [{ frame = 1,, }]\n",
    );
    let e = run(&syntax, out);
    assert!(e.contains("syntax.toml:2:"), "{e}");
    let e = run(&colour.replace("colour", "missing"), out);
    assert!(e.contains("missing.toml"), "{e}");
    let fine = write(tmp.path(), "fine.toml", RIGHTWARD);
    let e = run(&fine, tmp.path().join("seq.exr").to_str().unwrap());
    assert!(e.contains("no frame number") && e.contains("####"), "{e}");
}

#[test]
fn a_precomputed_table_serves_every_frame() {
    let tmp = temp_dir("sequence-table");
    let table = tmp.path().join("bounds.json");
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
    let table = table.to_str().unwrap();
    let path = write(tmp.path(), "path.toml", RIGHTWARD);
    let full = tmp.path().join("full");
    let alone = tmp.path().join("alone");
    for d in [&full, &alone] {
        std::fs::create_dir_all(d).unwrap();
    }
    let v = sequence(
        &full,
        &path,
        "1..5",
        "seq.####.exr",
        &["--precomputed", table],
    );
    for f in v["frames"].as_array().unwrap() {
        assert!(f["ghosts_drawn"].as_u64().unwrap() > 0, "{f}");
    }
    sequence(
        &alone,
        &path,
        "3",
        "seq.####.exr",
        &["--precomputed", table],
    );
    assert!(
        std::fs::read(alone.join("seq.0003.exr")).unwrap()
            == std::fs::read(full.join("seq.0003.exr")).unwrap(),
        "frame 3 rendered alone differs from frame 3 of the full run"
    );
    // A light that leaves the table's angles is an error naming the frame.
    let far = write(
        tmp.path(),
        "far.toml",
        "[[light]]\nkey = [\n  { frame = 1, theta = 2, phi = 0 },\n  { frame = 2, theta = 20, phi = 0 },\n]\n",
    );
    let o = flarebench(&[
        "render",
        "heliar-tronnier",
        "--frames",
        "1..2",
        "--light-path",
        &far,
        "--size",
        "32x18",
        "--precomputed",
        table,
        "-o",
        tmp.path().join("far.####.exr").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("frame 2") && !e.contains("panicked"), "{e}");
}

/// Plates `plate.0001.exr` … of a 64×48 sequence in `dir`: a dim background and a 2×2 light
/// of 2000 per pixel moving 6 px right per frame.
fn plates(dir: &Path, frames: std::ops::RangeInclusive<u64>) {
    let (w, h) = (64, 48);
    for f in frames {
        let mut img = HdrImage::from_pixels(w, h, vec![[0.1, 0.12, 0.15]; w * h]).unwrap();
        let x = 20 + 6 * f as usize;
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            img.pixels[(18 + dy) * w + x + dx] = [2000.0, 1900.0, 1700.0];
        }
        save_image(
            &img,
            &dir.join(format!("plate.{f:04}.exr")),
            &ToneMap::default(),
        )
        .unwrap();
    }
}

/// `apply` over plates in `dir` with `extra` arguments, `--json`.
fn apply_frames(dir: &Path, frames: &str, output: &str, extra: &[&str]) -> Value {
    let plate = dir.join("plate.####.exr");
    let out = dir.join(output);
    let mut args = vec![
        "apply",
        plate.to_str().unwrap(),
        "--lens",
        "heliar-tronnier",
        "--frames",
        frames,
        "--quality",
        "fast",
        "--starburst-texels",
        "64",
        "--backend",
        "cpu",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    json(&args)
}

#[test]
fn apply_over_a_sequence_equals_apply_frame_by_frame_with_its_exposure() {
    let tmp = temp_dir("apply-seq");
    let dir = tmp.path();
    plates(dir, 1..=3);
    // One bounds table for both: paraxial bounds, quick to make.
    let table = dir.join("bounds.json");
    let o = flarebench(&[
        "precompute",
        "heliar-tronnier",
        "--mode",
        "approximate",
        "-o",
        table.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let t = table.to_str().unwrap();
    // PNG frames: one automatic exposure from the brightest plate.
    let v = apply_frames(dir, "1..3", "seq.####.png", &["--precomputed", t]);
    assert_eq!(v["frames"].as_array().unwrap().len(), 3, "{v}");
    assert!(
        v["frames"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f["lights"] == 1)
    );
    assert!(v["exposure_frame"].is_u64(), "{v}");
    let ev = v["exposure_ev"].as_f64().unwrap().to_string();
    for f in 1..=3 {
        let one = dir.join(format!("one.{f:04}.png"));
        let o = flarebench(&[
            "apply",
            dir.join(format!("plate.{f:04}.exr")).to_str().unwrap(),
            "--lens",
            "heliar-tronnier",
            "--quality",
            "fast",
            "--starburst-texels",
            "64",
            "--backend",
            "cpu",
            "--precomputed",
            t,
            "--exposure-ev",
            &ev,
            "-o",
            one.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let seq = std::fs::read(dir.join(format!("seq.{f:04}.png"))).unwrap();
        assert!(seq == std::fs::read(&one).unwrap(), "frame {f} differs");
    }
}

#[test]
fn apply_shards_together_equal_the_full_run_and_a_missing_plate_is_named() {
    let tmp = temp_dir("apply-shards");
    let dir = tmp.path();
    plates(dir, 1..=3);
    // EXR frames, the bounds table built by each run.
    let full = apply_frames(dir, "1..3", "full/f.####.exr", &[]);
    assert_eq!(full["table"], "built", "{full}");
    for i in 0..2 {
        apply_frames(
            dir,
            "1..3",
            "shard/f.####.exr",
            &["--shard", &format!("{i}/2")],
        );
    }
    for f in 1..=3 {
        let name = format!("f.{f:04}.exr");
        let a = std::fs::read(dir.join("full").join(&name)).unwrap();
        let b = std::fs::read(dir.join("shard").join(&name)).unwrap();
        assert!(a == b, "frame {f} differs");
    }

    let plate = dir.join("plate.####.exr");
    let out = dir.join("m.####.exr");
    let o = flarebench(&[
        "apply",
        plate.to_str().unwrap(),
        "--lens",
        "heliar-tronnier",
        "--frames",
        "2..4",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    let missing = dir.join("plate.0004.exr");
    assert!(
        err.contains(&format!("frame 4: no image `{}`", missing.display())),
        "{err}"
    );
    assert!(!dir.join("m.0002.exr").exists(), "nothing is written");
}

//! End-to-end tests of the starburst in `flarebench render`, `--background`, half-float EXR,
//! and `flarebench apply` on synthetic images with lights at known places.

use crate::common;

use std::path::Path;

use common::{flarebench, json, temp_dir};
use flarebench::output::{ToneMap, read_exr, save_image};
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::chief_ray_landing;
use flarebench_test_support::load_lens;

const LENS: &str = "double-gauss-50mm";

/// A starburst's position against where its light is, projected or found (pixels).
const POSITION_TOL_PX: f64 = 1e-3;

/// Energy a starburst carries against its light's flux: the pattern's own energy error (white
/// light's luminance sum is held to 1% in `sdk/tests/starburst.rs`).
const STARBURST_ENERGY_TOL: f64 = 0.01;

/// Luminance added to a background, summed from the f32 EXR, against the reported addition.
const ADDED_LUMINANCE_TOL: f64 = 1e-3;

/// Half floats keep 11 significant bits: relative error ≤ 2⁻¹¹ = 4.88e-4.
const HALF_FLOAT_REL_TOL: f32 = 4.9e-4;
/// Half floats' absolute error near zero: the subnormal spacing 2⁻²⁴ = 5.96e-8.
const HALF_FLOAT_ABS_TOL: f32 = 6e-8;

/// A painted light's direction recovered by `apply` (degrees): the splat puts its centroid on
/// the light up to f32 rounding.
const DIRECTION_TOL_DEG: f64 = 1e-3;

/// A painted light's energy recovered by `apply` (relative): f32 rounding of the splat.
const LIGHT_ENERGY_REL_TOL: f64 = 1e-5;

/// Share of the lights' energy the whole flare must add at least: the starbursts carry it to
/// `STARBURST_ENERGY_TOL`.
const FLARE_ENERGY_FLOOR: f64 = 0.99;

/// Centroid of a symmetric 3×3 clipped light against its middle pixel's centre: f64 rounding.
const CENTROID_TOL_PX: f64 = 1e-9;

fn lens() -> flarebench_sdk::LensSystem {
    load_lens(LENS)
}

fn frame(w: usize, h: usize) -> Frame {
    let sys = lens();
    Frame {
        width: w,
        height: h,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * h as f64 / w as f64,
    }
}

/// Where a light at (θ, φ) degrees images, in pixels.
fn light_pixel(f: &Frame, theta: f64, phi: f64) -> [f64; 2] {
    let [x, y] =
        chief_ray_landing(&lens(), 587.5618, theta.to_radians(), phi.to_radians()).unwrap();
    f.to_pixel(x, y).map(f64::from)
}

fn lum(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

#[test]
fn render_adds_the_starburst_at_the_chief_ray_with_the_lights_flux() {
    let tmp = temp_dir("starburst");
    let dir = tmp.path();
    let out = dir.join("sb.exr");
    let v = json(&[
        "render",
        LENS,
        "--light",
        "6,40,2",
        "--size",
        "320x180",
        "--starburst",
        "only",
        "--iris-blades",
        "6",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let sb = &v["starbursts"][0];
    assert!(sb["left_out"].is_null(), "{sb}");
    let pos: Vec<f64> = sb["position_px"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let want = light_pixel(&frame(320, 180), 6.0, 40.0);
    assert!(
        (pos[0] - want[0]).abs() < POSITION_TOL_PX && (pos[1] - want[1]).abs() < POSITION_TOL_PX
    );
    // Wholly in the frame: the image carries the light's flux (intensity 2 × the direct
    // image's flux), and nothing else (no ghosts).
    let flux = sb["flux"].as_f64().unwrap();
    let img = read_exr(&out).unwrap();
    assert!(
        (img.luminance_sum() / flux - 1.0).abs() < STARBURST_ENERGY_TOL,
        "{} vs {flux}",
        img.luminance_sum()
    );
    assert!((sb["added"].as_f64().unwrap() / flux - 1.0).abs() < STARBURST_ENERGY_TOL);
    assert!(v["lights"].as_array().unwrap().is_empty());
    // The brightest pixel holds the light's image.
    let (k, _) = img
        .pixels
        .iter()
        .enumerate()
        .max_by(|a, b| lum(*a.1).total_cmp(&lum(*b.1)))
        .unwrap();
    assert_eq!((k % 320, k / 320), (want[0] as usize, want[1] as usize));
    assert!(v["timings"]["starburst_ms"].as_f64().unwrap() > 0.0);

    // With the ghosts (the default) the image gains their energy on top; off leaves the
    // starburst out.
    let both = json(&[
        "render",
        LENS,
        "--light",
        "6,40,2",
        "--size",
        "320x180",
        "--quality",
        "fast",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let off = json(&[
        "render",
        LENS,
        "--light",
        "6,40,2",
        "--size",
        "320x180",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let g = |v: &serde_json::Value| v["image_sum_rgb"][1].as_f64().unwrap();
    assert!(off["starbursts"].as_array().unwrap().is_empty());
    let added = both["starbursts"][0]["added"].as_f64().unwrap();
    assert!(g(&both) > g(&off) + 0.9 * added);
}

#[test]
fn a_background_keeps_its_values_where_the_flare_is_zero() {
    let tmp = temp_dir("starburst-bg");
    let dir = tmp.path();
    let (w, h) = (160, 90);
    // A background with values no flare could produce, tiny, large, negative, exact.
    let pixels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let t = i as f32;
            [t * 1e-3 + 0.123_456_7, (t * 0.37).sin() * 3.0, -1e-20 * t]
        })
        .collect();
    let bg = HdrImage::from_pixels(w, h, pixels).unwrap();
    let bg_path = dir.join("bg.exr");
    save_image(&bg, &bg_path, &ToneMap::default()).unwrap();
    let out = dir.join("out.exr");
    let v = json(&[
        "render",
        LENS,
        "--light",
        "4,120,5",
        "--starburst",
        "only",
        "--background",
        bg_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(160), Some(90))
    );
    let img = read_exr(&out).unwrap();
    let (mut same, mut changed) = (0, 0);
    let mut added = 0.0;
    for (o, b) in img.pixels.iter().zip(&bg.pixels) {
        if o.map(f32::to_bits) == b.map(f32::to_bits) {
            same += 1;
        } else {
            changed += 1;
            added += lum(*o) - lum(*b);
        }
    }
    // The starburst covers a few pixels around the light; everything else is untouched.
    assert!(changed > 0 && changed < 400, "{changed} changed");
    assert!(same > w * h - 400);
    let flux = v["starbursts"][0]["added"].as_f64().unwrap();
    assert!(
        (added / flux - 1.0).abs() < ADDED_LUMINANCE_TOL,
        "{added} vs {flux}"
    );

    // A PNG background: written with exposure 0 and the clamp curve, so 8-bit values
    // survive decoding and re-encoding wherever the flare is zero.
    let png = dir.join("bg.png");
    let raw: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
    image::RgbImage::from_raw(w as u32, h as u32, raw.clone())
        .unwrap()
        .save(&png)
        .unwrap();
    let out_png = dir.join("out.png");
    let o = flarebench(&[
        "render",
        LENS,
        "--light",
        "4,120,5",
        "--starburst",
        "only",
        "--background",
        png.to_str().unwrap(),
        "-o",
        out_png.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let back = image::open(&out_png).unwrap().to_rgb8().into_raw();
    let differ = raw.iter().zip(&back).filter(|(a, b)| a != b).count();
    assert!(differ > 0 && differ < 3 * 400, "{differ} bytes differ");
    assert!(raw.iter().zip(&back).all(|(a, b)| b >= a));
    // A size that is not the background's is refused.
    let o = flarebench(&[
        "render",
        LENS,
        "--light",
        "4,0",
        "--size",
        "100x100",
        "--background",
        bg_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("differs from the background"));
}

#[test]
fn half_float_exr_is_the_float_image_rounded() {
    let tmp = temp_dir("starburst-half");
    let dir = tmp.path();
    let (f, h) = (dir.join("f.exr"), dir.join("h.exr"));
    for (path, extra) in [(&f, None), (&h, Some("--exr-half"))] {
        let mut a = vec![
            "render",
            LENS,
            "--light",
            "3,0",
            "--size",
            "96x54",
            "--starburst",
            "only",
            "-q",
            "-o",
            path.to_str().unwrap(),
        ];
        a.extend(extra);
        assert!(flarebench(&a).status.success());
    }
    let (a, b) = (read_exr(&f).unwrap(), read_exr(&h).unwrap());
    for (x, y) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            // Half floats keep 11 significant bits: relative error ≤ 2⁻¹¹ (subnormals aside).
            assert!(
                (x[c] - y[c]).abs() <= x[c].abs() * HALF_FLOAT_REL_TOL + HALF_FLOAT_ABS_TOL,
                "{x:?} {y:?}"
            );
        }
    }
}

/// Paints a light of `energy` whose luminance-weighted centroid is exactly `p` (pixels): a
/// bilinear splat over the four pixels around it, replacing their values.
fn paint_light(img: &mut HdrImage, p: [f64; 2], energy: f32) {
    let (fx, fy) = (p[0] - 0.5, p[1] - 0.5);
    let (i0, j0) = (fx.floor() as usize, fy.floor() as usize);
    let (tx, ty) = ((fx - i0 as f64) as f32, (fy - j0 as f64) as f32);
    for (di, dj, wgt) in [
        (0, 0, (1.0 - tx) * (1.0 - ty)),
        (1, 0, tx * (1.0 - ty)),
        (0, 1, (1.0 - tx) * ty),
        (1, 1, tx * ty),
    ] {
        img.pixels[(j0 + dj) * img.width + i0 + di] = [energy * wgt; 3];
    }
}

#[test]
fn apply_finds_synthetic_lights_and_recovers_their_directions() {
    let tmp = temp_dir("apply");
    let dir = tmp.path();
    let (w, h) = (320, 180);
    let f = frame(w, h);
    let known = [
        (6.0, 30.0, 4000.0f32),
        (9.0, 210.0, 1500.0),
        (2.5, 95.0, 800.0),
    ];
    // A dim gradient background (below the threshold of 1) and three lights.
    let pixels = (0..w * h)
        .map(|i| [0.05 + 0.3 * (i % w) as f32 / w as f32, 0.1, 0.2])
        .collect();
    let mut img = HdrImage::from_pixels(w, h, pixels).unwrap();
    for &(t, p, e) in &known {
        paint_light(&mut img, light_pixel(&f, t, p), e);
    }
    let input = dir.join("scene.exr");
    save_image(&img, &input, &ToneMap::default()).unwrap();
    let out = dir.join("flared.exr");
    let v = json(&[
        "apply",
        input.to_str().unwrap(),
        "--lens",
        LENS,
        "-o",
        out.to_str().unwrap(),
        "--quality",
        "fast",
        "--json",
    ]);
    let lights = v["lights"].as_array().unwrap();
    assert_eq!(lights.len(), 3, "{v}");
    // Brightest first: the order painted.
    for (l, &(t, p, e)) in lights.iter().zip(&known) {
        let theta = l["theta_deg"].as_f64().unwrap();
        let phi = l["phi_deg"].as_f64().unwrap();
        assert!((theta - t).abs() < DIRECTION_TOL_DEG, "θ {theta} vs {t}");
        let dphi = (phi - p).rem_euclid(360.0);
        assert!(dphi.min(360.0 - dphi) < DIRECTION_TOL_DEG, "φ {phi} vs {p}");
        let energy = l["energy"].as_f64().unwrap();
        assert!(
            (energy / f64::from(e) - 1.0).abs() < LIGHT_ENERGY_REL_TOL,
            "{energy} vs {e}"
        );
    }
    // The starbursts carry the sources' energy (gain 1) and sit on them.
    for (sb, l) in v["starbursts"].as_array().unwrap().iter().zip(lights) {
        let added = sb["added"].as_f64().unwrap() + sb["outside"].as_f64().unwrap();
        let energy = l["energy"].as_f64().unwrap();
        assert!(
            (added / energy - 1.0).abs() < STARBURST_ENERGY_TOL,
            "{added} vs {energy}"
        );
        for k in 0..2 {
            let a = sb["position_px"][k].as_f64().unwrap();
            let b = l["centroid_px"][k].as_f64().unwrap();
            assert!((a - b).abs() < POSITION_TOL_PX, "{a} vs {b}");
        }
    }
    assert!(v["ghosts_traced"].as_u64().unwrap() > 0);
    // The output is the input plus a non-negative flare; the flare's energy is at least the
    // starbursts'.
    let res = read_exr(&out).unwrap();
    let mut added = 0.0;
    for (o, i) in res.pixels.iter().zip(&img.pixels) {
        for c in 0..3 {
            assert!(o[c] >= i[c], "{o:?} < {i:?}");
        }
        added += lum(*o) - lum(*i);
    }
    let total: f64 = known.iter().map(|k| f64::from(k.2)).sum();
    assert!(added > FLARE_ENERGY_FLOOR * total, "{added} vs {total}");
}

#[test]
fn apply_on_a_clipped_png_and_with_nothing_bright() {
    let tmp = temp_dir("apply-png");
    let dir = tmp.path();
    let (w, h) = (200, 120);
    let f = frame(w, h);
    let p = light_pixel(&f, 5.0, 300.0);
    let mut raw = vec![40u8; w * h * 3];
    // A clipped 3×3 light centred on pixel (round(p)).
    let (ci, cj) = (p[0] as usize, p[1] as usize);
    for j in cj - 1..=cj + 1 {
        for i in ci - 1..=ci + 1 {
            raw[(j * w + i) * 3..][..3].copy_from_slice(&[255, 255, 255]);
        }
    }
    let input = dir.join("clipped.png");
    image::RgbImage::from_raw(w as u32, h as u32, raw.clone())
        .unwrap()
        .save(&input)
        .unwrap();
    let out = dir.join("out.png");
    let v = json(&[
        "apply",
        input.to_str().unwrap(),
        "--lens",
        LENS,
        "-o",
        out.to_str().unwrap(),
        "--starburst",
        "only",
        "--gain",
        "50",
        "--json",
    ]);
    let l = &v["lights"][0];
    assert_eq!(v["lights"].as_array().unwrap().len(), 1);
    assert_eq!(l["pixels"].as_u64(), Some(9));
    assert_eq!(v["hdr"].as_bool(), Some(false));
    // The centroid is the middle of pixel (ci, cj).
    assert!((l["centroid_px"][0].as_f64().unwrap() - (ci as f64 + 0.5)).abs() < CENTROID_TOL_PX);
    // Energy: 9 clipped pixels of linear 1 × gain 50. At f/2 the pattern reaches about one
    // pixel (256 texels × 0.78 µm × 2 / 2 = 0.2 mm, pixels of 0.18 mm), so it lands on the
    // already clipped light: the 8-bit output can only stay or grow.
    let sb = &v["starbursts"][0];
    let added = sb["added"].as_f64().unwrap() + sb["outside"].as_f64().unwrap();
    assert!(
        (added / 450.0 - 1.0).abs() < STARBURST_ENERGY_TOL,
        "{added}"
    );
    let back = image::open(&out).unwrap().to_rgb8().into_raw();
    assert!(back.iter().zip(&raw).all(|(b, a)| b >= a));

    // Nothing above the threshold: the image comes back unchanged.
    let dark = dir.join("dark.png");
    image::RgbImage::from_raw(w as u32, h as u32, vec![40u8; w * h * 3])
        .unwrap()
        .save(&dark)
        .unwrap();
    let v = json(&[
        "apply",
        dark.to_str().unwrap(),
        "--lens",
        LENS,
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(v["lights"].as_array().unwrap().is_empty());
    assert_eq!(
        image::open(&out).unwrap().to_rgb8().into_raw(),
        vec![40u8; w * h * 3]
    );
    // Bad input is an error, not a panic.
    for bad in [
        vec!["apply", "/nonexistent.exr", "--lens", LENS, "-o", "x.exr"],
        vec![
            "apply",
            dark.to_str().unwrap(),
            "--lens",
            LENS,
            "-o",
            "x.jpg",
        ],
        vec![
            "apply",
            dark.to_str().unwrap(),
            "--lens",
            LENS,
            "-o",
            "x.exr",
            "--gain",
            "-1",
        ],
    ] {
        let o = flarebench(&bad);
        assert!(!o.status.success());
        assert!(String::from_utf8_lossy(&o.stderr).starts_with("error:"));
    }
}

/// A clipped disc of radius 4 px at 255 on a background of 20 in a 960 × 540 PNG, at `centre`.
fn clipped_photo(path: &Path, centre: [f64; 2]) -> Vec<u8> {
    let (w, h) = (960usize, 540usize);
    let mut raw = vec![20u8; w * h * 3];
    for j in 0..h {
        for i in 0..w {
            let (dx, dy) = (i as f64 + 0.5 - centre[0], j as f64 + 0.5 - centre[1]);
            if dx.hypot(dy) <= 4.0 {
                raw[(j * w + i) * 3..][..3].copy_from_slice(&[255, 255, 255]);
            }
        }
    }
    image::RgbImage::from_raw(w as u32, h as u32, raw.clone())
        .unwrap()
        .save(path)
        .unwrap();
    raw
}

/// Share of the pixels more than `radius` px from `centre` whose 8-bit value differs.
fn changed_beyond(a: &[u8], b: &[u8], w: usize, centre: [f64; 2], radius: f64) -> f64 {
    let (mut far, mut changed) = (0usize, 0usize);
    for (k, (pa, pb)) in a.chunks(3).zip(b.chunks(3)).enumerate() {
        let (i, j) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        if (i - centre[0]).hypot(j - centre[1]) > radius {
            far += 1;
            changed += usize::from(pa != pb);
        }
    }
    changed as f64 / far as f64
}

/// The first-user case: an 8-bit photo with one clipped light gets a visible flare by
/// default (its clipped source taken as 10 stops brighter than its pixels), the gain is
/// reported, and a gain too small to show anything is warned about.
#[test]
fn apply_makes_a_visible_flare_on_a_clipped_8_bit_photo() {
    let tmp = temp_dir("apply-photo");
    let dir = tmp.path();
    let centre = [600.5, 200.5];
    let input = dir.join("photo.png");
    let raw = clipped_photo(&input, centre);
    let out = dir.join("flared.png");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "apply",
            input.to_str().unwrap(),
            "--lens",
            "heliar-tronnier",
            "-o",
            out.to_str().unwrap(),
            "--quality",
            "fast",
        ];
        a.extend_from_slice(extra);
        flarebench(&a)
    };
    let o = run(&["--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["lights"][0]["gain"].as_f64(), Some(1024.0));
    let flared = image::open(&out).unwrap().to_rgb8().into_raw();
    let share = changed_beyond(&raw, &flared, 960, centre, 12.0);
    assert!(share > 0.01, "{:.4}% of the pixels changed", 100.0 * share);
    assert!(v["changed_pixels"].as_u64().unwrap() > 5000, "{v}");
    // The text report names the gain; a gain of 1 leaves the flare invisible and says so.
    let o = run(&[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("× gain 1024"), "{err}");
    assert!(!err.contains("warning"), "{err}");
    let o = run(&["--gain", "1"]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning: the flare changes no pixel more than 12 px"),
        "{err}"
    );
}

//! `--backend gpu` end to end, on whatever adapter the machine has (Mesa lavapipe in CI, with
//! `WGPU_BACKEND=vulkan`): the image equals the CPU backend's, the report names the adapter
//! and its pass times, and without an adapter `gpu` fails saying what to install while `auto`
//! renders on the CPU.

use crate::common;

use common::{flarebench, json, temp_dir};
use flarebench::output::read_exr;

/// Relative RMSE and energy of the GPU image against the CPU image (the bounds).
const MAX_RMSE: f64 = 0.005;
const MAX_ENERGY: f64 = 0.001;
/// 8-bit channels the GPU's tone pass may put more than one level away from the PNG
/// writer's (the linear images differ within `MAX_RMSE`; the sRGB curve is steep near black).
const MAX_FAR_CHANNELS: f64 = 0.002;

fn render(backend: &str, out: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "render",
        "heliar-tronnier",
        "--light",
        "8,60",
        "--light",
        "3,200,0.5,3200",
        "--size",
        "240x135",
        "--starburst-texels",
        "128",
        "--backend",
        backend,
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    json(&args)
}

#[test]
fn the_gpu_renders_the_cpu_image_and_reports_its_adapter() {
    let tmp = temp_dir("gpu");
    for extra in [
        &[][..],
        // Every band on its own, through a six-bladed iris, with the sensor stack's ghosts
        // (the 3° light's reach the sensor), drawn by both.
        &[
            "--band-by-band",
            "--iris-blades",
            "6",
            "--sensor-stack",
            "digital",
        ][..],
    ] {
        let (cpu_path, gpu_path) = (tmp.path().join("cpu.exr"), tmp.path().join("gpu.exr"));
        let cpu_report = render("cpu", &cpu_path, extra);
        let report = render("gpu", &gpu_path, extra);
        assert_eq!(cpu_report["backend"]["backend"], "cpu");
        let b = &report["backend"];
        assert_eq!(b["backend"], "gpu", "{b}");
        assert!(!b["adapter"].as_str().unwrap().is_empty());
        assert!(b["triangles"].as_array().is_some());
        assert!(b["bytes_uploaded"].as_u64().unwrap() > 0);
        let (cpu, gpu) = (read_exr(&cpu_path).unwrap(), read_exr(&gpu_path).unwrap());
        assert!(!gpu.has_non_finite());
        let c = gpu.compare(&cpu).unwrap();
        eprintln!(
            "{extra:?}: rmse {:.2e}, energy {:.2e}",
            c.relative_rmse, c.energy_error
        );
        assert!(
            c.relative_rmse <= MAX_RMSE,
            "{extra:?}: rmse {}",
            c.relative_rmse
        );
        assert!(
            c.energy_error.abs() <= MAX_ENERGY,
            "{extra:?}: energy {}",
            c.energy_error
        );
        // Both lights' starbursts are drawn, and reported alike.
        for k in 0..2 {
            let (a, b) = (&report["starbursts"][k], &cpu_report["starbursts"][k]);
            assert!(a["left_out"].is_null());
            let (x, y) = (a["added"].as_f64().unwrap(), b["added"].as_f64().unwrap());
            assert!((x / y - 1.0).abs() < 1e-9, "starburst {k}: {x} against {y}");
        }
    }
}

#[test]
fn the_gpu_tone_pass_maps_as_the_png_writer() {
    let tmp = temp_dir("gpu-png");
    let (cpu_path, gpu_path) = (tmp.path().join("cpu.png"), tmp.path().join("gpu.png"));
    // The automatic exposure of the CPU image, given to both (it is taken from each
    // backend's own ghosts, which differ within `MAX_RMSE`).
    let ev = render("cpu", &cpu_path, &[])["exposure_ev"]
        .as_f64()
        .unwrap()
        .to_string();
    for tone in ["aces", "clamp"] {
        let extra = ["--exposure-ev", ev.as_str(), "--tone", tone];
        render("cpu", &cpu_path, &extra);
        render("gpu", &gpu_path, &extra);
        let cpu = image::open(&cpu_path).unwrap().to_rgb8();
        let gpu = image::open(&gpu_path).unwrap().to_rgb8();
        assert_eq!(cpu.dimensions(), gpu.dimensions());
        let far = cpu
            .as_raw()
            .iter()
            .zip(gpu.as_raw())
            .filter(|(a, b)| a.abs_diff(**b) > 1)
            .count();
        let lit = cpu.as_raw().iter().filter(|&&v| v > 0).count();
        assert!(lit > cpu.as_raw().len() / 10, "{tone}: {lit} channels lit");
        let share = far as f64 / cpu.as_raw().len() as f64;
        eprintln!("{tone}: {far} channels more than one level apart ({share:.2e})");
        assert!(share <= MAX_FAR_CHANNELS, "{tone}: {share}");
    }
}

#[test]
fn without_an_adapter_gpu_says_what_to_install_and_auto_uses_the_cpu() {
    let tmp = temp_dir("gpu-none");
    let out = tmp.path().join("x.exr");
    let out = out.to_str().unwrap();
    let args = [
        "render",
        "heliar-tronnier",
        "--light",
        "8,60",
        "--size",
        "96x54",
        "-o",
        out,
    ];
    // No Metal on Linux, no Vulkan on macOS: with the other one asked for, no adapter.
    let other = if cfg!(target_os = "macos") {
        "vulkan"
    } else {
        "metal"
    };
    let run = |backend: &str, json: bool| {
        let mut a = args.to_vec();
        a.extend(["--backend", backend]);
        if json {
            a.push("--json");
        }
        common::command()
            .args(&a)
            .env("WGPU_BACKEND", other)
            .output()
            .unwrap()
    };
    let gpu = run("gpu", false);
    assert!(!gpu.status.success());
    let err = String::from_utf8_lossy(&gpu.stderr);
    assert!(
        err.contains("no GPU adapter found") && err.contains("mesa-vulkan-drivers"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let auto = run("auto", true);
    assert!(
        auto.status.success(),
        "{}",
        String::from_utf8_lossy(&auto.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&auto.stdout).unwrap();
    assert_eq!(v["backend"]["backend"], "cpu");
    assert!(v["backend"]["note"].as_str().unwrap().starts_with("auto:"));
    // The CPU path is the default's when asked for.
    assert!(
        flarebench(&[&args[..], &["--backend", "cpu"]].concat())
            .status
            .success()
    );
}

/// `auto` looks for a hardware GPU without a word on standard error, also where the window
/// systems cannot be reached: with `XDG_RUNTIME_DIR` unset, a Vulkan instance with the window
/// system's surface extensions makes Mesa's device-selection layer try the Wayland compositor,
/// and libwayland prints an error line for each try.
#[test]
fn auto_finds_its_backend_silently_without_a_runtime_directory() {
    let tmp = temp_dir("gpu-auto-quiet");
    let out = tmp.path().join("x.exr");
    let run = |quiet: &str| {
        common::command()
            .args([
                "render",
                "heliar-tronnier",
                "--light",
                "8,60",
                "--size",
                "96x54",
            ])
            .args(["--backend", "auto", quiet, "-o", out.to_str().unwrap()])
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .unwrap()
    };
    let quiet = run("-q");
    let err = String::from_utf8_lossy(&quiet.stderr);
    assert!(quiet.status.success(), "{err}");
    assert_eq!(
        err, "",
        "`render -q --backend auto` wrote to standard error"
    );
    let report = run("--json");
    let err = String::from_utf8_lossy(&report.stderr);
    assert!(report.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&report.stdout).unwrap();
    let b = &v["backend"];
    match b["backend"].as_str().unwrap() {
        // A hardware GPU found: `auto` never takes a software one.
        "gpu" => assert!(b.get("software_adapter").is_none(), "{b}"),
        // None: the report says why, naming the software adapter if there is one.
        "cpu" => assert!(b["note"].as_str().unwrap().starts_with("auto: "), "{b}"),
        other => panic!("backend {other}"),
    }
}

/// `apply --backend gpu` adds the flare the CPU adds.
#[test]
fn apply_on_the_gpu_matches_the_cpu() {
    use flarebench::output::{ToneMap, save_image};
    use flarebench_sdk::image::HdrImage;
    let tmp = temp_dir("gpu-apply");
    let scene = tmp.path().join("scene.exr");
    let mut img = HdrImage::new(320, 180);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let (x, y) = ((i % 320) as f64, (i / 320) as f64);
        let d = (x - 230.5).hypot(y - 60.5);
        *p = if d < 3.0 { [2000.0; 3] } else { [0.01; 3] };
    }
    save_image(&img, &scene, &ToneMap::default()).unwrap();
    let mut out = Vec::new();
    for backend in ["cpu", "gpu"] {
        let path = tmp.path().join(format!("{backend}.exr"));
        let v = json(&[
            "apply",
            scene.to_str().unwrap(),
            "--lens",
            "heliar-tronnier",
            "--starburst-texels",
            "128",
            "--backend",
            backend,
            "-o",
            path.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(v["backend"]["backend"], backend);
        assert!(v["ghosts_traced"].as_u64().unwrap() > 0);
        out.push(read_exr(&path).unwrap());
    }
    let c = out[1].compare(&out[0]).unwrap();
    eprintln!(
        "apply: rmse {:.2e}, energy {:.2e}",
        c.relative_rmse, c.energy_error
    );
    assert!(
        c.relative_rmse <= MAX_RMSE && c.energy_error.abs() <= MAX_ENERGY,
        "{c:?}"
    );
}

/// `bench --backend cpu,gpu --aperture circle,iris,mask --starburst`: a row per backend and
/// aperture, the GPU's with its adapter and pass times, the starburst timed (its pattern kept
/// from run to run), the same ghosts planned on both backends.
#[test]
fn bench_times_both_backends_and_every_aperture() {
    let rows = json(&[
        "bench",
        "heliar-tronnier",
        "--light",
        "8,60",
        "--size",
        "128x72",
        "--quality",
        "fast",
        "--runs",
        "2",
        "--backend",
        "cpu,gpu",
        "--aperture",
        "circle,iris,mask",
        "--starburst",
        "--json",
    ]);
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 6);
    for r in rows {
        let b = &r["backend"];
        let gpu = b["backend"] == "gpu";
        assert_eq!(r["gpu_ms"].is_f64(), gpu, "{r}");
        assert_eq!(b["adapter"].is_string(), gpu, "{r}");
        assert!(r["starburst_ms"].as_f64().unwrap() >= 0.0);
        assert!(r["ghosts_drawn"].as_u64().unwrap() > 0);
    }
    let apertures: Vec<&str> = rows
        .iter()
        .map(|r| r["aperture"].as_str().unwrap())
        .collect();
    assert_eq!(
        apertures,
        ["circle", "circle", "iris", "iris", "mask", "mask"]
    );
}

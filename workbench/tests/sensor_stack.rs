//! `--sensor-stack` (docs/physics.md §9, docs/cli.md): the `digital` preset on a bundled lens
//! against the Monte-Carlo reference, images unchanged bit for bit without a stack, the
//! preset written to a file and read back, and located errors for a bad stack.

use crate::common;

use common::{flarebench, json, temp_dir};
use flarebench::sensor_stack::{SensorStackArgs, SensorStackPreset, digital};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::monte_carlo::McSettings;
use flarebench_test_support::load_lens;
use ghost_raytrace::crosscheck::{Allot, CrosscheckOptions, crosscheck};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Standard errors a figure may lie from the Monte-Carlo estimate: a 4σ miss has odds of
/// 6e-5 for a normal estimate.
const SIGMAS: f64 = 4.0;

/// How far the stack's ghosts' energies may be from the Monte-Carlo's beyond its error bar:
/// the 0.5%. Measured (2026-12-07, the settings below): shares within 0.13%, the
/// mesh reference's energies within 0.6% of 1σ ≈ 0.25% estimates.
const STACK_ENERGY_TOLERANCE: f64 = 5e-3;

fn heliar_digital() -> flarebench_sdk::LensSystem {
    let args = SensorStackArgs {
        sensor_stack: Some(SensorStackPreset::Digital),
    };
    args.apply(load_lens("heliar-tronnier"))
        .expect("the preset fits behind the Heliar")
}

#[test]
fn the_digital_preset_is_an_ir_cut_filter_a_cover_glass_and_a_sensor_of_a_few_percent() {
    let bare = load_lens("heliar-tronnier");
    let s = digital(&bare);
    assert_eq!(s.plates.len(), 2);
    assert_eq!(s.plates[0].thickness, 1.5);
    assert_eq!(s.plates[1].thickness, 0.5);
    assert_eq!(s.plates[0].medium.label(), "SCHOTT:N-BK7");
    // The plates cover the frame's corners (the Heliar's file gives its sensor 18 mm, less
    // than the 36 × 24 mm film's half diagonal).
    let corner = 0.5 * bare.film_width_mm.hypot(bare.film_height_mm);
    assert!(bare.surfaces.last().unwrap().semi_diameter < corner);
    assert!(s.plates.iter().all(|p| p.semi_diameter >= corner));
    for nm in [400.0, 500.0, 550.0, 600.0, 700.0] {
        let r = s.sensor_reflectance.at(nm);
        assert!((0.04..=0.07).contains(&r), "{nm} nm: {r}");
    }
    let with = heliar_digital();
    assert_eq!(with.surfaces.len(), bare.surfaces.len() + 4);
    // `none` takes it away again, exactly.
    let none = SensorStackArgs {
        sensor_stack: Some(SensorStackPreset::None),
    };
    assert_eq!(none.apply(with).unwrap(), bare);
}

/// The Monte-Carlo settings and the error bars the estimates must reach.
struct McCheck {
    rays: usize,
    batches: usize,
    /// Largest relative standard error of a ghost's share of the direct light.
    share_error: f64,
    /// Largest relative standard error of a ghost's image energy.
    energy_error: f64,
}

/// Checks the stack's ghosts `ghosts` on the Heliar with `digital` at 3° (at 8° the light the
/// sensor and the plates send back misses the rear element: the exit pupil lies 92 mm in front
/// of the sensor): their energy shares as the plan bounds them and their images' energies as
/// the mesh reference draws them, against the independent Monte-Carlo tracer, within
/// `SIGMAS` of its standard error plus `STACK_ENERGY_TOLERANCE`.
fn check_stack_ghosts_against_monte_carlo(ghosts: &[&str], mc: &McCheck) -> Vec<(String, f64)> {
    let sys = heliar_digital();
    let frame = Frame::across_film(64, 36, sys.film_width_mm);
    let light = LightSpec::parse("3,60").expect("a light");
    let opts = CrosscheckOptions {
        mc: McSettings {
            rays: mc.rays,
            batches: mc.batches,
            seed: 7,
            pilot: 129,
            outside_weight: 1.0,
        },
        quality: Quality::Default,
        reference: true,
        ghosts: ghosts
            .iter()
            .map(|s| s.parse().expect("a ghost name"))
            .collect(),
        allot: Allot::Even,
    };
    let c = crosscheck(&sys, &Aperture::Circular, frame, &light, &opts).expect("a crosscheck");
    assert_eq!(c.ghosts.len(), ghosts.len());
    for g in &c.ghosts {
        let s = g.mc_share;
        let b = g.bounds_share.expect("each has light");
        assert!(
            s.mean > 0.0 && s.relative_error() < mc.share_error,
            "{}: {s:?}",
            g.path
        );
        assert!(
            (b - s.mean).abs() <= SIGMAS * s.std_error + STACK_ENERGY_TOLERANCE * s.mean,
            "{}: bounds share {b:e} against Monte-Carlo {s:?}",
            g.path
        );
        let e = g.mc_energy;
        let r = g.reference.expect("the mesh reference drew it");
        assert!(e.relative_error() < mc.energy_error, "{}: {e:?}", g.path);
        assert!(
            (r.energy - e.mean).abs() <= SIGMAS * e.std_error + STACK_ENERGY_TOLERANCE * e.mean,
            "{}: mesh reference {} against Monte-Carlo {e:?}",
            g.path,
            r.energy
        );
    }
    c.ghosts
        .iter()
        .map(|g| (g.path.clone(), g.mc_share.mean))
        .collect()
}

/// Every kind of the stack's ghosts — sensor ↔ lens (13-6), sensor ↔ plate (13-9, 13-12),
/// plate ↔ plate (12-11, 11-9, 10-9) — and the lens's brightest (3-1) beside them, with
/// error bars of 0.5% and 1%.
#[test]
#[ignore = "slow tier: seven ghosts' Monte-Carlo estimates to 0.5%, about a minute; by default \
            two of them to 2%"]
fn the_stack_s_ghosts_agree_with_the_monte_carlo_reference_on_the_heliar() {
    let shares = check_stack_ghosts_against_monte_carlo(
        &["13-6", "13-9", "13-12", "12-11", "11-9", "10-9", "3-1"],
        &McCheck {
            rays: 100_000,
            batches: 16,
            share_error: 5e-3,
            energy_error: 1e-2,
        },
    );
    // The sensor ↔ cover glass ghost 13-12 carries more light than the brightest of the
    // Heliar's own at this angle, 3-1 (5.1e-4 and 4.6e-4 of the direct light).
    let share = |p: &str| shares.iter().find(|(g, _)| g == p).unwrap().1;
    assert!(share("13-12") > share("3-1"), "{}", share("13-12"));
}

/// The sensor ↔ lens ghost and the sensor ↔ cover glass one, on a sixteenth of the rays.
#[test]
fn the_sensor_s_ghosts_agree_with_a_short_monte_carlo_run_on_the_heliar() {
    check_stack_ghosts_against_monte_carlo(
        &["13-6", "13-12"],
        &McCheck {
            rays: 25_000,
            batches: 4,
            share_error: 2e-2,
            energy_error: 4e-2,
        },
    );
}

fn render_args<'a>(lens: &'a str, out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "render",
        lens,
        "--light",
        "3,60",
        "--size",
        "160x90",
        "--quality",
        "fast",
        "--starburst",
        "off",
        "--backend",
        "cpu",
        "-q",
        "-o",
        out,
    ];
    v.extend_from_slice(extra);
    v
}

fn render_bytes(lens: &str, extra: &[&str], dir: &std::path::Path, name: &str) -> Vec<u8> {
    let out = dir.join(name);
    let out_s = out.to_str().unwrap();
    let run = flarebench(&render_args(lens, out_s, extra));
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::read(&out).unwrap()
}

/// The Heliar with the `digital` stack, written by `convert --sensor-stack digital` into `dir`.
fn heliar_with_digital_stack(dir: &std::path::Path) -> std::path::PathBuf {
    let file = dir.join("heliar-digital.xml");
    let run = flarebench(&[
        "convert",
        "heliar-tronnier",
        "--sensor-stack",
        "digital",
        "-o",
        file.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    file
}

/// A file with the `digital` stack (written by `convert --sensor-stack digital`) renders
/// bit for bit as the bare lens with `--sensor-stack digital`, and with `--sensor-stack none`
/// bit for bit as the lens without a stack; the stack changes the image.
#[test]
fn a_stack_renders_the_same_from_the_file_or_the_option_and_none_restores_the_bare_image() {
    let tmp = temp_dir("sensor-stack");
    let file = heliar_with_digital_stack(tmp.path());
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("<sensorStack>") && text.contains("SCHOTT:N-BK7"));
    let f = file.to_str().unwrap();

    let bare = render_bytes("heliar-tronnier", &[], tmp.path(), "bare.exr");
    let removed = render_bytes(f, &["--sensor-stack", "none"], tmp.path(), "none.exr");
    assert!(bare == removed, "--sensor-stack none changed the image");
    let from_file = render_bytes(f, &[], tmp.path(), "file.exr");
    let from_option = render_bytes(
        "heliar-tronnier",
        &["--sensor-stack", "digital"],
        tmp.path(),
        "option.exr",
    );
    assert!(from_file == from_option, "the file and the option differ");
    assert!(from_file != bare, "the stack left the image as it was");

    // 13 reflecting surfaces (8 of the lens, 4 plate faces, the sensor): 78 ghosts.
    let out = tmp.path().join("r.exr");
    let mut args = render_args("heliar-tronnier", out.to_str().unwrap(), &[]);
    args.extend(["--sensor-stack", "digital", "--json"]);
    let v = json(&args);
    let light = &v["lights"][0];
    let all = light["ghosts_traced"].as_u64().unwrap() + light["ghosts_dropped"].as_u64().unwrap();
    assert_eq!(all, 78);
}

#[test]
fn a_bad_stack_in_a_file_is_an_error_naming_the_file_line_and_field() {
    let tmp = temp_dir("sensor-stack-bad");
    let file = heliar_with_digital_stack(tmp.path());
    let text = std::fs::read_to_string(&file).unwrap();
    let bad = text.replacen("<gap>0.5</gap>", "<gap>-0.5</gap>", 1);
    std::fs::write(&file, &bad).unwrap();
    let line = bad.lines().position(|l| l.contains("<gap>-0.5")).unwrap() + 1;
    let run = flarebench(&["info", file.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains(&format!("heliar-digital.xml:{line}:")) && err.contains("field `gap`"),
        "{err}"
    );
    assert!(err.contains("plate 1: must be ≥ 0 mm, got -0.5"), "{err}");
}

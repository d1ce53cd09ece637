//! The plugin author's loop end to end: `plugins new` writes a crate that cargo builds and the
//! workbench loads, drawing what the guide's example draws; `compare --watch` reloads it when it
//! is rebuilt with another default, keeps the previous one when the library is broken, and
//! compares again when the lens file changes; the viewer window (`view --algo`) reloads a
//! rebuilt plugin and renders with its new default.
//!
//! The tests that build crates with cargo are in the slow tier (`docs/tests.md`): on a clean
//! clone their first build takes minutes. The default tier keeps what they check without cargo:
//! `plugins new` writes the crate and refuses what it must (the crate's code is the example's,
//! line for line: `plugin_template`'s unit tests; the example is built with the workspace), and
//! `compare --watch` reloads a library rewritten in place, here with the workspace's plugins.
//!
//! The new crates are built with cargo (offline, with the workspace's `Cargo.lock`) into
//! `target/plugin-tests/`, which persists between runs: the first run compiles the sdk and its
//! dependencies for the new crates' profile (a few minutes here); later runs compile only the
//! small plugin crate. It is not the workspace's own `target/debug`, where a library would be
//! found beside the binary by every other test, and where the sdk is built with other features
//! (the host's) anyway.

use crate::common;

use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use common::{flarebench, json, temp_dir};
use flarebench_sdk::abi::author::{Scene, SceneLight};
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_test_support::{build_dir, library_file_name, load_lens, plugin_library};
use serde_json::Value;

/// Relative difference allowed between the energy ratio of two glows and the ratio of their
/// gains: each pixel is computed in f64 and rounded to f32 (a relative 6e-8), and the energies
/// are sums of such pixels; 1e-5 leaves room and is far below any real change of `gain`.
const GAIN_RATIO_TOL: f64 = 1e-5;

/// Longest wait for the watcher's next line before the test gives up (a guard against a hang,
/// not a timing assertion: a debug build of the plugin and a comparison take seconds).
const LINE_WAIT: Duration = Duration::from_secs(600);

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs `plugins new NAME` into `target/plugin-tests/crates/NAME` (emptied first: a fixed
/// place, so each run rebuilds the same package instead of adding another to the target
/// directory) and gives the crate the workspace's lock file, so an offline build uses the
/// versions already downloaded.
fn new_plugin(name: &str) -> PathBuf {
    let krate = plugin_target_dir().join("crates").join(name);
    match std::fs::remove_dir_all(&krate) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => panic!("{}: {e}", krate.display()),
        _ => {}
    }
    let out = flarebench(&["plugins", "new", name, "--path", krate.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("cargo build --manifest-path"), "{text}");
    assert!(text.contains("--watch"), "{text}");
    // Inside this workspace (the target directory usually is), the note says what to add to
    // its members.
    let (krate_abs, root_abs) = (
        krate.canonicalize().unwrap(),
        root().canonicalize().unwrap(),
    );
    if let Ok(member) = krate_abs.strip_prefix(&root_abs) {
        let add = format!("add \"{}\" to `members`", member.display());
        assert!(text.contains(&add), "{text}");
    }
    std::fs::copy(root().join("Cargo.lock"), krate.join("Cargo.lock")).unwrap();
    krate
}

/// The target directory the new crates are built into.
fn plugin_target_dir() -> PathBuf {
    build_dir()
        .parent()
        .expect("the build directory is inside the target directory")
        .join("plugin-tests")
}

/// Builds the crate at `krate` with cargo and returns its library.
fn cargo_build(krate: &Path, lib_name: &str) -> PathBuf {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .args(["build", "--offline", "--quiet", "--manifest-path"])
        .arg(krate.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", plugin_target_dir())
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo build of {}:\n{}",
        krate.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let lib = plugin_target_dir()
        .join("debug")
        .join(library_file_name(lib_name));
    assert!(lib.is_file(), "{} was not built", lib.display());
    lib
}

#[test]
fn plugins_new_writes_a_crate_and_refuses_a_taken_directory_or_a_bad_name() {
    let krate = new_plugin("new-crate");
    for file in ["Cargo.toml", "Cargo.lock", "src/lib.rs"] {
        assert!(krate.join(file).is_file(), "{file} in {}", krate.display());
    }
    let manifest = std::fs::read_to_string(krate.join("Cargo.toml")).unwrap();
    assert!(manifest.contains("name = \"new-crate\""), "{manifest}");
    assert!(manifest.contains("\"cdylib\""), "{manifest}");

    // The directory is now taken, and a name cannot name a crate.
    let out = flarebench(&[
        "plugins",
        "new",
        "new-crate",
        "--path",
        krate.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("already exists and is not empty"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = flarebench(&["plugins", "new", "2fast", "--path", "unused"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("must start with a letter"), "{err}");
    assert!(!Path::new("unused").exists());
}

#[test]
#[ignore = "slow tier: cargo builds the new crate (minutes on a clean clone)"]
fn plugins_new_writes_a_crate_that_builds_loads_and_draws_what_the_example_draws() {
    let krate = new_plugin("new-glow");
    let lib = cargo_build(&krate, "new_glow");

    // Listed under its own name, with the example's parameters.
    let v = json(&[
        "plugins",
        "list",
        "--json",
        "--plugin",
        lib.to_str().unwrap(),
    ]);
    let entry = v["plugins"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["path"] == lib.to_str().unwrap())
        .expect("the new library is listed");
    assert_eq!(entry["status"], "ok", "{entry}");
    assert_eq!(entry["name"], "new-glow");
    let params: Vec<&str> = entry["params"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(params, ["sigma_px", "gain"]);

    // The same image as the example's library, bit for bit.
    let lens = load_lens("heliar-tronnier");
    let scene = Scene {
        lights: vec![SceneLight {
            theta_deg: 4.0,
            phi_deg: 60.0,
            intensity: 2.0,
            spectrum: LightSpectrum::D65,
        }],
        frame: Frame {
            width: 160,
            height: 90,
            film_width_mm: 36.0,
            film_height_mm: 20.25,
        },
        aperture: Aperture::Circular,
    };
    let render = |path: &Path| {
        let p = host::load(path).unwrap();
        let values = parse_values(&p.params, "sigma_px=5,gain=3").unwrap();
        let mut inst = p.instantiate().unwrap();
        inst.prepare(&lens).unwrap();
        inst.render(&scene, &values).unwrap().image
    };
    let mine = render(&lib);
    let example = render(&plugin_library("example_glow"));
    let energy: f64 = mine.pixels.iter().map(|p| p[0] as f64).sum();
    assert!(energy > 1.0, "the glow drew {energy}");
    assert!(mine.pixels == example.pixels, "the images differ");
}

/// The watcher as a child process, its stdout read line by line on a thread; killed when
/// dropped (a failing test leaves nothing running).
struct Watcher {
    child: Child,
    lines: mpsc::Receiver<String>,
    stderr: PathBuf,
}

impl Watcher {
    fn start(args: &[&str], stderr: PathBuf) -> Watcher {
        let mut child = common::command()
            .args(args)
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(&stderr).unwrap())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Watcher {
            child,
            lines,
            stderr,
        }
    }

    /// The next event the watcher printed (one JSON object per line), or `None` at its end.
    fn next(&self) -> Option<Value> {
        match self.lines.recv_timeout(LINE_WAIT) {
            Ok(line) => Some(
                serde_json::from_str(&line)
                    .unwrap_or_else(|e| panic!("not a JSON line ({e}): {line}")),
            ),
            Err(mpsc::RecvTimeoutError::Disconnected) => None,
            Err(mpsc::RecvTimeoutError::Timeout) => panic!(
                "no line from compare --watch in {LINE_WAIT:?}; its stderr:\n{}",
                std::fs::read_to_string(&self.stderr).unwrap_or_default()
            ),
        }
    }

    /// The next event, which must be of kind `event`.
    fn expect(&self, event: &str) -> Value {
        let v = self.next().unwrap_or_else(|| {
            panic!(
                "compare --watch ended before `{event}`; its stderr:\n{}",
                std::fs::read_to_string(&self.stderr).unwrap_or_default()
            )
        });
        assert_eq!(v["event"], event, "{v}");
        v
    }
}

impl Drop for Watcher {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The value `compare` printed for parameter `name` of its only algorithm.
fn param(report: &Value, name: &str) -> String {
    report["algorithms"][0]["params"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p[0] == name)
        .map(|p| p[1].as_str().unwrap().to_string())
        .unwrap_or_else(|| panic!("no parameter {name} in {report}"))
}

/// The algorithm's energy relative to the reference's (1 + the energy error).
fn relative_energy(report: &Value) -> f64 {
    let a = &report["algorithms"][0];
    assert!(a["failure"].is_null(), "{a}");
    1.0 + a["error"]["energy_error"].as_f64().unwrap()
}

/// A copy of the Heliar's lens file in `dir`, and `compare --watch` of the plugin library
/// `lib` on it (64 × 36, one run, on the CPU, three changes), its events in JSON.
fn watch_compare(dir: &Path, lib: &Path) -> (PathBuf, Watcher) {
    let lens = dir.join("lens.xml");
    std::fs::copy(root().join("lenses/heliar-tronnier.xml"), &lens).unwrap();
    let w = Watcher::start(
        &[
            "compare",
            lens.to_str().unwrap(),
            "--light",
            "3,0",
            "--algo",
            lib.to_str().unwrap(),
            "--size",
            "64x36",
            "--runs",
            "1",
            "--backend",
            "cpu",
            // The reference is rendered once: the lens reload reads it back (the lens is the
            // same system).
            "--reference-file",
            dir.join("reference.exr").to_str().unwrap(),
            "--json",
            "--watch",
            "--watch-events",
            "3",
            "-o",
            dir.join("cmp.png").to_str().unwrap(),
        ],
        dir.join("watch.stderr"),
    );
    (lens, w)
}

/// Puts `bytes` at `path` as cargo does, by replacing the file: cargo's library beside the
/// build is a hard link to the one in `deps/`, which a write in place would corrupt for the
/// next build.
fn replace_file(path: &Path, bytes: &[u8]) {
    let tmp = path.with_extension("new");
    std::fs::write(&tmp, bytes).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// The watched library `lib` broken, then `lens` saved again (one more blank line): the
/// watcher shows the error, compares again with the plugin of the last good load, and ends
/// after these, its third change. Returns that comparison.
fn break_library_then_save_lens(w: &Watcher, lib: &Path, lens: &Path) -> Value {
    replace_file(lib, b"not a shared library");
    let failed = w.expect("reload_failed");
    assert_eq!(failed["what"], "plugin");
    let error = failed["error"].as_str().unwrap();
    assert!(
        error.contains(lib.to_str().unwrap()) && error.contains("could not load the library"),
        "{error}"
    );
    let mut text = std::fs::read_to_string(lens).unwrap();
    text.push('\n');
    std::fs::write(lens, text).unwrap();
    assert_eq!(w.expect("reloaded")["what"], "lens");
    let third = w.expect("compared");
    assert!(w.next().is_none(), "nothing after the third change");
    third
}

#[test]
#[ignore = "slow tier: cargo builds the new crate twice (minutes on a clean clone)"]
fn compare_watch_reloads_a_rebuilt_plugin_and_keeps_it_when_a_broken_library_follows() {
    let tmp = temp_dir("plugin-watch");
    let krate = new_plugin("loop-glow");
    let lib = cargo_build(&krate, "loop_glow");
    let (lens, w) = watch_compare(tmp.path(), &lib);
    let first = w.expect("compared");
    assert_eq!(param(&first, "gain"), "1");
    let e1 = relative_energy(&first);
    assert!(tmp.path().join("cmp.png").is_file());

    // Change the gain's default from 1 to 2.5 and rebuild.
    let src = krate.join("src/lib.rs");
    let code = std::fs::read_to_string(&src).unwrap();
    let old = "1e6,\n                    1.0,\n";
    assert_eq!(code.matches(old).count(), 1, "the gain's default in {code}");
    std::fs::write(&src, code.replace(old, "1e6,\n                    2.5,\n")).unwrap();
    cargo_build(&krate, "loop_glow");

    let reloaded = w.expect("reloaded");
    assert_eq!(reloaded["what"], "plugin");
    assert_eq!(reloaded["name"], "loop-glow");
    assert_eq!(reloaded["defaults"][1], serde_json::json!(["gain", "2.5"]));
    let second = w.expect("compared");
    assert_eq!(param(&second, "gain"), "2.5");
    let e2 = relative_energy(&second);
    assert!(
        (e2 / e1 / 2.5 - 1.0).abs() < GAIN_RATIO_TOL,
        "energy {e1} → {e2}: not 2.5 times"
    );

    // A broken library: the error is shown and the rebuilt plugin stays in use.
    let third = break_library_then_save_lens(&w, &lib, &lens);
    assert_eq!(param(&third, "gain"), "2.5");
    assert!((relative_energy(&third) / e2 - 1.0).abs() < GAIN_RATIO_TOL);
}

/// `compare --watch` without cargo: the library at the watched path is rewritten in place with
/// another of the workspace's plugins (replaced as cargo replaces it), then with a broken file;
/// the lens file is saved again.
#[test]
fn compare_watch_reloads_a_rewritten_library_and_keeps_it_when_a_broken_one_follows() {
    let tmp = temp_dir("plugin-watch-copy");
    let lib = tmp.path().join(library_file_name("watched"));
    std::fs::copy(plugin_library("example_glow"), &lib).unwrap();
    let (lens, w) = watch_compare(tmp.path(), &lib);
    let first = w.expect("compared");
    assert_eq!(first["algorithms"][0]["plugin"], "example-glow", "{first}");
    assert_eq!(param(&first, "gain"), "1");
    let glow_energy = relative_energy(&first);

    // Another build at the same path (here the ghost-matrix plugin).
    replace_file(
        &lib,
        &std::fs::read(plugin_library("ghost_matrix")).unwrap(),
    );
    let reloaded = w.expect("reloaded");
    assert_eq!(reloaded["what"], "plugin");
    assert_eq!(reloaded["name"], "ghost-matrix");
    let second = w.expect("compared");
    assert_eq!(
        second["algorithms"][0]["plugin"], "ghost-matrix",
        "{second}"
    );
    let matrix_energy = relative_energy(&second);
    assert!(
        (matrix_energy / glow_energy - 1.0).abs() > 0.01,
        "the glow's energy {glow_energy} and the ghosts' {matrix_energy}"
    );

    // A broken library: the error, and the last good one stays in use when the lens changes.
    let third = break_library_then_save_lens(&w, &lib, &lens);
    assert_eq!(third["algorithms"][0]["plugin"], "ghost-matrix", "{third}");
    assert!((relative_energy(&third) / matrix_energy - 1.0).abs() < GAIN_RATIO_TOL);
}

/// A pass of the viewer's UI with no display and no painting (the viewer's state is all the
/// test reads): a bare egui context.
#[cfg(feature = "window")]
fn viewer_pass(ctx: &egui::Context, viewer: &mut flarebench::viewer::Viewer) {
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(1200.0, 640.0),
        )),
        ..egui::RawInput::default()
    };
    let mut out = ctx.run_ui(input, |ui| viewer.frame(ui));
    // Nothing paints: the textures it uploads are dropped.
    out.textures_delta.clear();
}

/// Passes until `done` holds, waiting for the render thread between them, or panics.
#[cfg(feature = "window")]
fn viewer_until(
    ctx: &egui::Context,
    viewer: &mut flarebench::viewer::Viewer,
    what: &str,
    done: impl Fn(&flarebench::viewer::Viewer) -> bool,
) {
    let end = std::time::Instant::now() + LINE_WAIT;
    viewer_pass(ctx, viewer);
    while !done(viewer) {
        assert!(
            viewer.render_failure().is_none(),
            "{:?}",
            viewer.render_failure()
        );
        assert!(
            std::time::Instant::now() < end,
            "no {what} in {LINE_WAIT:?}; status: {:?}",
            viewer.message()
        );
        viewer.wait_for_render(Duration::from_millis(50));
        viewer_pass(ctx, viewer);
    }
}

#[cfg(feature = "window")]
#[test]
#[ignore = "slow tier: cargo builds the new crate twice (minutes on a clean clone)"]
fn the_window_reloads_a_rebuilt_plugin_and_renders_with_its_new_default() {
    use flarebench::algo_spec::Algo;
    use flarebench::flare::backend::BackendChoice;
    use flarebench::viewer::{StarburstMode, Viewer, ViewerOptions};
    use ghost_raytrace::scene::{LightSpec, Quality};

    let krate = new_plugin("window-glow");
    let lib = cargo_build(&krate, "window_glow");
    let options = ViewerOptions {
        backend: BackendChoice::Cpu,
        size: (64, 36),
        lights: vec![LightSpec::parse("3,0").unwrap()],
        quality: Quality::Fast,
        starburst: StarburstMode::Off,
        ..ViewerOptions::default()
    };
    let algo = Algo::resolve(lib.to_str().unwrap(), &[], true);
    let mut viewer = Viewer::new(load_lens("heliar-tronnier"), options, Box::new(|| {}))
        .with_algos(vec![algo])
        .unwrap();
    let ctx = egui::Context::default();
    viewer_until(&ctx, &mut viewer, "first frame", Viewer::settled);
    let energy = |v: &Viewer| v.frame_shown().unwrap().hdr.sum().iter().sum::<f64>();
    let e1 = energy(&viewer);
    assert!(e1 > 0.0, "the glow drew nothing");
    assert_eq!(
        viewer.frame_shown().unwrap().plugin.as_ref().unwrap().name,
        "window-glow"
    );

    // The gain's default from 1 to 2.5, rebuilt by cargo while the viewer runs.
    let src = krate.join("src/lib.rs");
    let code = std::fs::read_to_string(&src).unwrap();
    let old = "1e6,\n                    1.0,\n";
    assert_eq!(code.matches(old).count(), 1, "the gain's default in {code}");
    std::fs::write(&src, code.replace(old, "1e6,\n                    2.5,\n")).unwrap();
    cargo_build(&krate, "window_glow");
    let built = std::time::Instant::now();
    viewer_until(&ctx, &mut viewer, "reload", |v| v.algos()[0].reloads == 1);
    viewer_until(&ctx, &mut viewer, "frame after the reload", Viewer::settled);
    eprintln!(
        "cargo build returned → the new frame: {:.0} ms ({})",
        built.elapsed().as_secs_f64() * 1e3,
        viewer.message().unwrap_or_default()
    );
    let f = viewer.frame_shown().unwrap();
    assert_eq!(f.plugin.as_ref().unwrap().reloads, 1);
    let e2 = energy(&viewer);
    assert!(
        (e2 / e1 / 2.5 - 1.0).abs() < GAIN_RATIO_TOL,
        "energy {e1} → {e2}: not 2.5 times"
    );
}

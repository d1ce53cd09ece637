//! The viewer's flare preview through ghost plugins (`view --algo`), drawn offscreen as in
//! `viewer.rs`: a plugin's frame is the image `compare` renders with it
//! (`GhostBackend::render_plugin`) bit for bit, `A` switches to the built-in renderer and back,
//! the debug views say they are not available; a plugin library rewritten under the window is
//! loaded afresh and the preview renders again with it, and a broken one leaves the previous
//! plugin in use with the error in the status line and the editor's.
//!
//! The plugins are the workspace's own libraries (`cargo build --workspace` puts them beside
//! the binary); the author's loop with a real rebuild is in `plugin_loop.rs`.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use flarebench::algo_spec::Algo;
use flarebench::flare::backend::{BackendChoice, GhostBackend};
use flarebench::link::{FromEditor, ToEditor};
use flarebench::viewer::flare_worker::view_frame;
use flarebench::viewer::offscreen::Offscreen;
use flarebench::viewer::{EditorLink, StarburstMode, Viewer, ViewerOptions, status};
use flarebench_sdk::LensSystem;
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::image::HdrImage;
use flarebench_test_support::{load_lens, plugin_library};
use ghost_raytrace::scene::{LightSpec, Quality};

use crate::offscreen_viewer;
use offscreen_viewer::{key, settled};

const WINDOW: (u32, u32) = (1200, 640);
const SIZE: (usize, usize) = (480, 270);
/// Longest wait for a frame (a guard against a hang, not a timing assertion).
/// Longest wait for the watch thread to notice a rewritten library: it polls every 200 ms
/// and takes a file once it has held still for two polls, so well under a second; the rest
/// is a guard against a hang on a loaded machine.
const RELOAD_WAIT: Duration = Duration::from_secs(60);

fn options() -> ViewerOptions {
    ViewerOptions {
        backend: BackendChoice::Cpu,
        size: SIZE,
        lights: vec![LightSpec::parse("8,30").unwrap()],
        quality: Quality::Fast,
        // The ghosts alone: what `compare` draws.
        starburst: StarburstMode::Off,
        ..ViewerOptions::default()
    }
}

/// What `compare` renders with the library at `path` (default parameters) on the CPU backend,
/// for the viewer's scene: `GhostBackend::render_plugin`, as `compare` calls it.
fn compare_render(path: &Path, lens: &LensSystem, light: &LightSpec) -> HdrImage {
    compare_render_on(BackendChoice::Cpu, path, lens, light, SIZE)
}

/// [`compare_render`] on `backend`, `size` pixels.
fn compare_render_on(
    backend: BackendChoice,
    path: &Path,
    lens: &LensSystem,
    light: &LightSpec,
    size: (usize, usize),
) -> HdrImage {
    let plugin = host::load(path).unwrap();
    let values = parse_values(&plugin.params, "").unwrap();
    let mut inst = plugin.instantiate().unwrap();
    inst.prepare(lens).unwrap();
    let scene = Scene {
        lights: vec![light.scene_light()],
        frame: view_frame(lens, size.0, size.1),
        aperture: Aperture::Circular,
    };
    let mut backend = GhostBackend::open(backend).unwrap();
    let mut image = HdrImage::new(0, 0);
    backend
        .render_plugin(&mut inst, &scene, &values, &mut image)
        .unwrap();
    image
}

/// The viewer with the plugin library at `path` (given by path, as `view --algo PATH`), linked
/// to a pretend editor whose notes come back on the receiver.
fn viewer_with(path: &Path) -> (Viewer, Receiver<ToEditor>) {
    viewer_on(options(), &[path])
}

/// [`viewer_with`] with `options` and several plugins.
fn viewer_on(options: ViewerOptions, paths: &[&Path]) -> (Viewer, Receiver<ToEditor>) {
    let (change_tx, changes) = channel();
    drop(change_tx);
    let (_sel_tx, selection) = channel::<FromEditor>();
    let (to_editor, from_window) = channel::<ToEditor>();
    let link = EditorLink {
        changes,
        selection,
        to_editor,
    };
    let algos = paths
        .iter()
        .map(|p| Algo::resolve(p.to_str().unwrap(), &[], true))
        .collect();
    let viewer = Viewer::new(load_lens("heliar-tronnier"), options, Box::new(|| {}))
        .with_link(link)
        .with_algos(algos)
        .unwrap();
    (viewer, from_window)
}

#[test]
fn a_plugins_preview_is_what_compare_renders_and_a_switches_to_the_built_in_renderer() {
    let lib = plugin_library("ghost_matrix");
    let (mut viewer, _notes) = viewer_with(&lib);
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let f = viewer.frame_shown().unwrap().clone();
    let p = f.plugin.as_ref().expect("a plugin's frame");
    assert_eq!(p.name, "ghost-matrix");
    assert_eq!(p.reloads, 0);
    assert!(p.items_drawn > 0 && p.mesh_triangles > 0, "{p:?}");
    let want = compare_render(&lib, viewer.system(), &viewer.scene().lights[0]);
    assert!(
        want.sum().iter().sum::<f64>() > 0.0,
        "the plugin drew nothing"
    );
    assert!(
        f.hdr.pixels == want.pixels,
        "the preview differs from compare's image"
    );
    assert!(status::frame_line(&f).contains("frame by plugin `ghost-matrix`"));

    // The debug views are the built-in renderer's: a note, no trace asked for.
    target.pass(&mut viewer, key(egui::Key::N));
    target.pass(&mut viewer, key(egui::Key::D));
    settled(&mut viewer, &mut target);
    assert!(viewer.selected_ghost().is_some());
    let f = viewer.frame_shown().unwrap();
    assert!(f.debug.is_none() && f.plugin.is_some());
    target.pass(&mut viewer, key(egui::Key::D));
    target.pass(&mut viewer, key(egui::Key::D));
    target.pass(&mut viewer, key(egui::Key::D));
    target.pass(&mut viewer, key(egui::Key::D));

    // A: the built-in renderer (its fast frame, with ghost footprints), then the plugin again.
    target.pass(&mut viewer, key(egui::Key::A));
    assert!(viewer.active_algo().is_none());
    settled(&mut viewer, &mut target);
    let built_in = viewer.frame_shown().unwrap().clone();
    assert!(built_in.plugin.is_none() && !built_in.ghosts.is_empty());
    assert!(built_in.hdr.pixels != want.pixels);
    target.pass(&mut viewer, key(egui::Key::A));
    settled(&mut viewer, &mut target);
    let again = viewer.frame_shown().unwrap();
    assert_eq!(again.plugin.as_ref().unwrap().name, "ghost-matrix");
    assert!(again.hdr.pixels == want.pixels);
}

/// Puts `bytes` at `path` as cargo puts a new library there: written beside it, then renamed
/// over it (the old file's inode stays intact for the copies loaded from it).
fn replace_file(path: &Path, bytes: &[u8]) {
    let tmp = path.with_extension("new");
    std::fs::write(&tmp, bytes).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// Passes until `done` holds (the watch thread's events are taken in a pass), or panics.
fn pass_until(
    viewer: &mut Viewer,
    target: &mut Offscreen,
    what: &str,
    done: impl Fn(&Viewer) -> bool,
) {
    let end = Instant::now() + RELOAD_WAIT;
    while !done(viewer) {
        assert!(
            Instant::now() < end,
            "no {what} within {RELOAD_WAIT:?}; status: {:?}",
            viewer.message()
        );
        std::thread::sleep(Duration::from_millis(20));
        target.pass(viewer, Vec::new());
    }
}

#[test]
fn a_rewritten_plugin_library_is_reloaded_and_a_broken_one_keeps_the_previous_with_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let lib: PathBuf = dir
        .path()
        .join(flarebench_test_support::library_file_name("watched"));
    std::fs::copy(plugin_library("ghost_matrix"), &lib).unwrap();
    let (mut viewer, notes) = viewer_with(&lib);
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let first = viewer.frame_shown().unwrap().clone();
    assert_eq!(first.plugin.as_ref().unwrap().name, "ghost-matrix");

    // Another build at the same path (here another plugin: a spec given by path names no
    // plugin): loaded as a fresh copy, and the preview renders with it.
    let glow = plugin_library("example_glow");
    let t = Instant::now();
    replace_file(&lib, &std::fs::read(&glow).unwrap());
    pass_until(&mut viewer, &mut target, "reload", |v| {
        v.algos()[0].reloads == 1
    });
    settled(&mut viewer, &mut target);
    eprintln!(
        "rewritten library → its frame shown: {:.0} ms ({})",
        t.elapsed().as_secs_f64() * 1e3,
        viewer.message().unwrap_or_default()
    );
    let second = viewer.frame_shown().unwrap().clone();
    let p = second.plugin.as_ref().unwrap();
    assert_eq!((p.name.as_str(), p.reloads), ("example-glow", 1));
    assert!(second.id > first.id);
    let want = compare_render(&glow, viewer.system(), &viewer.scene().lights[0]);
    assert!(
        second.hdr.pixels == want.pixels,
        "the reloaded plugin's preview differs from compare's image"
    );
    assert!(
        viewer
            .message()
            .unwrap()
            .starts_with("reloaded plugin `example-glow`")
    );
    let note = notes.try_iter().last();
    assert!(
        matches!(&note, Some(ToEditor::Note(n)) if n.contains("reloaded plugin `example-glow`")),
        "{note:?}"
    );

    // A broken library: the error in the status line and the editor's, the plugin of the
    // last good load still rendering (a moved light renders with it).
    replace_file(&lib, b"not a shared library");
    pass_until(&mut viewer, &mut target, "failed reload", |v| {
        v.algos()[0].reload_error.is_some()
    });
    let message = viewer.message().unwrap().to_string();
    assert!(
        message.starts_with("plugin reload failed, the previous one stays in use")
            && message.contains(lib.to_str().unwrap()),
        "{message}"
    );
    let (line, error) = status::renderer_line(viewer.algos(), viewer.active_algo()).unwrap();
    assert!(
        line.contains("`example-glow`") && line.contains("reload 1"),
        "{line}"
    );
    assert!(error.unwrap().contains("last reload failed"));
    let note = notes.try_iter().last();
    assert!(
        matches!(&note, Some(ToEditor::Note(n)) if n.contains("plugin reload failed")),
        "{note:?}"
    );
    viewer.move_light(0, 5.0, 100.0);
    settled(&mut viewer, &mut target);
    let third = viewer.frame_shown().unwrap();
    let p = third.plugin.as_ref().unwrap();
    assert_eq!((p.name.as_str(), p.reloads), ("example-glow", 1));
    assert!(third.hdr.pixels != second.hdr.pixels, "the light moved");
    let want = compare_render(&glow, viewer.system(), &viewer.scene().lights[0]);
    assert!(third.hdr.pixels == want.pixels);
}

/// The GPU against the CPU for a plugin's mesh, relative RMSE and energy: what
/// `plugins.rs`'s `compare_draws_plugin_meshes_on_the_gpu_and_reports_the_backend` allows (the
/// two rasterizers' exact coverage differ in rounding along edges).
const GPU_CPU_MAX_RMSE: f64 = 0.005;
const GPU_CPU_MAX_ENERGY: f64 = 0.001;

#[test]
fn on_the_gpu_a_plugins_preview_is_compares_gpu_image_its_own_pixels_kept() {
    let matrix = plugin_library("ghost_matrix");
    let glow = plugin_library("example_glow");
    // A sixteenth of the other tests' frame: lavapipe shades the matrix ghosts' frame-wide
    // triangles one fragment at a time.
    let size = (SIZE.0 / 4, SIZE.1 / 4);
    let (mut viewer, _notes) = viewer_on(
        ViewerOptions {
            backend: BackendChoice::Gpu,
            size,
            // Near the axis: the starburst lands in the frame.
            lights: vec![LightSpec::parse("3,40").unwrap()],
            ..options()
        },
        &[&matrix, &glow],
    );
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    // The first plugin (a mesh), then `A` to the second (pixels of its own).
    for (k, lib) in [&matrix, &glow].into_iter().enumerate() {
        if k > 0 {
            target.pass(&mut viewer, key(egui::Key::A));
        }
        settled(&mut viewer, &mut target);
        let f = viewer.frame_shown().unwrap().clone();
        assert_eq!(f.backend.backend, "gpu", "{:?}", f.backend);
        assert_eq!(
            viewer.active_algo().unwrap().spec,
            lib.to_str().unwrap(),
            "A goes to the next plugin"
        );
        let light = viewer.scene().lights[0].clone();
        let gpu = compare_render_on(BackendChoice::Gpu, lib, viewer.system(), &light, size);
        let cpu = compare_render_on(BackendChoice::Cpu, lib, viewer.system(), &light, size);
        assert!(
            f.hdr.pixels == gpu.pixels,
            "{}: not compare's GPU image",
            lib.display()
        );
        let c = f.hdr.compare(&cpu).unwrap();
        assert!(
            c.relative_rmse <= GPU_CPU_MAX_RMSE && c.energy_error.abs() <= GPU_CPU_MAX_ENERGY,
            "{}: against the CPU {c:?}",
            lib.display()
        );
    }
    // With the starburst (S: off → only → on) added to the glow's frame, the glow is still
    // there: the starburst only adds light.
    let glow_only = viewer.frame_shown().unwrap().hdr.clone();
    target.pass(&mut viewer, key(egui::Key::S));
    target.pass(&mut viewer, key(egui::Key::S));
    assert_eq!(viewer.scene().starburst, StarburstMode::On);
    settled(&mut viewer, &mut target);
    let with_starburst = &viewer.frame_shown().unwrap().hdr;
    let lost = with_starburst
        .pixels
        .iter()
        .zip(&glow_only.pixels)
        .filter(|(p, q)| (0..3).any(|c| p[c] < q[c] * (1.0 - 1e-5)))
        .count();
    assert_eq!(
        lost, 0,
        "pixels of the plugin's own lost under the starburst"
    );
    assert!(with_starburst.sum()[1] > glow_only.sum()[1]);
}

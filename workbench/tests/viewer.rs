//! The viewer drawn offscreen by the same code as the window (`Viewer::frame` painted by egui-
//! wgpu into a texture, on lavapipe in CI): the views against golden PNGs, and the viewer
//! driven by synthetic input — a light drag, a ghost click, an edit through the document
//! channel. (A panicking render: `window.rs`, in a process of its own.)
//!
//! Golden tolerance: egui's text and anti-aliased edges and the flare's tone mapping are
//! deterministic for one driver, but another driver may round blending differently: at most
//! 0.5% of the pixels may differ by more than 24 levels in a channel, and the mean absolute
//! difference must stay under 1 level. A missing golden fails; `UPDATE_GOLDEN=1` writes it.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::channel;
use std::time::Duration;

use egui::{Event, PointerButton, Pos2, pos2};
use flarebench::backend::BackendChoice;
use flarebench::document::{Document, Edit};
use flarebench::link::{FromEditor, ToEditor};
use flarebench::viewer::offscreen::Offscreen;
use flarebench::viewer::{EditorLink, Viewer, ViewerOptions};
use flarebench_sdk::LensSystem;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::scene::{LightSpec, Quality};

const WINDOW: (u32, u32) = (1200, 640);
const SETTLE: Duration = Duration::from_secs(240);

fn lens(name: &str) -> LensSystem {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lenses")
        .join(format!("{name}.xml"));
    read_lens(&path).unwrap().system
}

fn options() -> ViewerOptions {
    ViewerOptions {
        backend: BackendChoice::Cpu,
        size: (480, 270),
        lights: vec![LightSpec::parse("8,30").unwrap()],
        quality: Quality::Fast,
        ..ViewerOptions::default()
    }
}

fn settled(viewer: &mut Viewer, target: &mut Offscreen) {
    assert!(
        target.settle(viewer, SETTLE),
        "the viewer did not settle; status: {:?}",
        viewer.message()
    );
}

/// Compares `got` with the golden PNG `name`, within the module's tolerance.
fn assert_golden(got: &image::RgbaImage, name: &str) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let path = dir.join(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        got.save(&path).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let want = image::open(&path)
        .unwrap_or_else(|e| {
            panic!(
                "missing golden image {} ({e}); run with UPDATE_GOLDEN=1 to create it",
                path.display()
            )
        })
        .to_rgba8();
    assert_eq!(got.dimensions(), want.dimensions(), "{name}: size");
    let (far, mean) = difference(got, &want);
    if far > 0.005 || mean > 1.0 {
        let out = std::env::temp_dir().join(format!("got-{name}"));
        got.save(&out).unwrap();
        panic!(
            "{name}: {:.3}% of the pixels differ by more than 24 levels, mean difference {mean:.3} \
             (image written to {})",
            100.0 * far,
            out.display()
        );
    }
}

/// The share of pixels with a channel more than 24 levels apart, and the mean absolute
/// difference per channel.
fn difference(a: &image::RgbaImage, b: &image::RgbaImage) -> (f64, f64) {
    let mut far = 0usize;
    let mut sum = 0u64;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d: Vec<u32> = (0..3).map(|c| p[c].abs_diff(q[c]) as u32).collect();
        if d.iter().any(|&d| d > 24) {
            far += 1;
        }
        sum += d.iter().map(|&d| d as u64).sum::<u64>();
    }
    let n = (a.width() * a.height()) as f64;
    (far as f64 / n, sum as f64 / (3.0 * n))
}

/// Where the flare image is drawn (points = pixels here): found from the layout the viewer
/// logs.
fn flare_rect(log: &std::sync::Mutex<Vec<String>>) -> egui::Rect {
    view_rect(log, "flare")
}

/// Where view `name` (`lens` or `flare`) is, from the layout the viewer logs.
fn view_rect(log: &std::sync::Mutex<Vec<String>>, name: &str) -> egui::Rect {
    let lines = log.lock().unwrap();
    let head = format!("{name} view at ");
    let line = lines
        .iter()
        .rev()
        .find(|l| l.starts_with(&head))
        .expect("the viewer logs its layout");
    let nums: Vec<f32> = line
        .trim_start_matches(&head)
        .split([',', ' ', 'x'])
        .filter_map(|t| t.parse().ok())
        .collect();
    egui::Rect::from_min_size(pos2(nums[0], nums[1]), egui::vec2(nums[2], nums[3]))
}

fn logged(viewer: Viewer) -> (Viewer, Arc<std::sync::Mutex<Vec<String>>>) {
    let log = Arc::new(std::sync::Mutex::new(Vec::new()));
    let l = Arc::clone(&log);
    let v = viewer.with_log(Box::new(move |line| {
        l.lock().unwrap().push(line.to_string())
    }));
    (v, log)
}

fn press(pos: Pos2, pressed: bool) -> Event {
    Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers: Default::default(),
    }
}

/// The part of `img` inside `r`.
fn crop(img: &image::RgbaImage, r: egui::Rect) -> image::RgbaImage {
    image::imageops::crop_imm(
        img,
        r.min.x as u32,
        r.min.y as u32,
        r.width() as u32,
        r.height() as u32,
    )
    .to_image()
}

#[test]
fn the_views_drawn_offscreen_match_their_golden_images() {
    let (mut viewer, log) = logged(Viewer::new(
        lens("heliar-tronnier"),
        options(),
        Box::new(|| {}),
    ));
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let f = viewer.frame_shown().unwrap();
    assert!(f.stats.ghosts_drawn > 0, "the Heliar at 8° draws ghosts");
    assert!(!f.hdr.has_non_finite());
    let img = target.read().unwrap();
    // The views, not the status line (its times differ from run to run).
    assert_golden(
        &crop(&img, view_rect(&log, "lens")),
        "viewer-heliar-lens.png",
    );
    assert_golden(
        &crop(&img, view_rect(&log, "flare")),
        "viewer-heliar-flare.png",
    );
}

#[test]
fn a_drag_in_the_flare_view_moves_the_light_and_renders_anew() {
    let (mut viewer, log) = logged(Viewer::new(
        lens("heliar-tronnier"),
        options(),
        Box::new(|| {}),
    ));
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let before_id = viewer.frame_shown().unwrap().id;
    let before = viewer.scene().lights[0].clone();
    let rect = flare_rect(&log);
    // Drag from the centre to a point right of and above it.
    let a = rect.center();
    let b = rect.lerp_inside(egui::vec2(0.8, 0.3));
    target.pass(&mut viewer, vec![Event::PointerMoved(a), press(a, true)]);
    for k in 1..=4 {
        let p = a + (b - a) * (k as f32 / 4.0);
        target.pass(&mut viewer, vec![Event::PointerMoved(p)]);
    }
    target.pass(&mut viewer, vec![press(b, false)]);
    settled(&mut viewer, &mut target);
    let after = viewer.scene().lights[0].clone();
    assert_ne!(
        (before.theta_deg, before.phi_deg),
        (after.theta_deg, after.phi_deg)
    );
    // The light now images where the drag ended: the chief ray's landing at (θ, φ) is at the
    // pixel under the mouse.
    let sys = viewer.system().clone();
    let frame = flarebench::viewer::flare_worker::view_frame(&sys, 480, 270);
    let px = [
        ((b.x - rect.min.x) / rect.width() * 480.0) as f64,
        ((b.y - rect.min.y) / rect.height() * 270.0) as f64,
    ];
    let (theta, phi) = flarebench::sources::direction_of(&sys, &frame, px[0], px[1]).unwrap();
    // Within a tenth of a pixel (egui rounds pointer positions to physical pixels).
    assert!(
        (theta - after.theta_deg).abs() < 5e-3 && (phi - after.phi_deg).abs() < 5e-2,
        "light at {},{} but the drag ended over {theta},{phi}",
        after.theta_deg,
        after.phi_deg
    );
    assert!(theta > 1.0, "the drag ended off-centre");
    assert!(viewer.frame_shown().unwrap().id > before_id);
}

#[test]
fn clicking_a_ghost_selects_it_and_tells_the_editor() {
    let (change_tx, changes) = channel();
    drop(change_tx);
    let (_sel_tx, selection) = channel::<FromEditor>();
    let (to_editor, from_window) = channel::<ToEditor>();
    let link = EditorLink {
        changes,
        selection,
        to_editor,
    };
    let (viewer, log) =
        logged(Viewer::new(lens("heliar-tronnier"), options(), Box::new(|| {})).with_link(link));
    let mut viewer = viewer;
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let rect = flare_rect(&log);
    // The brightest drawn ghost whose landing rectangle's centre is in the frame: click there.
    let sys = viewer.system().clone();
    let film = [sys.film_width_mm, sys.film_width_mm * 270.0 / 480.0];
    let f = viewer.frame_shown().unwrap().clone();
    let centre_px = |g: &flarebench::viewer::flare_worker::GhostFootprint| {
        let [x0, y0, x1, y1] = g.rect;
        let (s, c) = g.phi.sin_cos();
        let (mx, my) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let (x, y) = (mx * c - my * s, mx * s + my * c);
        [(0.5 - x / film[0]) * 480.0, (0.5 + y / film[1]) * 270.0]
    };
    let mut ghosts = f.ghosts.clone();
    ghosts.sort_by(|a, b| b.energy_share.total_cmp(&a.energy_share));
    let px = ghosts
        .iter()
        .map(centre_px)
        .find(|p| (10.0..470.0).contains(&p[0]) && (10.0..260.0).contains(&p[1]))
        .expect("a ghost lands in the frame");
    let pos = pos2(
        rect.min.x + (px[0] / 480.0) as f32 * rect.width(),
        rect.min.y + (px[1] / 270.0) as f32 * rect.height(),
    );
    let expected = flarebench::viewer::flare_view::ghost_at(&f, film, px)
        .unwrap()
        .path;
    let light = viewer.scene().lights[0].clone();
    target.pass(
        &mut viewer,
        vec![Event::PointerMoved(pos), press(pos, true)],
    );
    target.pass(&mut viewer, vec![press(pos, false)]);
    target.pass(&mut viewer, vec![]);
    assert_eq!(viewer.selected_ghost(), Some(expected));
    assert_eq!(
        viewer.scene().lights[0],
        light,
        "a click does not move the light"
    );
    assert_eq!(
        from_window.try_iter().collect::<Vec<_>>(),
        vec![ToEditor::SelectGhost(expected)]
    );
}

#[test]
fn an_edit_through_the_document_channel_redraws_lens_and_flare() {
    let system = lens("heliar-tronnier");
    let mut doc = Document::new(system.clone()).unwrap();
    let changes = doc.subscribe();
    let (_sel_tx, selection) = channel::<FromEditor>();
    let (to_editor, _from_window) = channel::<ToEditor>();
    let link = EditorLink {
        changes,
        selection,
        to_editor,
    };
    let mut viewer = Viewer::new(system.clone(), options(), Box::new(|| {})).with_link(link);
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let before = target.read().unwrap();
    let energy_before = viewer.frame_shown().unwrap().hdr.sum();

    // Make the first surface much flatter.
    let old = system.surfaces[0].clone();
    let mut new = old.clone();
    new.curvature *= 0.5;
    doc.apply(Edit::Replace {
        index: 0,
        old,
        new: new.clone(),
    })
    .unwrap();
    settled(&mut viewer, &mut target);
    assert_eq!(viewer.revision(), 1);
    assert_eq!(viewer.system().surfaces[0], new);
    let after = target.read().unwrap();
    let (far, _) = difference(&before, &after);
    assert!(far > 0.001, "the window did not change after the edit");
    let energy_after = viewer.frame_shown().unwrap().hdr.sum();
    assert_ne!(energy_before, energy_after, "the flare did not change");
}

#[test]
fn the_wheel_changes_the_exposure_without_rendering_anew() {
    let (mut viewer, log) = logged(Viewer::new(
        lens("heliar-tronnier"),
        options(),
        Box::new(|| {}),
    ));
    let mut target = Offscreen::new(WINDOW.0, WINDOW.1).unwrap();
    settled(&mut viewer, &mut target);
    let id = viewer.frame_shown().unwrap().id;
    let rect = flare_rect(&log);
    let before = target.read().unwrap();
    let wheel = Event::MouseWheel {
        unit: egui::MouseWheelUnit::Line,
        delta: egui::vec2(0.0, 2.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Unknown,
        modifiers: Default::default(),
    };
    target.pass(&mut viewer, vec![Event::PointerMoved(rect.center()), wheel]);
    target.pass(&mut viewer, vec![]);
    assert_eq!(
        viewer.scene().exposure_offset_ev,
        1.0,
        "two notches: one stop"
    );
    assert_eq!(viewer.frame_shown().unwrap().id, id, "no new render");
    let after = target.read().unwrap();
    // One stop brighter: the flare's mean level rises, the lens view stays.
    let mean = |img: &image::RgbaImage| {
        let mut s = 0u64;
        let mut n = 0u64;
        for y in rect.min.y as u32 + 2..rect.max.y as u32 - 2 {
            for x in rect.min.x as u32 + 2..rect.max.x as u32 - 2 {
                s += img.get_pixel(x, y).0[..3]
                    .iter()
                    .map(|&c| c as u64)
                    .sum::<u64>();
                n += 3;
            }
        }
        s as f64 / n as f64
    };
    assert!(
        mean(&after) > 1.1 * mean(&before),
        "{} → {}",
        mean(&before),
        mean(&after)
    );
}

//! The viewer window's reaction times (the viewer issue's targets), measured on the same code
//! the window runs, drawn offscreen at 1500 × 820 (egui-wgpu on whatever adapter there is):
//!
//! - `ui_layout/{heliar,nikon}`: one UI pass with nothing new to render, laid out and
//!   tessellated — the CPU's share of a redraw, what is left of it on a GPU (target ≤ 16 ms);
//! - `ui_pass/{heliar,nikon}`: the same pass also painted, waiting for the device (on
//!   lavapipe the painting runs on the CPU too);
//! - `lens_rebuild/nikon`: the lens drawing, three ray fans and the ghost list rebuilt after an
//!   edit (the UI thread's share of an edit);
//! - `drag_to_fast_frame/{heliar,nikon}`: a light moved until its fast frame (960 × 540) has
//!   arrived and been laid out with its new image uploaded, ready to paint (targets ≤ 50 ms
//!   and ≤ 100 ms); the lens's bounds table (`viewer::bounds_table`) is complete first, as it
//!   is a few seconds after the lens last changed;
//! - `edit_to_fast_frame/nikon`: an edit arriving through the document channel until the new
//!   lens and its fast flare are laid out, ready to paint (target ≤ 100 ms).
//!
//! The reaction times leave the final paint out: `ui_pass − ui_layout` is its cost here. The
//! flare is rendered by the CPU backend (`--backend cpu`; `auto` on a machine without a
//! hardware GPU). Run: `cargo bench -p flarebench --bench viewer`.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use flarebench::flare::backend::BackendChoice;
use flarebench::lens_drawing::{self, LensDrawing};
use flarebench::viewer::offscreen::Offscreen;
use flarebench::viewer::{Viewer, ViewerOptions};
use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::enumerate_ghosts;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::scene::{LightSpec, Quality};

fn lens(name: &str) -> LensSystem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../lenses/{name}.xml"));
    read_lens(&path).unwrap().system
}

/// A viewer on `name` whose newest frame is its fast frame, shown.
fn settled_viewer(name: &str, target: &mut Offscreen) -> Viewer {
    let options = ViewerOptions {
        backend: BackendChoice::Cpu,
        size: (960, 540),
        lights: vec![LightSpec::parse("8,30").unwrap()],
        quality: Quality::Fast,
        ..ViewerOptions::default()
    };
    let mut v = Viewer::new(lens(name), options, Box::new(|| {}));
    assert!(target.settle(&mut v, Duration::from_secs(600)));
    v
}

/// Unpainted passes until the newest job's frame has arrived and been laid out.
fn until_shown(v: &mut Viewer, target: &mut Offscreen) {
    target.pass_unpainted(v, Vec::new());
    let end = Instant::now() + Duration::from_secs(600);
    while !v.settled() {
        assert!(v.render_failure().is_none(), "{:?}", v.message());
        assert!(Instant::now() < end, "no frame in 600 s");
        v.wait_for_render(Duration::from_millis(200));
        target.pass_unpainted(v, Vec::new());
    }
}

/// Waits until the render thread's bounds table for the viewer's lens is finished (it works
/// on it between jobs).
fn table_finished(v: &mut Viewer, target: &mut Offscreen) {
    let end = Instant::now() + Duration::from_secs(600);
    while !v.bounds_table_complete() {
        assert!(Instant::now() < end, "no bounds table in 600 s");
        std::thread::sleep(Duration::from_millis(100));
    }
    // A frame planned from the finished table.
    v.move_light(0, 7.0, 30.0);
    until_shown(v, target);
}

fn bench(c: &mut Criterion) {
    let mut target = Offscreen::new(1500, 820).unwrap();
    let mut g = c.benchmark_group("viewer");
    g.sample_size(20);
    for name in ["heliar-tronnier", "nikon-zoom-short"] {
        let mut v = settled_viewer(name, &mut target);
        let short = if name.starts_with("nikon") {
            "nikon"
        } else {
            "heliar"
        };
        g.bench_function(format!("ui_layout/{short}"), |b| {
            b.iter(|| target.pass_unpainted(&mut v, Vec::new()))
        });
        g.bench_function(format!("ui_pass/{short}"), |b| {
            b.iter(|| target.pass(&mut v, Vec::new()))
        });
        table_finished(&mut v, &mut target);
        let mut k = 0u32;
        g.bench_function(format!("drag_to_fast_frame/{short}"), |b| {
            b.iter(|| {
                k += 1;
                // Back and forth between two directions in the frame.
                let theta = if k.is_multiple_of(2) { 8.0 } else { 6.0 };
                v.move_light(0, theta, 30.0 + (k % 7) as f64);
                until_shown(&mut v, &mut target);
            })
        });
        let f = v.frame_shown().unwrap();
        eprintln!(
            "{short}: last drag frame: plan {:.1} ms (bounds from the table: {}), ghosts {:.1} ms, \
             tone {:.1} ms, total {:.1} ms",
            f.stats.plan_ms,
            f.stats.bounds_from_table,
            f.stats.ghosts_ms,
            f.stats.tone_ms,
            f.stats.total_ms
        );
        if short == "nikon" {
            let base = v.system().clone();
            let mut edited = base.clone();
            edited.surfaces[0].curvature *= 1.02;
            let systems = [Arc::new(base.clone()), Arc::new(edited)];
            g.bench_function("lens_rebuild/nikon", |b| {
                b.iter(|| {
                    let d = LensDrawing::new(&base);
                    let f = lens_drawing::standard_fields(&base).unwrap();
                    let fans = lens_drawing::ray_fans(&base, &f, &[587.56], 7);
                    (d, fans, enumerate_ghosts(&base))
                })
            });
            let mut rev = 0;
            g.bench_function("edit_to_fast_frame/nikon", |b| {
                b.iter(|| {
                    rev += 1;
                    v.set_system(Arc::clone(&systems[rev as usize % 2]), rev);
                    until_shown(&mut v, &mut target);
                })
            });
            let f = v.frame_shown().unwrap();
            eprintln!(
                "nikon: last edit frame: plan {:.1} ms (bounds from the table of the lens before \
                 the edit: {}), ghosts {:.1} ms, tone {:.1} ms, total {:.1} ms",
                f.stats.plan_ms,
                f.stats.bounds_from_previous_lens,
                f.stats.ghosts_ms,
                f.stats.tone_ms,
                f.stats.total_ms
            );
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

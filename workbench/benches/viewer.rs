//! The viewer window's reaction times (the viewer issue's targets), measured on the same code
//! the window runs, drawn offscreen (egui-wgpu on whatever adapter there is; lavapipe here):
//!
//! - `ui_pass/{heliar,nikon}`: one UI pass with nothing new to render — the lens view, the
//!   flare image, panels and status tessellated and painted at 1500 × 820 (target ≤ 16 ms);
//! - `lens_rebuild/nikon`: the lens drawing, three ray fans and the ghost list rebuilt after an
//!   edit (the UI thread's share of an edit);
//! - `edit_to_fast_frame/nikon`: an edit arriving through the document channel until the
//!   window shows the new lens and its fast flare at 960 × 540 (target ≤ 100 ms);
//! - `drag_to_fast_frame/{heliar,nikon}`: a light moved until its fast frame is shown
//!   (targets ≤ 50 ms and ≤ 100 ms).
//!
//! The flare is rendered by the CPU backend (`--backend cpu`; `auto` on a machine without a
//! hardware GPU). Run: `cargo bench -p flarebench --bench viewer`.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flarebench::backend::BackendChoice;
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

fn wait_shown(v: &mut Viewer, target: &mut Offscreen) {
    assert!(
        target.settle(v, Duration::from_secs(600)),
        "{:?}",
        v.message()
    );
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
        g.bench_function(format!("ui_pass/{short}"), |b| {
            b.iter(|| target.pass(&mut v, Vec::new()))
        });
        let mut k = 0u32;
        g.bench_function(format!("drag_to_fast_frame/{short}"), |b| {
            b.iter(|| {
                k += 1;
                // Back and forth between two directions in the frame.
                let theta = if k.is_multiple_of(2) { 8.0 } else { 6.0 };
                v.move_light(0, theta, 30.0 + (k % 7) as f64);
                wait_shown(&mut v, &mut target);
            })
        });
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
                    wait_shown(&mut v, &mut target);
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! The plugin boundary's cost: one render of the Heliar (light at 8°, 640×360, quality fast)
//! called directly (`plan::plan` + `ghosts::render`, as `flarebench render` does) against the
//! same render through the loaded plugin library (`host::load` →
//! `PluginInstance::render_into`: scene conversion, clearing the host's reused buffer, the
//! thunk's checks, the plugin rendering straight into that buffer, the NaN scan). Needs the release library first:
//!
//! ```sh
//! cargo build --release -p flarebench-ghost-raytrace -p flarebench-test-plugin-faulty
//! cargo bench -p flarebench-ghost-raytrace --bench plugin_overhead
//! ```

use std::path::Path;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use flarebench_sdk::abi::author::Scene;
use flarebench_sdk::abi::host;
use flarebench_sdk::abi::params::parse_values;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use flarebench_test_support::{build_dir, library_file_name};
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

fn bench(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../lenses/heliar-tronnier.xml"
    );
    let sys = read_lens(Path::new(path)).unwrap().system;
    let (w, h) = (640, 360);
    let frame = Frame {
        width: w,
        height: h,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * h as f64 / w as f64,
    };
    let light = LightSpec::parse("8,30").unwrap();
    let aperture = Aperture::Circular;

    let dir = build_dir();
    let lib = dir.join(library_file_name("ghost_raytrace"));
    let plugin = host::load(&lib).unwrap_or_else(|e| {
        panic!("{e}\n(run `cargo build --release -p flarebench-ghost-raytrace` first)")
    });
    let mut inst = plugin.instantiate().unwrap();
    inst.prepare(&sys).unwrap();
    let values = parse_values(&plugin.params, "quality=fast").unwrap();
    let scene = Scene {
        lights: vec![light.scene_light()],
        frame,
        aperture: aperture.clone(),
    };

    let mut g = c.benchmark_group("heliar_8deg_640x360_fast");
    g.sample_size(20);
    g.bench_function("direct", |b| {
        b.iter(|| {
            let opts = PlanOptions::for_quality(Quality::Fast, None);
            let plans = plan::plan(&sys, std::slice::from_ref(&light), &frame, &opts).unwrap();
            let (img, _) = ghosts::render(&sys, &aperture, frame, &plans).unwrap();
            assert!(!img.has_non_finite());
            img
        })
    });
    // A host rendering frame after frame keeps its buffer (`render_into`).
    let mut buffer = HdrImage::new(0, 0);
    g.bench_function("plugin", |b| {
        b.iter(|| inst.render_into(&scene, &values, &mut buffer).unwrap())
    });
    g.finish();

    drop(inst);

    // The boundary alone, with the test plugin that only adds a constant to every pixel
    // (`tests/plugins/faulty`, `level=0`): scene conversion, the host's zeroed image, the
    // thunk's checks, one pass over the pixels, the NaN scan — an upper bound on what the
    // boundary adds to any render of that size.
    let faulty = dir.join(library_file_name("flarebench_test_plugin_faulty"));
    match host::load(&faulty) {
        Ok(p) => {
            let mut inst = p.instantiate().unwrap();
            inst.prepare(&sys).unwrap();
            let values = parse_values(&p.params, "level=0").unwrap();
            for (w, h) in [(640, 360), (1920, 1080)] {
                let mut s = scene.clone();
                s.frame = Frame {
                    width: w,
                    height: h,
                    film_width_mm: sys.film_width_mm,
                    film_height_mm: sys.film_width_mm * h as f64 / w as f64,
                };
                let mut buffer = HdrImage::new(0, 0);
                c.bench_function(&format!("boundary_only_{w}x{h}"), |b| {
                    b.iter(|| inst.render_into(&s, &values, &mut buffer).unwrap())
                });
            }
        }
        Err(e) => eprintln!(
            "skipping boundary_only: {e} (cargo build --release -p flarebench-test-plugin-faulty)"
        ),
    }
    for (size, quality, pairs) in [
        ((640, 360), Quality::Fast, 41),
        ((1920, 1080), Quality::Default, 9),
    ] {
        paired(&sys, &light, size, quality, pairs, &plugin);
    }
}

/// On a shared, loaded machine the two criterion figures drift by more than the effect
/// measured; alternating the two calls and taking the median of the per-pair ratios cancels the
/// drift.
fn paired(
    sys: &flarebench_sdk::LensSystem,
    light: &LightSpec,
    (w, h): (usize, usize),
    quality: Quality,
    pairs: usize,
    plugin: &host::LoadedPlugin,
) {
    let frame = Frame {
        width: w,
        height: h,
        film_width_mm: sys.film_width_mm,
        film_height_mm: sys.film_width_mm * h as f64 / w as f64,
    };
    let aperture = Aperture::Circular;
    let mut inst = plugin.instantiate().unwrap();
    inst.prepare(sys).unwrap();
    let values = parse_values(&plugin.params, &format!("quality={}", quality.name())).unwrap();
    let scene = Scene {
        lights: vec![light.scene_light()],
        frame,
        aperture: aperture.clone(),
    };
    let mut direct = Vec::with_capacity(pairs);
    let mut through = Vec::with_capacity(pairs);
    let mut ratios = Vec::with_capacity(pairs);
    let mut buffer = HdrImage::new(0, 0);
    let run_direct = || {
        let t = Instant::now();
        let opts = PlanOptions::for_quality(quality, None);
        let plans = plan::plan(sys, std::slice::from_ref(light), &frame, &opts).unwrap();
        let (img, _) = ghosts::render(sys, &aperture, frame, &plans).unwrap();
        assert!(!img.has_non_finite());
        t.elapsed().as_secs_f64()
    };
    for i in 0..pairs {
        let mut run_plugin = || {
            let t = Instant::now();
            let out = inst.render_into(&scene, &values, &mut buffer).unwrap();
            std::hint::black_box((out, &buffer));
            t.elapsed().as_secs_f64()
        };
        // Alternate which goes first.
        let (d, p) = if i % 2 == 0 {
            let d = run_direct();
            (d, run_plugin())
        } else {
            let p = run_plugin();
            (run_direct(), p)
        };
        direct.push(d);
        through.push(p);
        ratios.push(p / d);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{w}x{h} {quality}, {pairs} alternating pairs: direct median {:.2} ms, plugin median {:.2} ms, median plugin/direct ratio {:.4}",
        median(&mut direct) * 1e3,
        median(&mut through) * 1e3,
        median(&mut ratios)
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);

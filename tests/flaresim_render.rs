//! Slow tier: every lens of FlareSim's library that loads (`tests/data/flaresim-lenses/`,
//! `sdk/tests/flaresim_corpus.rs` for the loading) renders its ghosts at 320 × 180, fast
//! quality, light at 10°, 30° (as `flarebench render LENS --size 320x180 --quality fast
//! --light 10,30` draws them), without a panic or an error and with a finite image.
//!
//! The library is split in four parts, one test each, so that a part can be run on its own
//! (`cargo test -p flarebench-tests --test workspace -- --ignored flaresim_render::part_1`); one after the
//! other, the four took 780 s on the 2-core machine of `docs/lenses.md` under a load average of
//! 7–8 (167–215 s each).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use flarebench_sdk::Frame;
use flarebench_sdk::aperture::Aperture;
use flarebench_test_support::{flaresim_library_files, read_flaresim_library_file};
use ghost_raytrace::ghosts;
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// The parts the library is rendered in.
const PARTS: usize = 4;

/// Renders every loaded lens whose index in the sorted library is `part` modulo [`PARTS`];
/// panics listing every lens that panicked, failed or gave a non-finite pixel.
fn render_part(part: usize) {
    let lights = [LightSpec::parse("10,30").expect("a valid light")];
    let options = PlanOptions::for_quality(Quality::Fast, None);
    let mut rendered = 0;
    let mut failures = Vec::new();
    // Seconds per lens, printed for docs/lenses.md (never asserted).
    let mut seconds: Vec<(f64, String)> = Vec::new();
    for path in flaresim_library_files().iter().skip(part).step_by(PARTS) {
        let Ok(lens) = read_flaresim_library_file(path, false) else {
            continue;
        };
        let sys = lens.system;
        let frame = Frame::across_film(320, 180, sys.film_width_mm);
        let start = Instant::now();
        let run = catch_unwind(AssertUnwindSafe(|| {
            let plans = plan::plan(&sys, &lights, &frame, &options)?;
            ghosts::render(&sys, &Aperture::Circular, frame, &plans).map(|(image, _)| image)
        }));
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        seconds.push((start.elapsed().as_secs_f64(), name.to_string()));
        match run {
            Err(_) => failures.push(format!("{name}: panicked")),
            Ok(Err(e)) => failures.push(format!("{name}: {e}")),
            Ok(Ok(image)) if image.has_non_finite() => {
                failures.push(format!("{name}: non-finite pixels"))
            }
            Ok(Ok(_)) => rendered += 1,
        }
    }
    seconds.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((slowest, name)) = seconds.last() {
        eprintln!(
            "part {}: {rendered} lenses rendered, median {:.3} s, slowest {slowest:.3} s ({name})",
            part + 1,
            seconds[seconds.len() / 2].0
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(rendered > 0);
}

#[test]
#[ignore = "slow tier: renders a quarter of FlareSim's 1,254 loadable lenses (minutes)"]
fn flaresim_library_renders_finite_part_1() {
    render_part(0);
}

#[test]
#[ignore = "slow tier: renders a quarter of FlareSim's 1,254 loadable lenses (minutes)"]
fn flaresim_library_renders_finite_part_2() {
    render_part(1);
}

#[test]
#[ignore = "slow tier: renders a quarter of FlareSim's 1,254 loadable lenses (minutes)"]
fn flaresim_library_renders_finite_part_3() {
    render_part(2);
}

#[test]
#[ignore = "slow tier: renders a quarter of FlareSim's 1,254 loadable lenses (minutes)"]
fn flaresim_library_renders_finite_part_4() {
    render_part(3);
}

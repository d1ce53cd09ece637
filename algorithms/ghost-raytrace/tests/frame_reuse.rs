//! A frame buffer and coarse frames kept from frame to frame (`ghosts::render_into_reusing`,
//! `RenderOptions::replace`) give the image a fresh render gives, bit for bit, whatever they
//! held.

use std::path::Path;

use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::read_lens;
use ghost_raytrace::ghosts::{self, RenderOptions, RenderScratch};
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Luminance of a frame drawn twice into one buffer over the frame drawn once, against 2:
/// f32 accumulation in the pixels.
const ACCUMULATED_RATIO_TOL: f64 = 1e-5;

fn heliar() -> LensSystem {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../lenses/heliar-tronnier.xml"
    );
    read_lens(Path::new(path)).unwrap().system
}

#[test]
fn a_kept_buffer_replaced_frame_after_frame_holds_each_frame_alone() {
    let sys = heliar();
    let frame = Frame::across_film(320, 180, sys.film_width_mm);
    let aperture = Aperture::Circular;
    let opts = PlanOptions::for_quality(Quality::Default, None);
    let plan_of =
        |light: &str| plan::plan(&sys, &[LightSpec::parse(light).unwrap()], &frame, &opts).unwrap();
    // Two lights whose ghosts land elsewhere and at several coarse factors, each including
    // full resolution (drawn after the upsampling pass) and coarse ones.
    let scenes = [plan_of("10,30"), plan_of("4,200"), plan_of("10,30")];
    for plans in &scenes {
        let factors: Vec<usize> = plans[0].ghosts.iter().map(|j| j.downscale).collect();
        assert!(factors.contains(&1), "{factors:?}");
        assert!(factors.iter().any(|&f| f > 1), "{factors:?}");
    }
    let mut scratch = RenderScratch::default();
    let mut kept = HdrImage::new(frame.width, frame.height);
    kept.pixels.fill([3.0, f32::NAN, -1.0]);
    let replace = RenderOptions {
        replace: true,
        ..Default::default()
    };
    for plans in &scenes {
        let (alone, _) = ghosts::render(&sys, &aperture, frame, plans).unwrap();
        assert!(alone.luminance_sum() > 0.0);
        ghosts::render_into_reusing(
            &sys,
            &aperture,
            frame,
            plans,
            replace,
            &mut scratch,
            &mut kept.pixels,
        )
        .unwrap();
        assert!(!kept.has_non_finite());
        // The same image, bit for bit: each mesh is rasterized in plan order, whatever the
        // threads.
        assert!(kept.pixels == alone.pixels, "the kept buffer differs");
    }
    // Adding (the default) keeps what the buffer held.
    let mut twice = HdrImage::new(frame.width, frame.height);
    for _ in 0..2 {
        ghosts::render_into_reusing(
            &sys,
            &aperture,
            frame,
            &scenes[0],
            RenderOptions::default(),
            &mut scratch,
            &mut twice.pixels,
        )
        .unwrap();
    }
    let (once, _) = ghosts::render(&sys, &aperture, frame, &scenes[0]).unwrap();
    let ratio = twice.luminance_sum() / once.luminance_sum();
    assert!((ratio - 2.0).abs() < ACCUMULATED_RATIO_TOL, "{ratio}");
}

#[test]
fn replacing_covers_two_lights_only_full_resolution_and_no_ghosts() {
    let sys = heliar();
    let frame = Frame::across_film(240, 135, sys.film_width_mm);
    let aperture = Aperture::Circular;
    let lights = [
        LightSpec::parse("10,30").unwrap(),
        LightSpec::parse("6,200,0.5").unwrap(),
    ];
    let preset = PlanOptions::for_quality(Quality::Default, None);
    let full_only = PlanOptions {
        max_downscale: 1,
        ..preset
    };
    let mut scratch = RenderScratch::default();
    let mut kept = HdrImage::new(frame.width, frame.height);
    let replace = RenderOptions {
        replace: true,
        ..Default::default()
    };
    for opts in [preset, full_only] {
        let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
        assert_eq!(plans.len(), 2);
        let (alone, stats) = ghosts::render(&sys, &aperture, frame, &plans).unwrap();
        kept.pixels.fill([f32::NAN, 5.0, -2.0]);
        let kept_stats = ghosts::render_into_reusing(
            &sys,
            &aperture,
            frame,
            &plans,
            replace,
            &mut scratch,
            &mut kept.pixels,
        )
        .unwrap();
        // The same image, bit for bit: each mesh is rasterized in plan order, whatever the
        // threads.
        assert!(kept.pixels == alone.pixels, "the kept buffer differs");
        // Each light's ghosts' statistics in plan order, whichever group drew them: every
        // band of a ghost traces its whole grid.
        for (lp, (s, t)) in plans.iter().zip(stats.iter().zip(&kept_stats)) {
            assert_eq!(s.len(), lp.ghosts.len());
            for (job, (a, b)) in lp.ghosts.iter().zip(s.iter().zip(t)) {
                assert_eq!(a.rays, job.grid * job.grid * job.bands.len());
                assert_eq!((a.rays, a.triangles), (b.rays, b.triangles));
            }
        }
    }
    // No ghosts at all: the buffer is made black.
    let mut empty = plan::plan(&sys, &lights[..1], &frame, &preset).unwrap();
    empty[0].ghosts.clear();
    kept.pixels.fill([1.0, f32::NAN, 3.0]);
    ghosts::render_into_reusing(
        &sys,
        &aperture,
        frame,
        &empty,
        replace,
        &mut scratch,
        &mut kept.pixels,
    )
    .unwrap();
    assert_eq!(kept, HdrImage::new(frame.width, frame.height));
}

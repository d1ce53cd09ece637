//! The default preset draws smooth ghosts (bounds' grid up to `plan::SMOOTH_GRID`) with
//! fewer triangles, and every other ghost with its bounds' grid.

use flarebench_sdk::frame::Frame;
use flarebench_test_support::load_lens;
use ghost_raytrace::plan::{self, PlanOptions, SMOOTH_GRID};
use ghost_raytrace::scene::{LightSpec, Quality};

#[test]
fn smooth_ghosts_take_three_quarters_of_their_grid() {
    assert_eq!(Quality::Default.smooth_grid_scale(), 0.75);
    let (mut smooth, mut other) = (0, 0);
    for lens in ["heliar-tronnier", "nikon-zoom-short"] {
        let sys = load_lens(lens);
        let frame = Frame::across_film(480, 270, sys.film_width_mm);
        let lights = [LightSpec::parse("10,30").unwrap()];
        let preset = PlanOptions::for_quality(Quality::Default, None);
        let whole = PlanOptions {
            smooth_grid_scale: 1.0,
            ..preset
        };
        let a = &plan::plan(&sys, &lights, &frame, &preset).unwrap()[0];
        let b = &plan::plan(&sys, &lights, &frame, &whole).unwrap()[0];
        assert_eq!(a.ghosts.len(), b.ghosts.len());
        for (g, w) in a.ghosts.iter().zip(&b.ghosts) {
            assert_eq!(g.path, w.path);
            if w.grid <= SMOOTH_GRID {
                assert_eq!(g.grid, (w.grid as f64 * 0.75).round() as usize, "{lens}");
                smooth += 1;
            } else {
                assert_eq!(g.grid, w.grid, "{lens}");
                other += 1;
            }
        }
    }
    assert!(
        smooth > 0 && other > 0,
        "{smooth} smooth, {other} other ghosts"
    );
}

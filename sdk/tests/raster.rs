//! Energy conservation of the rasterizer over random triangles (proptest): for a constant
//! shade `c`, the image gains `c × (area of the triangle inside the image)`.
//!
//! The expected area is computed here independently: the shoelace formula for a triangle inside
//! the image, and a plain `Vec`-based clip of the triangle to the image rectangle otherwise.

use flarebench_sdk::image::HdrImage;
use flarebench_sdk::raster::rasterize;
use proptest::prelude::*;

/// 150 × 100 pixels: three tile columns and two tile rows, the last ones partial.
const W: usize = 150;
const H: usize = 100;

/// Relative tolerance on the image sum: each pixel holds an f32 sum of exact f64 areas, so the
/// total is off by about an f32 ulp (6e-8) of the total; measured: below 1e-7 in every case,
/// 1e-8 fails.
const REL_TOL: f64 = 1e-6;
/// Absolute floor for tiny triangles (an area of 1e-6 px² rounds to ~1e-13 in a pixel).
const ABS_TOL: f64 = 1e-9;
/// A pixel's value over the shade it was drawn with (coverage at most 1): f32 rounding of the
/// pixel's sum of areas.
const PIXEL_REL_TOL: f32 = 1e-6;
/// The clipped area of a triangle wholly inside the image against its closed form (px²): f64
/// rounding.
const AREA_TOL: f64 = 1e-9;

fn shoelace(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        .abs()
        * 0.5
}

/// Area of the triangle inside [0, W] × [0, H]: clip to each of the four half-planes.
fn area_inside(t: [[f32; 2]; 3]) -> f64 {
    let mut poly: Vec<[f64; 2]> = t
        .iter()
        .map(|p| [f64::from(p[0]), f64::from(p[1])])
        .collect();
    // (axis, bound, keep >= bound?)
    for (axis, bound, above) in [
        (0, 0.0, true),
        (0, W as f64, false),
        (1, 0.0, true),
        (1, H as f64, false),
    ] {
        let inside = |p: &[f64; 2]| {
            if above {
                p[axis] >= bound
            } else {
                p[axis] <= bound
            }
        };
        let mut out = Vec::new();
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            if inside(&a) {
                out.push(a);
            }
            if inside(&a) != inside(&b) {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        poly = out;
        if poly.is_empty() {
            return 0.0;
        }
    }
    shoelace(&poly)
}

fn render(tris: &[[[f32; 2]; 3]], c: f32) -> HdrImage {
    let positions: Vec<[f32; 2]> = tris.iter().flatten().copied().collect();
    let attrs = vec![[c]; positions.len()];
    let indices: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mut img = HdrImage::new(W, H);
    rasterize(&mut img, &positions, &attrs, &indices, |a| {
        [a[0], 2.0 * a[0], 0.0]
    });
    img
}

fn point(lo: f32, hi: f32) -> impl Strategy<Value = [f32; 2]> {
    (lo..hi, lo..hi).prop_map(|(x, y)| [x, y])
}

/// Triangles of every kind: ordinary, around and past the image border, tiny, huge, degenerate.
fn triangle() -> impl Strategy<Value = [[f32; 2]; 3]> {
    prop_oneof![
        // Ordinary, mostly on screen, often crossing the border.
        [
            point(-60.0, 210.0),
            point(-60.0, 210.0),
            point(-60.0, 210.0)
        ],
        // Tiny: within a hundredth of a pixel.
        (point(-1.0, 151.0), point(0.0, 0.01), point(0.0, 0.01)).prop_map(|(p, a, b)| [
            p,
            [p[0] + a[0], p[1] + a[1]],
            [p[0] + b[0], p[1] - b[1]]
        ]),
        // Small, a few pixels.
        (point(-5.0, 155.0), point(-3.0, 3.0), point(-3.0, 3.0)).prop_map(|(p, a, b)| [
            p,
            [p[0] + a[0], p[1] + a[1]],
            [p[0] + b[0], p[1] + b[1]]
        ]),
        // Huge: vertices up to 1e5 pixels away.
        [point(-1e5, 1e5), point(-1e5, 1e5), point(-1e5, 1e5)],
        // Off screen entirely.
        [
            point(200.0, 400.0),
            point(200.0, 400.0),
            point(200.0, 400.0)
        ],
        // Degenerate: the third vertex on the line through the first two, or repeated.
        (point(-20.0, 170.0), point(-20.0, 170.0), -2.0_f32..3.0).prop_map(|(a, b, t)| [
            a,
            b,
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        ]),
        (point(-20.0, 170.0), point(-20.0, 170.0)).prop_map(|(a, b)| [a, b, a]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// One triangle: image sum = c × area inside the image; no pixel gets more than c; the
    /// green channel (shade 2c) is exactly twice the red.
    #[test]
    fn one_triangle_adds_exactly_its_area_inside_the_image(t in triangle(), c in 0.1_f32..10.0) {
        let img = render(&[t], c);
        prop_assert!(!img.has_non_finite());
        let want = f64::from(c) * area_inside(t);
        let [r, g, b] = img.sum();
        prop_assert!((r - want).abs() <= REL_TOL * want + ABS_TOL, "sum {r} vs {want} for {t:?}");
        prop_assert!((g - 2.0 * r).abs() <= REL_TOL * r + ABS_TOL);
        prop_assert_eq!(b, 0.0);
        prop_assert!(img.max() <= 2.0 * c * (1.0 + PIXEL_REL_TOL) || img.max() == f32::NEG_INFINITY);
        prop_assert!(img.pixels.iter().all(|p| p[0] >= 0.0 && p[0] <= c * (1.0 + PIXEL_REL_TOL)));
    }

    /// Many triangles of every kind in one call: the sums add up.
    #[test]
    fn many_triangles_add_up(ts in prop::collection::vec(triangle(), 1..60), c in 0.1_f32..10.0) {
        let img = render(&ts, c);
        prop_assert!(!img.has_non_finite());
        let want: f64 = ts.iter().map(|&t| f64::from(c) * area_inside(t)).sum();
        let r = img.sum()[0];
        prop_assert!((r - want).abs() <= REL_TOL * want + ABS_TOL, "sum {r} vs {want}");
    }

    /// A triangle wholly inside the image: its shoelace area, with no clipping anywhere.
    #[test]
    fn an_inside_triangle_adds_its_shoelace_area(t in [point(0.0, 100.0), point(0.0, 100.0), point(0.0, 100.0)]) {
        let img = render(&[t], 1.0);
        let p: Vec<[f64; 2]> = t.iter().map(|q| [f64::from(q[0]), f64::from(q[1])]).collect();
        let want = shoelace(&p);
        let r = img.sum()[0];
        prop_assert!((r - want).abs() <= REL_TOL * want + ABS_TOL, "sum {r} vs {want}");
    }
}

/// The test catches an error: dropping one pixel's worth (a unit square) is detected.
#[test]
fn the_area_check_detects_a_missing_pixel() {
    let t = [[10.0, 10.0], [60.0, 10.0], [10.0, 60.0]];
    let want = area_inside(t);
    assert!((want - 1250.0).abs() < AREA_TOL);
    let r = render(&[t], 1.0).sum()[0] - 1.0;
    assert!((r - want).abs() > REL_TOL * want + ABS_TOL);
}

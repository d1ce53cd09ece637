//! Hand-computed coverage, attribute interpolation, robustness and determinism of the
//! rasterizer. The energy property over random triangles is in `sdk/tests/raster.rs`.

use super::*;

/// Per-pixel tolerance: an f32 pixel holding a sum of a few exact f64 areas.
const PIXEL_TOL: f32 = 1e-6;

fn draw(img: &mut HdrImage, pts: &[[f32; 2]], tris: &[[u32; 3]], c: [f32; 3]) {
    let attrs = vec![[0.0_f32; 0]; pts.len()];
    rasterize(img, pts, &attrs, tris, |_| c);
}

fn red(img: &HdrImage) -> Vec<f32> {
    img.pixels.iter().map(|p| p[0]).collect()
}

fn close(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= PIXEL_TOL)
}

#[test]
fn a_unit_square_on_a_pixel_fills_exactly_that_pixel() {
    let mut img = HdrImage::new(4, 5);
    let pts = [[2.0, 3.0], [3.0, 3.0], [3.0, 4.0], [2.0, 4.0]];
    draw(&mut img, &pts, &[[0, 1, 2], [0, 2, 3]], [2.0, 3.0, 4.0]);
    for y in 0..5 {
        for x in 0..4 {
            let want = if (x, y) == (2, 3) {
                [2.0, 3.0, 4.0]
            } else {
                [0.0; 3]
            };
            let got = img.get(x, y).unwrap();
            assert!(
                (0..3).all(|c| (got[c] - want[c]).abs() <= PIXEL_TOL),
                "({x},{y}) {got:?}"
            );
        }
    }
}

#[test]
fn a_half_pixel_triangle_covers_half_a_pixel() {
    let mut img = HdrImage::new(2, 2);
    draw(
        &mut img,
        &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        &[[0, 1, 2]],
        [1.0; 3],
    );
    assert!(close(&red(&img), &[0.5, 0.0, 0.0, 0.0]), "{:?}", red(&img));
}

/// The rectangle [0.5, 2.5] × [0.25, 1] covers 0.375, 0.75, 0.375 of pixels 0, 1, 2 of row 0.
#[test]
fn a_rectangle_across_pixel_edges_gives_fractional_coverage() {
    let mut img = HdrImage::new(4, 2);
    let pts = [[0.5, 0.25], [2.5, 0.25], [2.5, 1.0], [0.5, 1.0]];
    draw(&mut img, &pts, &[[0, 1, 2], [2, 3, 0]], [1.0; 3]);
    assert!(
        close(&red(&img), &[0.375, 0.75, 0.375, 0.0, 0.0, 0.0, 0.0, 0.0]),
        "{:?}",
        red(&img)
    );
}

/// A triangle with its hypotenuse through pixel corners: pixels on the diagonal are half
/// covered, those below it fully (right isosceles triangle of legs 3: area 4.5).
#[test]
fn a_diagonal_edge_halves_the_pixels_it_crosses() {
    let mut img = HdrImage::new(3, 3);
    draw(
        &mut img,
        &[[0.0, 0.0], [0.0, 3.0], [3.0, 3.0]],
        &[[0, 1, 2]],
        [1.0; 3],
    );
    let want = [0.5, 0.0, 0.0, 1.0, 0.5, 0.0, 1.0, 1.0, 0.5];
    assert!(close(&red(&img), &want), "{:?}", red(&img));
}

/// Two triangles covering the image exactly (150 × 70: three tile columns, two tile rows,
/// partial tiles at the edges) give every pixel exactly the colour.
#[test]
fn a_full_screen_quad_covers_every_pixel_once() {
    let (w, h) = (150, 70);
    let mut img = HdrImage::new(w, h);
    let (fw, fh) = (w as f32, h as f32);
    draw(
        &mut img,
        &[[0.0, 0.0], [fw, 0.0], [fw, fh], [0.0, fh]],
        &[[0, 1, 2], [0, 2, 3]],
        [0.25, 0.5, 1.0],
    );
    for p in &img.pixels {
        assert!(
            (p[0] - 0.25).abs() <= PIXEL_TOL && (p[2] - 1.0).abs() <= PIXEL_TOL,
            "{p:?}"
        );
    }
}

/// A triangle a million pixels across, enclosing the image, covers every pixel exactly once.
#[test]
fn a_huge_triangle_covers_every_pixel_once() {
    let mut img = HdrImage::new(100, 80);
    draw(
        &mut img,
        &[[-1.0e6, -1.0e6], [3.0e6, -1.0e6], [-1.0e6, 3.0e6]],
        &[[0, 1, 2]],
        [1.0; 3],
    );
    assert!(img.pixels.iter().all(|p| (p[0] - 1.0).abs() <= PIXEL_TOL));
}

/// With `shade = attribute` and the attribute equal to x at the vertices, each pixel receives
/// ∫ x dA over its covered piece: for a fully covered pixel, its centre's x.
#[test]
fn attributes_are_interpolated_linearly() {
    let mut img = HdrImage::new(8, 8);
    let pts = [[0.0, 0.0], [8.0, 0.0], [8.0, 8.0], [0.0, 8.0]];
    let attrs: Vec<[f32; 2]> = pts.iter().map(|p| [p[0], 2.0 * p[1] + 1.0]).collect();
    rasterize(&mut img, &pts, &attrs, &[[0, 1, 2], [0, 2, 3]], |a| {
        [a[0], a[1], 1.0]
    });
    for y in 0..8 {
        for x in 0..8 {
            let p = img.get(x, y).unwrap();
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            assert!((p[0] - cx).abs() < 1e-5, "({x},{y}) {p:?}");
            assert!((p[1] - (2.0 * cy + 1.0)).abs() < 1e-5, "({x},{y}) {p:?}");
        }
    }
    // A triangle cut by pixel edges: Σ over pixels of area × x = area × centroid x exactly.
    let mut img = HdrImage::new(8, 8);
    let pts = [[0.3, 0.7], [7.1, 2.2], [2.6, 6.9]];
    let attrs: Vec<[f32; 1]> = pts.iter().map(|p| [p[0]]).collect();
    rasterize(&mut img, &pts, &attrs, &[[0, 1, 2]], |a| [a[0], 1.0, 0.0]);
    let [sx, area, _] = img.sum();
    let want_area = 0.5 * ((7.1 - 0.3) * (6.9 - 0.7) - (2.6 - 0.3) * (2.2 - 0.7_f64)).abs();
    let want_cx = (0.3 + 7.1 + 2.6) / 3.0;
    assert!(
        (area - want_area).abs() < 1e-5 * want_area,
        "{area} vs {want_area}"
    );
    assert!((sx - want_area * want_cx).abs() < 1e-5 * sx, "{sx}");
}

#[test]
fn degenerate_invalid_and_off_screen_triangles_add_nothing() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let pts = [
        [1.0, 1.0],
        [2.0, 2.0],
        [3.0, 3.0], // collinear with the two before
        [nan, 2.0],
        [inf, 1.0],
        [-50.0, -50.0],
        [-40.0, -50.0],
        [-40.0, -40.0],
        [5.0, 1.0],
    ];
    let attrs: Vec<[f32; 1]> = (0..pts.len())
        .map(|i| [if i == 8 { nan } else { 1.0 }])
        .collect();
    let tris = [
        [0, 1, 2],  // collinear: zero area
        [0, 0, 1],  // repeated vertex
        [2, 2, 2],  // a point
        [0, 1, 3],  // NaN coordinate
        [0, 4, 1],  // infinite coordinate
        [5, 6, 7],  // off screen
        [0, 1, 99], // index out of range
        [0, 1, 8],  // NaN attribute
    ];
    let mut img = HdrImage::new(16, 16);
    rasterize(&mut img, &pts, &attrs, &tris, |a| [a[0]; 3]);
    assert!(!img.has_non_finite());
    assert_eq!(img.sum(), [0.0; 3]);
    // Attribute arrays shorter than the positions: the triangle is skipped.
    rasterize(&mut img, &pts, &attrs[..2], &[[0, 1, 8]], |a| [a[0]; 3]);
    assert_eq!(img.sum(), [0.0; 3]);
}

#[test]
fn empty_images_and_empty_meshes_are_fine() {
    let mut empty = HdrImage::new(0, 7);
    draw(
        &mut empty,
        &[[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]],
        &[[0, 1, 2]],
        [1.0; 3],
    );
    let mut img = HdrImage::new(3, 3);
    draw(&mut img, &[], &[], [1.0; 3]);
    assert_eq!(img.sum(), [0.0; 3]);
}

/// A bare pixel buffer is drawn exactly as the image holding it; a partial last row (a
/// buffer that is not whole rows) is left alone, as is a zero width.
#[test]
fn a_pixel_buffer_is_drawn_as_its_image() {
    let pts = [
        [1.3, 0.2],
        [9.7, 4.1],
        [2.2, 6.9],
        [0.0, 0.0],
        [70.0, 3.0],
        [3.0, 70.0],
    ];
    let tris = [[0, 1, 2], [3, 4, 5]];
    let attrs = vec![[0.0_f32; 0]; pts.len()];
    for coverage in [Coverage::Exact, Coverage::Sampled { min_area: 2.0 }] {
        let mut img = HdrImage::new(11, 7);
        rasterize_with(&mut img, &pts, &attrs, &tris, coverage, |_| [1.0, 2.0, 3.0]);
        let mut buf = vec![[0.0_f32; 3]; 11 * 7 + 4];
        rasterize_into(&mut buf, 11, &pts, &attrs, &tris, coverage, |_| {
            [1.0, 2.0, 3.0]
        });
        assert_eq!(&buf[..77], &img.pixels[..]);
        assert!(buf[77..].iter().all(|p| *p == [0.0; 3]));
        rasterize_into(&mut buf, 0, &pts, &attrs, &tris, coverage, |_| [1.0; 3]);
        assert_eq!(&buf[..77], &img.pixels[..]);
    }
}

/// Tiles add their triangles in input order, so the image is the same bit for bit on one
/// thread or many.
#[test]
fn the_result_does_not_depend_on_the_number_of_threads() {
    let (w, h) = (300, 200);
    let mut pts = Vec::new();
    let mut tris = Vec::new();
    // A fan of overlapping thin triangles across tiles.
    for k in 0..200_u32 {
        let a = k as f32 * 0.031;
        pts.push([150.0, 100.0]);
        pts.push([150.0 + 180.0 * a.cos(), 100.0 + 180.0 * a.sin()]);
        pts.push([
            150.0 + 170.0 * (a + 0.05).cos(),
            100.0 + 170.0 * (a + 0.05).sin(),
        ]);
        tris.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let attrs: Vec<[f32; 2]> = pts.iter().map(|p| [p[0] * 0.01, p[1] * 0.02]).collect();
    let render = || {
        let mut img = HdrImage::new(w, h);
        rasterize(&mut img, &pts, &attrs, &tris, |a| [a[0], a[1], 0.1]);
        img
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(render);
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap()
        .install(render);
    assert!(one.sum()[0] > 0.0);
    assert_eq!(one, many);
}

/// The winding does not matter.
#[test]
fn both_windings_give_the_same_image() {
    let pts = [[0.3, 0.4], [9.7, 2.1], [4.2, 7.7]];
    let mut a = HdrImage::new(10, 10);
    let mut b = HdrImage::new(10, 10);
    draw(&mut a, &pts, &[[0, 1, 2]], [1.0; 3]);
    draw(&mut b, &pts, &[[0, 2, 1]], [1.0; 3]);
    assert!(close(&red(&a), &red(&b)));
}

/// Against brute force: clip the triangle to every pixel square and take the piece's area and
/// centroid. With attributes (x, y) and shade (1, x, y), a pixel holds
/// (area, area · centroid x, area · centroid y).
#[test]
fn every_pixel_matches_clipping_the_triangle_to_it() {
    let (w, h) = (70, 40);
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut rnd = |lo: f32, hi: f32| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        lo + (hi - lo) * ((seed >> 40) as f32 / (1u64 << 24) as f32)
    };
    for case in 0..400 {
        // Tiny (often inside one pixel), small, medium and large triangles, some past the
        // borders.
        let size = [0.3, 2.0, 12.0, 90.0][case % 4];
        let (cx, cy) = (rnd(-5.0, 75.0), rnd(-5.0, 45.0));
        let pts: Vec<[f32; 2]> = (0..3)
            .map(|_| [cx + rnd(-size, size), cy + rnd(-size, size)])
            .collect();
        let mut img = HdrImage::new(w, h);
        rasterize(&mut img, &pts, &pts, &[[0, 1, 2]], |a| [1.0, a[0], a[1]]);
        let tri = Polygon::triangle(
            pts[0].map(f64::from),
            pts[1].map(f64::from),
            pts[2].map(f64::from),
        );
        let (mut col, mut px, mut tmp) = (Polygon::EMPTY, Polygon::EMPTY, Polygon::EMPTY);
        for y in 0..h {
            for x in 0..w {
                let (x0, y0) = (x as f64, y as f64);
                tri.clip_slab::<0>(x0, x0 + 1.0, &mut col, &mut tmp);
                col.clip_slab::<1>(y0, y0 + 1.0, &mut px, &mut tmp);
                let (area, c) = px.area_centroid([x0, y0]);
                let want = [area, area * c[0], area * c[1]];
                let got = img.get(x, y).unwrap();
                for k in 0..3 {
                    // f32 pixel values up to 70: a few ulps.
                    let tol = 2e-5 * (1.0 + want[k].abs());
                    assert!(
                        (f64::from(got[k]) - want[k]).abs() <= tol,
                        "case {case} pixel ({x},{y}) channel {k}: {got:?} vs {want:?}, {pts:?}"
                    );
                }
            }
        }
    }
}

/// A warped mesh of large triangles, point-sampled, covers every pixel centre inside it
/// exactly once (shared edges counted once: no gap, no double count), in any tile layout.
#[test]
fn sampled_coverage_of_a_closed_mesh_counts_every_pixel_centre_once() {
    let (w, h) = (150, 130);
    let n = 9;
    let mut pts = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (5.0 + i as f32 * 17.3, 3.0 + j as f32 * 15.1);
            // Irregular interior vertices, the outline left straight.
            let inner = i > 0 && i < n - 1 && j > 0 && j < n - 1;
            let d = if inner {
                ((i * 7 + j * 3) % 5) as f32 * 1.37 - 2.7
            } else {
                0.0
            };
            pts.push([x + d, y - 0.6 * d]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = (j * n + i) as u32;
            let n = n as u32;
            tris.push([k, k + 1, k + n + 1]);
            tris.push([k, k + n + 1, k + n]);
        }
    }
    let mut img = HdrImage::new(w, h);
    let attrs = vec![[0.0_f32; 0]; pts.len()];
    rasterize_with(
        &mut img,
        &pts,
        &attrs,
        &tris,
        Coverage::Sampled { min_area: 1.0 },
        |_| [1.0; 3],
    );
    let (x1, y1) = (5.0 + 8.0 * 17.3, 3.0 + 8.0 * 15.1);
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let inside = cx >= 5.0 && cx < x1 && cy >= 3.0 && cy < y1;
            let got = img.get(x, y).unwrap()[0];
            assert_eq!(got, if inside { 1.0 } else { 0.0 }, "pixel ({x}, {y})");
        }
    }
}

/// Triangles under `min_area` keep exact coverage; larger ones are sampled at pixel centres
/// with their attributes interpolated there.
#[test]
fn sampled_coverage_keeps_small_triangles_exact_and_samples_large_ones() {
    let mut img = HdrImage::new(2, 2);
    let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let attrs = vec![[0.0_f32; 0]; 3];
    let sampled = Coverage::Sampled { min_area: 1.0 };
    rasterize_with(&mut img, &pts, &attrs, &[[0, 1, 2]], sampled, |_| [1.0; 3]);
    assert!(close(&red(&img), &[0.5, 0.0, 0.0, 0.0]), "{:?}", red(&img));
    // A 4 × 4 half square: the centres strictly left of the diagonal (a right-hand edge
    // is exclusive); the attribute x is read at each centre.
    let mut img = HdrImage::new(4, 4);
    let pts = [[0.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
    let attrs: Vec<[f32; 1]> = pts.iter().map(|p| [p[0]]).collect();
    rasterize_with(&mut img, &pts, &attrs, &[[0, 1, 2]], sampled, |a| {
        [a[0], 0.0, 0.0]
    });
    for y in 0..4 {
        for x in 0..4 {
            let want = if x < y { x as f32 + 0.5 } else { 0.0 };
            let got = img.get(x, y).unwrap()[0];
            assert!((got - want).abs() < 1e-5, "({x},{y}) {got} vs {want}");
        }
    }
}

/// A shader's row split on sampled rows: pixels outside `lit` are skipped, those in `core`
/// take `shade_core`, the rest `shade` — each at the attributes of its own centre.
#[test]
fn a_shader_s_row_split_skips_and_cores_pixels() {
    struct Split;
    impl Shader<1> for Split {
        type Rows = ();
        fn shade(&self, a: &[f32; 1]) -> [f32; 3] {
            [a[0], 1.0, 0.0]
        }
        fn split_row(&self, _: &(), a: &[f32; 1], step: &[f32; 1], n: usize) -> RowSplit {
            // The attribute is x: lit from x = 2 on, core for 4 ≤ x < 6.
            assert_eq!(step[0], 1.0);
            let from = |x: f32| (x - (a[0] - 0.5)).max(0.0) as usize;
            RowSplit {
                lit: from(2.0)..n,
                core: from(4.0)..from(6.0),
            }
        }
        fn shade_core(&self, a: &[f32; 1]) -> [f32; 3] {
            [a[0], 2.0, 0.0]
        }
    }
    let (w, h) = (10, 4);
    let pts = [[0.0, 0.0], [10.0, 0.0], [10.0, 4.0], [0.0, 4.0]];
    let attrs: Vec<[f32; 1]> = pts.iter().map(|p| [p[0]]).collect();
    let mut img = HdrImage::new(w, h);
    let sampled = Coverage::Sampled { min_area: 1.0 };
    let tris = [[0, 1, 2], [0, 2, 3]];
    rasterize_shaded_into(&mut img.pixels, w, &pts, &attrs, &tris, sampled, &Split);
    for y in 0..h {
        for x in 0..w {
            let got = img.get(x, y).unwrap();
            let want = match x {
                0 | 1 => [0.0; 3],
                4 | 5 => [x as f32 + 0.5, 2.0, 0.0],
                _ => [x as f32 + 0.5, 1.0, 0.0],
            };
            assert!(
                (0..3).all(|c| (got[c] - want[c]).abs() < 1e-5),
                "({x},{y}) {got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn a_pixel_summing_millions_of_tiny_pieces_keeps_their_total() {
    // A 2 × 2-pixel square cut into 1000² cells of two triangles each (as a dense reference
    // grid draws a ghost): each pixel gains half a million pieces of 2e-6 px². Summed in f32
    // one by one, every piece would be rounded against the whole pixel (the sum drifts by a
    // percent); summed in f64 per tile, each pixel is within f32 rounding of its area.
    let n = 1000_u32;
    let side = 2.0_f64;
    let pts: Vec<[f32; 2]> = (0..=n)
        .flat_map(|j| {
            (0..=n).map(move |i| {
                let s = side / f64::from(n);
                [
                    (10.0 + f64::from(i) * s) as f32,
                    (20.0 + f64::from(j) * s) as f32,
                ]
            })
        })
        .collect();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let tris: Vec<[u32; 3]> = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .flat_map(|(i, j)| {
            [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ]
        })
        .collect();
    let mut img = HdrImage::new(40, 30);
    draw(&mut img, &pts, &tris, [0.3, 1.0, 3.0]);
    for (x, y) in [(10, 20), (11, 20), (10, 21), (11, 21)] {
        let px = img.pixels[y * 40 + x];
        for (got, want) in px.iter().zip([0.3_f32, 1.0, 3.0]) {
            assert!(
                ((got - want) / want).abs() < 1e-5,
                "pixel ({x}, {y}): {got} for {want}"
            );
        }
    }
    let total: f64 = img.pixels.iter().map(|p| f64::from(p[1])).sum();
    assert!((total - 4.0).abs() < 4e-5, "total {total}");
}

//! A ghost's smallest triangles drawn as box splats (`crate::raster::boxes`) instead of with
//! exact coverage.
//!
//! Where a ghost's grid lands in cells far smaller than a pixel (a near-focus ghost), exact
//! coverage clips every triangle against the pixels it touches: most of such a ghost's time.
//! A splatted ghost's triangle under [`SPLAT_MAX_AREA`] pixels² is added as one axis-aligned
//! box of its area at its centroid, shaded there, its aspect that of the triangle's second
//! moments along x and y. The triangle's energy is kept exactly (for a shade affine in the
//! attributes, as an open triangle's is, the centroid's shade times the area is its integral);
//! what moves is how the light of a triangle that crosses a pixel border is shared between
//! the pixels, by up to the triangle's size. Larger triangles keep the rasterizer's coverage:
//! boxes of a pixel or more (tried, cut from larger triangles) put a moiré of 5–30% on the
//! ghosts they draw.

use crate::raster::boxes::Boxes;

/// Triangles under this area (pixels²) of a splatted ghost are drawn as boxes: a quarter of a
/// pixel, about a box's side of half a pixel.
pub const SPLAT_MAX_AREA: f32 = 0.25;

/// Longest side (pixels) a splatted triangle may have: a longer one is a sliver (a fold or a
/// grazing ray stretches a cell into a line) whose light a box of its area would not follow;
/// it keeps exact coverage.
pub const SPLAT_MAX_EDGE: f32 = 2.0;

/// Most aspect (width over height, or its inverse) a box may have: a sliver's moments would
/// ask for a box of no width.
const MAX_ASPECT: f32 = 16.0;

/// The area (pixels²) of triangle `p` when it is splatted: under [`SPLAT_MAX_AREA`], no side
/// longer than [`SPLAT_MAX_EDGE`], finite; else `None`.
#[inline]
pub fn splat_area(p: &[[f32; 2]; 3]) -> Option<f32> {
    let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1]];
    let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
    let area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]).abs();
    let e3 = [p[2][0] - p[1][0], p[2][1] - p[1][1]];
    let longest2 = [e1, e2, e3]
        .iter()
        .map(|e| e[0] * e[0] + e[1] * e[1])
        .fold(0.0_f32, f32::max);
    (area.is_finite() && area < SPLAT_MAX_AREA && longest2 <= SPLAT_MAX_EDGE * SPLAT_MAX_EDGE)
        .then_some(area)
}

/// Adds triangle `p` (pixels, area `area`, from [`splat_area`]) with corner attributes `a`
/// to `boxes`: one box of its area at its centroid, with irradiance `shade` of the attributes
/// there and the aspect of the triangle's second moments along x and y.
pub fn splat_triangle<const N: usize>(
    p: &[[f32; 2]; 3],
    a: &[[f32; N]; 3],
    area: f32,
    shade: impl Fn(&[f32; N]) -> [f32; 3],
    boxes: &mut Boxes,
) {
    if area.is_nan() || area <= 0.0 {
        return;
    }
    let spread = |c: usize| {
        let (x0, x1, x2) = (p[0][c], p[1][c], p[2][c]);
        (x0 * x0 + x1 * x1 + x2 * x2 - x0 * x1 - x1 * x2 - x2 * x0).max(0.0)
    };
    let aspect = (spread(0) / spread(1)).sqrt();
    let aspect = if aspect.is_finite() {
        aspect.clamp(1.0 / MAX_ASPECT, MAX_ASPECT)
    } else {
        1.0
    };
    let half_w = 0.5 * (area * aspect).sqrt();
    let half_h = 0.5 * (area / aspect).sqrt();
    let c = [
        (p[0][0] + p[1][0] + p[2][0]) / 3.0,
        (p[0][1] + p[1][1] + p[2][1]) / 3.0,
    ];
    let attrs: [f32; N] = std::array::from_fn(|m| (a[0][m] + a[1][m] + a[2][m]) / 3.0);
    boxes.push(
        [c[0] - half_w, c[1] - half_h, c[0] + half_w, c[1] + half_h],
        shade(&attrs),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::boxes::splat_boxes_into;
    use crate::raster::{Coverage, rasterize_into};

    fn total(px: &[[f32; 3]]) -> f64 {
        px.iter().map(|p| f64::from(p[0])).sum()
    }

    #[test]
    fn a_small_triangle_s_box_keeps_an_affine_shade_s_energy_and_its_place() {
        // 0.2 px² across a pixel corner; a shade affine in the attribute.
        let p = [[10.7, 5.8], [11.3, 5.9], [10.9, 6.45]];
        let area = splat_area(&p).expect("small and compact");
        let a = [[1.0_f32], [3.0], [2.0]];
        let mut boxes = Boxes::default();
        splat_triangle(&p, &a, area, |a| [a[0], 0.0, 0.0], &mut boxes);
        assert_eq!(boxes.len(), 1);
        // Energy: area × the shade at the centroid (2.0).
        let e = boxes.energy()[0];
        assert!((e - 2.0 * f64::from(area)).abs() < 1e-5 * e, "{e}");
        // Drawn, the same energy as the triangle's exact coverage, in the same 2 × 2 pixels,
        // each within a fraction of the whole.
        let (w, h) = (16, 10);
        let mut splat = vec![[0.0_f32; 3]; w * h];
        splat_boxes_into(&mut splat, w, &boxes);
        let mut exact = vec![[0.0_f32; 3]; w * h];
        rasterize_into(
            &mut exact,
            w,
            &p,
            &a,
            &[[0, 1, 2]],
            Coverage::Exact,
            |a: &[f32; 1]| [a[0], 0.0, 0.0],
        );
        assert!((total(&splat) - total(&exact)).abs() < 1e-5 * total(&exact));
        for (i, (s, x)) in splat.iter().zip(&exact).enumerate() {
            let (col, row) = (i % w, i / w);
            if !(10..=11).contains(&col) || !(5..=6).contains(&row) {
                assert_eq!((s[0], x[0]), (0.0, 0.0), "pixel {col}, {row}");
            }
        }
        let moved: f64 = splat
            .iter()
            .zip(&exact)
            .map(|(s, e)| f64::from((s[0] - e[0]).abs()))
            .sum();
        assert!(moved < 0.35 * total(&exact), "{moved} of {}", total(&exact));
    }

    #[test]
    fn large_and_long_triangles_are_not_splatted() {
        assert!(splat_area(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).is_none());
        assert!(splat_area(&[[0.0, 0.0], [3.0, 0.0], [0.0, 0.05]]).is_none());
        assert!(splat_area(&[[0.0, 0.0], [f32::NAN, 0.0], [0.0, 0.5]]).is_none());
        assert_eq!(
            splat_area(&[[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]]),
            Some(0.125)
        );
    }

    #[test]
    fn a_sliver_s_box_follows_its_direction() {
        // 1.9 px along x, 0.2 px high: a wide, flat box.
        let p = [[0.0, 0.0], [1.9, 0.1], [0.2, 0.2]];
        let area = splat_area(&p).unwrap();
        let mut boxes = Boxes::default();
        splat_triangle(&p, &[[1.0_f32]; 3], area, |a| [a[0]; 3], &mut boxes);
        let r = boxes.rects[0];
        assert!(r[2] - r[0] > 4.0 * (r[3] - r[1]), "{r:?}");
    }
}

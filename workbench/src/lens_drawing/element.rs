//! Glass elements: the closed outline of the glass between two surfaces, and its triangles.

use flarebench_sdk::{LensSystem, Surface};

use super::profile::{drawn_semi_diameter, profile_heights};

/// One glass element: the glass between surfaces `rows.0` and `rows.1`, as lens drawings show
/// it in section.
///
/// The outline is one closed, non-self-intersecting polygon (the last point joins the first),
/// running clockwise with z to the right and y up (counter-clockwise on a screen whose y
/// grows downward): from the element's lowest point up the front side, across the top edge,
/// then down the back side; the bottom edge closes it. Each side is its surface's profile,
/// where the two semi-diameters differ continued from the smaller surface's rim by a flat step
/// (perpendicular to the axis) out to the larger one, whose rims are then joined by an edge
/// parallel to the axis. Both sides are sampled at the same heights (the surfaces' sample
/// heights, merged over a cemented group), so the polygon is a stack of trapezoids, which
/// `triangles` splits in two each. Adjacent elements of a cemented group share the vertices
/// of their common surface.
///
/// Where the two sides would cross before the edge (an over-large semi-diameter, a negative
/// edge thickness), the element ends at the height where they meet, in a single point.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementFill {
    /// The surfaces in front of and behind the glass (`(i, i + 1)`).
    pub rows: (usize, usize),
    /// The glass's index at the d line, and its Abbe number (`None`: non-dispersive).
    pub n_d: f64,
    pub abbe: Option<f64>,
    /// The closed outline, points (z, y) in mm.
    pub outline: Vec<[f64; 2]>,
    /// Triangles covering the outline exactly (indices into `outline`, wound like it).
    pub triangles: Vec<[u32; 3]>,
}

/// One side of an element: a surface at its vertex position, drawn to its semi-diameter and
/// continued beyond it by the flat step.
struct Side<'a> {
    surface: &'a Surface,
    z0: f64,
    h: f64,
}

impl Side<'_> {
    /// The side's z at height `y` (either sign).
    fn z(&self, y: f64) -> f64 {
        self.z0 + self.surface.sag(y.abs().min(self.h)).unwrap_or(0.0)
    }
}

/// Where an element ends outward: at height `y`, with the two sides distinct there (an edge)
/// or meeting in one point (`apex`).
#[derive(Clone, Copy, Debug)]
struct Top {
    y: f64,
    apex: bool,
}

/// Every glass element of `system` (vertex positions `z`), front to back; a gap of glass with
/// no area (zero centre thickness) is left out.
pub(super) fn elements(system: &LensSystem, z: &[f64]) -> Vec<ElementFill> {
    let n = system.surfaces.len().min(z.len());
    let glass = |i: usize| i + 1 < n && !system.surfaces[i].medium.is_air();
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        if !glass(i) {
            i += 1;
            continue;
        }
        // A cemented group: glass after surfaces first..last, bounded by surfaces first..=last.
        let first = i;
        while glass(i) {
            i += 1;
        }
        group(system, z, first, i, &mut out);
    }
    out
}

/// The elements of the cemented group bounded by surfaces `first..=last`.
fn group(system: &LensSystem, z: &[f64], first: usize, last: usize, out: &mut Vec<ElementFill>) {
    let sides: Vec<Side<'_>> = (first..=last)
        .map(|j| {
            let surface = &system.surfaces[j];
            Side {
                surface,
                z0: z[j],
                h: drawn_semi_diameter(surface),
            }
        })
        .collect();
    // Heights shared by the whole group, so that neighbours share their common surface's
    // vertices; every element's top is added once known.
    let mut grid: Vec<f64> = sides
        .iter()
        .flat_map(|s| profile_heights(s.surface))
        .collect();
    sort_dedup(&mut grid);
    let mut tops: Vec<Option<Top>> = Vec::new();
    // A top found between two heights adds a height to the neighbours, where their sides
    // might meet in turn: a few rounds settle it (`build` stops at a meeting it was not told
    // of anyway).
    for _ in 0..4 {
        tops = sides.windows(2).map(|w| top(&w[0], &w[1], &grid)).collect();
        let before = grid.len();
        grid.extend(tops.iter().flatten().map(|t| t.y));
        sort_dedup(&mut grid);
        if grid.len() == before {
            break;
        }
    }
    for (k, t) in tops.iter().enumerate() {
        let Some(t) = *t else { continue };
        let (outline, triangles) = build(&sides[k], &sides[k + 1], &grid, t);
        if triangles.is_empty() {
            continue;
        }
        let medium = &system.surfaces[first + k].medium;
        out.push(ElementFill {
            rows: (first + k, first + k + 1),
            n_d: medium.nd(),
            abbe: medium.vd(),
            outline,
            triangles,
        });
    }
}

fn sort_dedup(v: &mut Vec<f64>) {
    v.retain(|y| y.is_finite());
    v.sort_by(f64::total_cmp);
    v.dedup();
}

/// Where the element between `front` and `back` ends: the larger semi-diameter, or the
/// height where the two sides meet (found among `grid`'s heights, then by bisection); `None`
/// when there is no glass at the axis (centre thickness 0).
fn top(front: &Side<'_>, back: &Side<'_>, grid: &[f64]) -> Option<Top> {
    let hmax = front.h.max(back.h);
    // Widths below this count as the sides meeting (a knife edge).
    let eps = 1e-9 * hmax.max(1.0);
    let open = |y: f64| back.z(y) - front.z(y) > eps;
    if !(hmax > 0.0 && open(0.0)) {
        return None;
    }
    let mut prev = 0.0;
    for &y in grid.iter().filter(|&&y| y > 0.0 && y <= hmax) {
        if !open(y) {
            let (mut lo, mut hi) = (prev, y);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if !(mid > lo && mid < hi) || hi - lo <= 1e-12 * hi.max(1.0) {
                    break;
                }
                if open(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return if lo > prev {
                Some(Top { y: lo, apex: true })
            } else if prev > 0.0 {
                Some(Top {
                    y: prev,
                    apex: false,
                })
            } else {
                None
            };
        }
        prev = y;
    }
    (prev > 0.0).then_some(Top {
        y: prev,
        apex: false,
    })
}

/// The outline and triangles of the element between `front` and `back` up to `top`, sampled at
/// `grid`'s heights (which include `top.y`).
fn build(
    front: &Side<'_>,
    back: &Side<'_>,
    grid: &[f64],
    top: Top,
) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let mut apex = top.apex;
    let mut up: Vec<f64> = grid
        .iter()
        .copied()
        .filter(|&y| y >= 0.0 && y <= top.y)
        .collect();
    // Every edge across the element must have positive width (the apex aside): end below
    // the first that has not.
    let last = up.len().saturating_sub(1);
    if let Some(k) = (1..up.len())
        .filter(|&k| !(apex && k == last))
        .find(|&k| !positive(back.z(up[k]) - front.z(up[k])))
    {
        up.truncate(k);
        apex = false;
    }
    let heights: Vec<f64> = up
        .iter()
        .rev()
        .filter(|&&y| y > 0.0)
        .map(|&y| -y)
        .chain(up.iter().copied())
        .collect();
    let n = heights.len();
    let mut outline: Vec<[f64; 2]> = Vec::with_capacity(2 * n);
    // The front side, bottom to top (the apex, where the sides meet, halfway between them).
    for (k, &y) in heights.iter().enumerate() {
        let z = if apex && (k == 0 || k == n - 1) {
            0.5 * (front.z(y) + back.z(y))
        } else {
            front.z(y)
        };
        outline.push([z, y]);
    }
    // The back side, top to bottom; `back_index[k]` is the vertex at `heights[k]`.
    let mut back_index = vec![0u32; n];
    for k in (0..n).rev() {
        back_index[k] = if apex && (k == 0 || k == n - 1) {
            k as u32
        } else {
            outline.push([back.z(heights[k]), heights[k]]);
            (outline.len() - 1) as u32
        };
    }
    // Each band between two heights is a trapezoid (both edges across it have positive
    // width): two triangles, or one where the band ends in the apex.
    let mut triangles = Vec::with_capacity(2 * n);
    for k in 0..n.saturating_sub(1) {
        let (f0, f1) = (k as u32, k as u32 + 1);
        let (b0, b1) = (back_index[k], back_index[k + 1]);
        if f1 == b1 {
            triangles.push([f0, f1, b0]);
        } else if f0 == b0 {
            triangles.push([f0, f1, b1]);
        } else {
            triangles.push([f0, f1, b1]);
            triangles.push([f0, b1, b0]);
        }
    }
    (outline, triangles)
}

/// `x > 0` (false for NaN).
fn positive(x: f64) -> bool {
    x > 0.0
}

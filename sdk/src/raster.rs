//! CPU triangle rasterizer for ghost meshes: exact, anti-aliased coverage, tiled over cores.
//!
//! **Coverage.** Each triangle adds to every pixel it overlaps
//! `A · shade(attributes at C)`, where `A` is the exact area of the pixel square covered by the
//! triangle (pixel²) and `C` the centroid of that covered piece; attributes are interpolated
//! linearly (barycentric) at `C`. So the contribution is the exact integral of `shade` over
//! the covered piece whenever `shade` is affine in the attributes, and energy is conserved
//! exactly: for a constant shade `c` the image gains `c × (area of the triangle inside the
//! image)`, up to one f32 rounding of each pixel's sum: a tile's pixels are summed in f64
//! while its triangles are added and rounded to f32 once (a pixel of a dense reference grid
//! gains hundreds of thousands of pieces; added one by one in f32, the Nikon zoom's ghost 9-7
//! at 160 × 90 gained 1% of energy).
//!
//! **Method.** The triangle is clipped (Sutherland–Hodgman) to its tile and to each pixel row;
//! the area and first moments of the row piece above each pixel column then follow from
//! Green's theorem along the piece's edges (see `rasterize_in_tile`), and pixels wholly
//! inside get area 1 at their centre. No polygon is cut per pixel; a test checks every pixel
//! against clipping the triangle to the pixel square.
//!
//! **Conventions.** Positions are pixel coordinates, x to the right and y down; pixel `(i, j)`
//! covers `[i, i + 1) × [j, j + 1)`. Either winding. Geometry is computed in f64 (from the
//! f32 inputs), pixels are summed in f64 per tile and stored in f32.
//!
//! **Robustness.** A triangle is skipped — adds nothing — when a vertex index is out of range
//! (of `positions` or of `attrs`), a coordinate or attribute is NaN or infinite, or its area is
//! zero; nothing it does writes NaN or ∞ into the image (what `shade` returns is added as is).
//!
//! **Parallelism.** Triangles are binned into 64 × 64-pixel tiles by their bounding boxes (one
//! counting sort per call); tiles are rasterized in parallel (rayon), each writing only its
//! own pixels through disjoint slices — no locks or atomics — and each adding its triangles in
//! input order, so the result does not depend on the number of threads. The per-triangle and
//! per-pixel work uses fixed-size stack polygons: no allocation.

pub mod boxes;
mod polygon;

use rayon::prelude::*;

use crate::image::HdrImage;
use polygon::Polygon;

/// Side of a square tile, in pixels.
pub const TILE_SIZE: usize = 64;

/// Rasterizes `triangles` (indices into `positions` and `attrs`) into `img`, adding to each
/// covered pixel the covered area (pixel²) times `shade` of the attributes interpolated at the
/// covered piece's centroid. See the module documentation for the method and guarantees.
///
/// # Panics
/// If `img.pixels.len() != img.width * img.height` (a broken [`HdrImage`] invariant).
pub fn rasterize<const N: usize, F>(
    img: &mut HdrImage,
    positions: &[[f32; 2]],
    attrs: &[[f32; N]],
    triangles: &[[u32; 3]],
    shade: F,
) where
    F: Fn(&[f32; N]) -> [f32; 3] + Sync,
{
    rasterize_with(img, positions, attrs, triangles, Coverage::Exact, shade);
}

/// How a triangle covers the pixels it overlaps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coverage {
    /// Exact covered area of every pixel, shaded at the covered piece's centroid (the
    /// module documentation).
    Exact,
    /// Triangles of at least `min_area` pixel² are point-sampled: a pixel whose centre lies
    /// in the triangle gets `shade` at its centre, weight 1 (a half-open rule at edges and
    /// vertices, so triangles sharing an edge cover every pixel centre along it exactly
    /// once: a closed mesh adds its shade once per pixel, as exact coverage would in its
    /// interior). Smaller triangles — a mesh's folds, caustics, the diffraction-sized ones —
    /// keep exact coverage, where a sample could miss them or count them whole, and so do
    /// slivers narrower than [`MIN_SAMPLED_WIDTH`] (a caustic's cell drawn as a line across
    /// the frame: its samples would fall on a few pixel centres it happens to cross, a
    /// knife-edge that f32 and f64 positions decide differently). Energy is
    /// then kept up to the sampling of each triangle's outline where no neighbour shares it
    /// (zero-mean, a fraction of a pixel's worth per edge pixel); within a mesh, exactly up
    /// to the interpolated shade.
    Sampled { min_area: f32 },
}

/// Narrowest a triangle may be (its height over its longest side, pixels) to be point-sampled
/// under [`Coverage::Sampled`]; the GPU backend's rasterizer (`raster.wgsl`) uses the same.
pub const MIN_SAMPLED_WIDTH: f64 = 1.0;

/// True when the triangle `p` of `area` pixel² is at least [`MIN_SAMPLED_WIDTH`] across its
/// longest side.
fn wide_enough(p: [[f32; 2]; 3], area: f64) -> bool {
    let edge2 = |a: [f32; 2], b: [f32; 2]| {
        let (dx, dy) = (f64::from(b[0] - a[0]), f64::from(b[1] - a[1]));
        dx * dx + dy * dy
    };
    let longest2 = edge2(p[0], p[1])
        .max(edge2(p[1], p[2]))
        .max(edge2(p[2], p[0]));
    // Height on the longest side = 2 · area / its length.
    4.0 * area * area >= MIN_SAMPLED_WIDTH * MIN_SAMPLED_WIDTH * longest2
}

/// [`rasterize`] with a choice of [`Coverage`].
///
/// # Panics
/// If `img.pixels.len() != img.width * img.height` (a broken [`HdrImage`] invariant).
pub fn rasterize_with<const N: usize, F>(
    img: &mut HdrImage,
    positions: &[[f32; 2]],
    attrs: &[[f32; N]],
    triangles: &[[u32; 3]],
    coverage: Coverage,
    shade: F,
) where
    F: Fn(&[f32; N]) -> [f32; 3] + Sync,
{
    assert_eq!(
        img.pixels.len(),
        img.width * img.height,
        "HdrImage invariant: pixels.len() == width * height"
    );
    rasterize_into(
        &mut img.pixels,
        img.width,
        positions,
        attrs,
        triangles,
        coverage,
        shade,
    );
}

/// [`rasterize_with`] into a row-major pixel buffer `width` pixels wide (a host's buffer,
/// say), whose height is `pixels.len() / width` (whole rows; a partial last row is left
/// alone).
pub fn rasterize_into<const N: usize, F>(
    pixels: &mut [[f32; 3]],
    width: usize,
    positions: &[[f32; 2]],
    attrs: &[[f32; N]],
    triangles: &[[u32; 3]],
    coverage: Coverage,
    shade: F,
) where
    F: Fn(&[f32; N]) -> [f32; 3] + Sync,
{
    rasterize_shaded_into(
        pixels,
        width,
        positions,
        attrs,
        triangles,
        coverage,
        &FnShader(shade),
    );
}

/// What a pixel adds, as a function of its interpolated attributes — with, for point-sampled
/// rows, a way to say in advance where along a row the shade is zero (those pixels are
/// skipped) and where it takes a cheaper form ([`Shader::shade_core`]).
pub trait Shader<const N: usize>: Sync {
    /// What [`Shader::split_row`] needs of a triangle that is the same on each of its rows
    /// (reciprocals of its steps, bounds over its corners): made once per point-sampled
    /// triangle and tile ([`Shader::rows`]).
    type Rows: Default;

    /// The value added at a pixel (times its covered area) with attributes `a`.
    fn shade(&self, a: &[f32; N]) -> [f32; 3];

    /// The [`Shader::Rows`] of a triangle whose attributes change by `step` from one pixel to
    /// the next along x and are `corners` at its corners. The default is the default.
    fn rows(&self, step: &[f32; N], corners: &[[f32; N]; 3]) -> Self::Rows {
        let _ = (step, corners);
        Self::Rows::default()
    }

    /// For a point-sampled row of `n` pixels of a triangle (`rows`, made by [`Shader::rows`])
    /// whose attributes are `a + k · step` at pixel `k` (exactly; the rasterizer's f32 values
    /// are within a few ulps of that), the pixels where [`Shader::shade`] may be non-zero
    /// (`lit`; outside it it must be exactly zero) and, within them, those where it equals
    /// [`Shader::shade_core`] (`core`). The default is the whole row, no core.
    fn split_row(&self, rows: &Self::Rows, a: &[f32; N], step: &[f32; N], n: usize) -> RowSplit {
        let _ = (rows, a, step);
        RowSplit {
            lit: 0..n,
            core: 0..0,
        }
    }

    /// [`Shader::shade`] where [`Shader::split_row`] put a pixel in the core.
    fn shade_core(&self, a: &[f32; N]) -> [f32; 3] {
        self.shade(a)
    }
}

/// How a point-sampled row of pixels divides ([`Shader::split_row`]): indices from the row's
/// first pixel. A `core` outside `lit` is taken as empty.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RowSplit {
    pub lit: std::ops::Range<usize>,
    pub core: std::ops::Range<usize>,
}

/// A closure as a [`Shader`] (no row split).
struct FnShader<F>(F);

impl<const N: usize, F> Shader<N> for FnShader<F>
where
    F: Fn(&[f32; N]) -> [f32; 3] + Sync,
{
    type Rows = ();

    #[inline]
    fn shade(&self, a: &[f32; N]) -> [f32; 3] {
        (self.0)(a)
    }
}

/// [`rasterize_into`] with a [`Shader`]: its row split is used on point-sampled rows.
pub fn rasterize_shaded_into<const N: usize, S: Shader<N>>(
    pixels: &mut [[f32; 3]],
    width: usize,
    positions: &[[f32; 2]],
    attrs: &[[f32; N]],
    triangles: &[[u32; 3]],
    coverage: Coverage,
    shader: &S,
) {
    let height = pixels.len().checked_div(width).unwrap_or(0);
    if width == 0 || height == 0 || triangles.is_empty() {
        return;
    }
    let tiles_x = width.div_ceil(TILE_SIZE);
    let tiles_y = height.div_ceil(TILE_SIZE);
    let bins = Bins::build(
        positions,
        attrs,
        triangles,
        [width, height],
        [tiles_x, tiles_y],
    );

    // One view per tile: the tile's part of each of its rows, as disjoint mutable slices.
    let mut views: Vec<TileView<'_>> = (0..tiles_x * tiles_y)
        .map(|t| {
            let (tx, ty) = (t % tiles_x, t / tiles_x);
            let (x0, y0) = (tx * TILE_SIZE, ty * TILE_SIZE);
            TileView {
                index: t,
                x0,
                y0,
                width: TILE_SIZE.min(width - x0),
                height: TILE_SIZE.min(height - y0),
                rows: Vec::new(),
            }
        })
        .collect();
    for (y, row) in pixels.chunks_exact_mut(width).enumerate() {
        let ty = y / TILE_SIZE;
        if bins.tile_is_empty_row(ty, tiles_x) {
            continue;
        }
        for (tx, segment) in row.chunks_mut(TILE_SIZE).enumerate() {
            let view = &mut views[ty * tiles_x + tx];
            if !bins.tile(view.index).is_empty() {
                view.rows.push(segment);
            }
        }
    }
    views.retain(|v| !v.rows.is_empty());
    views
        .into_par_iter()
        .for_each_init(TileSums::new, |sums, mut view| {
            let mut scratch = Scratch::NEW;
            let min_area = match coverage {
                Coverage::Exact => f64::INFINITY,
                Coverage::Sampled { min_area } => f64::from(min_area),
            };
            for &t in bins.tile(view.index) {
                let tri = triangles[t];
                let p = tri.map(|i| positions[i as usize]);
                let corners = tri.map(|i| attrs[i as usize]);
                let setup = Setup::new(p, corners, [view.x0 as f64, view.y0 as f64]);
                if setup.area >= min_area && wide_enough(p, setup.area) {
                    sample_in_tile(&view, sums, p, &setup, &corners, shader);
                } else {
                    rasterize_in_tile(&view, sums, &setup, shader, &mut scratch);
                }
            }
            sums.add_into(&mut view.rows);
        });
}

/// One tile's pixel sums in f64 while its triangles are added, then added to the image's f32
/// pixels once: a pixel may gain millions of tiny pieces (a dense reference grid), and summed
/// in f32 each would be rounded against the whole sum — the image's energy off by a percent.
struct TileSums {
    /// `TILE_SIZE²` pixel sums, row by row.
    px: Vec<[f64; 3]>,
    /// Per row, the columns written since the last [`TileSums::add_into`] (empty: `start ≥ end`).
    spans: [(usize, usize); TILE_SIZE],
}

impl TileSums {
    const UNTOUCHED: (usize, usize) = (TILE_SIZE, 0);

    fn new() -> TileSums {
        TileSums {
            px: vec![[0.0; 3]; TILE_SIZE * TILE_SIZE],
            spans: [Self::UNTOUCHED; TILE_SIZE],
        }
    }

    /// Pixels `i0..i1` of row `j` of the tile, to add to.
    #[inline]
    fn row(&mut self, j: usize, i0: usize, i1: usize) -> &mut [[f64; 3]] {
        let span = &mut self.spans[j];
        *span = (span.0.min(i0), span.1.max(i1));
        &mut self.px[j * TILE_SIZE + i0..j * TILE_SIZE + i1]
    }

    /// Adds the sums to the tile's pixels `rows` (rounding each pixel once) and clears them.
    fn add_into(&mut self, rows: &mut [&mut [[f32; 3]]]) {
        for (j, row) in rows.iter_mut().enumerate() {
            let (i0, i1) = std::mem::replace(&mut self.spans[j], Self::UNTOUCHED);
            if i0 >= i1 {
                continue;
            }
            let sums = &mut self.px[j * TILE_SIZE + i0..j * TILE_SIZE + i1];
            for (px, sum) in row[i0..i1].iter_mut().zip(sums) {
                for c in 0..3 {
                    px[c] = (f64::from(px[c]) + sum[c]) as f32;
                }
                *sum = [0.0; 3];
            }
        }
    }
}

/// The pixels of one tile: `rows[j][i]` is pixel `(x0 + i, y0 + j)`.
struct TileView<'a> {
    index: usize,
    x0: usize,
    y0: usize,
    width: usize,
    height: usize,
    rows: Vec<&'a mut [[f32; 3]]>,
}

/// Triangle indices per tile (compressed rows: `indices[offsets[t]..offsets[t + 1]]`), each
/// tile's in input order.
struct Bins {
    offsets: Vec<usize>,
    indices: Vec<usize>,
}

impl Bins {
    fn build<const N: usize>(
        positions: &[[f32; 2]],
        attrs: &[[f32; N]],
        triangles: &[[u32; 3]],
        [width, height]: [usize; 2],
        [tiles_x, tiles_y]: [usize; 2],
    ) -> Bins {
        // Pass 1 (parallel): the tile rectangle of every usable triangle.
        let rects: Vec<Option<[usize; 4]>> = triangles
            .par_iter()
            .map(|tri| tile_rect(tri, positions, attrs, [width, height], [tiles_x, tiles_y]))
            .collect();
        // Pass 2: count, prefix-sum, fill (a counting sort keeps input order in each tile).
        let mut offsets = vec![0_usize; tiles_x * tiles_y + 1];
        for r in rects.iter().flatten() {
            for ty in r[1]..=r[3] {
                for tx in r[0]..=r[2] {
                    offsets[ty * tiles_x + tx + 1] += 1;
                }
            }
        }
        for t in 0..tiles_x * tiles_y {
            offsets[t + 1] += offsets[t];
        }
        let mut fill = offsets.clone();
        let mut indices = vec![0_usize; offsets[tiles_x * tiles_y]];
        for (i, r) in rects.iter().enumerate() {
            let Some(r) = r else { continue };
            for ty in r[1]..=r[3] {
                for tx in r[0]..=r[2] {
                    let slot = &mut fill[ty * tiles_x + tx];
                    indices[*slot] = i;
                    *slot += 1;
                }
            }
        }
        Bins { offsets, indices }
    }

    fn tile(&self, t: usize) -> &[usize] {
        &self.indices[self.offsets[t]..self.offsets[t + 1]]
    }

    fn tile_is_empty_row(&self, ty: usize, tiles_x: usize) -> bool {
        self.offsets[ty * tiles_x] == self.offsets[(ty + 1) * tiles_x]
    }
}

/// `[tx0, ty0, tx1, ty1]` (inclusive) of the tiles a triangle's bounding box meets, or `None`
/// for a triangle that is skipped (bad index, non-finite value, zero area, outside the image).
fn tile_rect<const N: usize>(
    tri: &[u32; 3],
    positions: &[[f32; 2]],
    attrs: &[[f32; N]],
    [width, height]: [usize; 2],
    [tiles_x, tiles_y]: [usize; 2],
) -> Option<[usize; 4]> {
    let mut p = [[0.0_f64; 2]; 3];
    for (k, &i) in tri.iter().enumerate() {
        let i = i as usize;
        let (pos, attr) = (positions.get(i)?, attrs.get(i)?);
        if !(pos.iter().all(|v| v.is_finite()) && attr.iter().all(|v| v.is_finite())) {
            return None;
        }
        p[k] = pos.map(f64::from);
    }
    let area2 =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
    if area2 == 0.0 || !area2.is_finite() {
        return None;
    }
    let xmin = p[0][0].min(p[1][0]).min(p[2][0]).max(0.0);
    let xmax = p[0][0].max(p[1][0]).max(p[2][0]).min(width as f64);
    let ymin = p[0][1].min(p[1][1]).min(p[2][1]).max(0.0);
    let ymax = p[0][1].max(p[1][1]).max(p[2][1]).min(height as f64);
    if !(xmin < xmax && ymin < ymax) {
        return None;
    }
    let tile = TILE_SIZE as f64;
    let first = |v: f64, n: usize| ((v / tile).floor() as usize).min(n - 1);
    let last = |v: f64, n: usize| ((v / tile).ceil() as usize).clamp(1, n) - 1;
    Some([
        first(xmin, tiles_x),
        first(ymin, tiles_y),
        last(xmax, tiles_x),
        last(ymax, tiles_y),
    ])
}

/// A triangle ready to rasterize in one tile: vertices relative to the tile origin (f64) and
/// its attribute plane.
struct Setup<const N: usize> {
    v: [[f64; 2]; 3],
    /// Barycentric weights of vertices 1 and 2 as affine functions of the position:
    /// `w_k(x, y) = bary[k][0] x + bary[k][1] y + bary[k][2]`.
    bary: [[f64; 3]; 2],
    /// +1 or −1: the sign that makes the boundary integral `−∮ y dx` of this triangle's
    /// winding its (positive) area.
    winding: f64,
    /// Area (pixel²).
    area: f64,
    /// Attributes of vertex 0, and those of vertices 1 and 2 minus those of vertex 0.
    a0: [f32; N],
    d1: [f32; N],
    d2: [f32; N],
}

impl<const N: usize> Setup<N> {
    fn new(p: [[f32; 2]; 3], attrs: [[f32; N]; 3], origin: [f64; 2]) -> Setup<N> {
        let v = p.map(|q| [f64::from(q[0]) - origin[0], f64::from(q[1]) - origin[1]]);
        let [a, b, c] = v;
        let (e1, e2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
        let area2 = e1[0] * e2[1] - e2[0] * e1[1];
        // The area was checked non-zero in `tile_rect`; translating very large coordinates
        // to the tile origin can still round it to 0: then every weight goes to vertex 0.
        let inv = if (1.0 / area2).is_finite() {
            1.0 / area2
        } else {
            0.0
        };
        // w1 = ((p − a) × e2) / area2, w2 = (e1 × (p − a)) / area2.
        let bary = [
            [
                e2[1] * inv,
                -e2[0] * inv,
                (e2[0] * a[1] - a[0] * e2[1]) * inv,
            ],
            [
                -e1[1] * inv,
                e1[0] * inv,
                (a[0] * e1[1] - e1[0] * a[1]) * inv,
            ],
        ];
        let [a0, a1, a2] = attrs;
        Setup {
            v,
            bary,
            // −∮ y dx is the shoelace signed area, area2 / 2 (see `add_edge`).
            winding: if area2 > 0.0 { 1.0 } else { -1.0 },
            area: 0.5 * area2.abs(),
            a0,
            d1: std::array::from_fn(|k| a1[k] - a0[k]),
            d2: std::array::from_fn(|k| a2[k] - a0[k]),
        }
    }

    /// Change of the attributes from one pixel to the next along x.
    #[inline]
    fn x_step(&self) -> [f32; N] {
        let (d1, d2) = (self.bary[0][0] as f32, self.bary[1][0] as f32);
        std::array::from_fn(|k| d1 * self.d1[k] + d2 * self.d2[k])
    }

    /// Change of the attributes from one pixel to the next along y.
    #[inline]
    fn y_step(&self) -> [f32; N] {
        let (d1, d2) = (self.bary[0][1] as f32, self.bary[1][1] as f32);
        std::array::from_fn(|k| d1 * self.d1[k] + d2 * self.d2[k])
    }

    /// Attributes at `p` (tile coordinates): barycentric weights clamped to the triangle, so
    /// that rounding can never extrapolate beyond the vertices' values.
    #[inline]
    fn interpolate(&self, p: [f64; 2]) -> [f32; N] {
        let [k1, k2] = &self.bary;
        let mut w1 = (k1[0] * p[0] + k1[1] * p[1] + k1[2]).clamp(0.0, 1.0);
        let mut w2 = (k2[0] * p[0] + k2[1] * p[1] + k2[2]).clamp(0.0, 1.0);
        let s = w1 + w2;
        if s > 1.0 {
            w1 /= s;
            w2 /= s;
        }
        let (w1, w2) = (w1 as f32, w2 as f32);
        std::array::from_fn(|k| self.a0[k] + w1 * self.d1[k] + w2 * self.d2[k])
    }
}

/// The pixel `[i, j]` of a `tw × th` tile that holds the whole triangle `v` (tile
/// coordinates), if one does.
#[inline]
fn one_pixel(v: &[[f64; 2]; 3], tw: f64, th: f64) -> Option<[usize; 2]> {
    let lo = [
        v[0][0].min(v[1][0]).min(v[2][0]),
        v[0][1].min(v[1][1]).min(v[2][1]),
    ];
    let hi = [
        v[0][0].max(v[1][0]).max(v[2][0]),
        v[0][1].max(v[1][1]).max(v[2][1]),
    ];
    let (x, y) = (lo[0].floor(), lo[1].floor());
    (x >= 0.0 && y >= 0.0 && hi[0] <= (x + 1.0).min(tw) && hi[1] <= (y + 1.0).min(th))
        .then_some([x as usize, y as usize])
}

/// Scratch reused for every triangle of a tile: clipped polygons and one row of per-column
/// integrals.
struct Scratch {
    cols: Polygon,
    piece: Polygon,
    strip: Polygon,
    tmp: Polygon,
    /// Per column of the current row: `[∫∫ dA, ∫∫ (x − column) dA, ∫∫ (y − row) dA]`, as
    /// signed boundary integrals (see [`rasterize_in_tile`]).
    moments: [[f64; 3]; TILE_SIZE],
}

impl Scratch {
    const NEW: Scratch = Scratch {
        cols: Polygon::EMPTY,
        piece: Polygon::EMPTY,
        strip: Polygon::EMPTY,
        tmp: Polygon::EMPTY,
        moments: [[0.0; 3]; TILE_SIZE],
    };
}

/// Adds one triangle's coverage to the pixels of one tile.
///
/// The triangle is clipped to the tile, then to each pixel row (a strip, a convex polygon).
/// In a strip, the area and first moments of its part in each pixel column come from Green's
/// theorem, `∫∫ dA = −∮ y dx`, `∫∫ x dA = −∮ x y dx`, `∫∫ y dA = −∮ y²/2 dx`: the column's
/// vertical sides have `dx = 0`, so each column only needs the pieces of the strip's edges
/// above it. Each edge is walked column by column and its exact integrals (y is linear along
/// an edge) are added to those columns; with `y` measured from the row's top, the top edge
/// contributes nothing. No polygon is cut per pixel.
fn rasterize_in_tile<const N: usize, S: Shader<N>>(
    view: &TileView<'_>,
    sums: &mut TileSums,
    tri: &Setup<N>,
    shader: &S,
    s: &mut Scratch,
) {
    let (tw, th) = (view.width as f64, view.height as f64);
    if let Some([i, j]) = one_pixel(&tri.v, tw, th) {
        // Wholly inside one pixel of the tile: that pixel's covered piece is the whole
        // triangle (its area, shaded at its centroid), without clipping.
        let [a, b, c] = tri.v;
        let centroid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
        let value = shader.shade(&tri.interpolate(centroid));
        let px = &mut sums.row(j, i, i + 1)[0];
        for k in 0..3 {
            px[k] += tri.area * f64::from(value[k]);
        }
        return;
    }
    let whole = Polygon::triangle(tri.v[0], tri.v[1], tri.v[2]);
    whole.clip_slab::<0>(0.0, tw, &mut s.cols, &mut s.tmp);
    s.cols.clip_slab::<1>(0.0, th, &mut s.piece, &mut s.tmp);
    if s.piece.len < 3 {
        return;
    }
    let [ymin, ymax] = s.piece.range::<1>();
    let j0 = floor_index(ymin);
    let j1 = ceil_index(ymax).min(view.height);
    for j in j0..j1 {
        let y0 = j as f64;
        s.piece
            .clip_slab::<1>(y0, y0 + 1.0, &mut s.strip, &mut s.tmp);
        if s.strip.len < 3 {
            continue;
        }
        let [xmin, xmax] = s.strip.range::<0>();
        let i0 = floor_index(xmin);
        let i1 = ceil_index(xmax).min(view.width);
        if i0 >= i1 {
            continue;
        }
        // Columns [full0, full1) lie wholly inside the strip: both its top and bottom edges
        // cover them (the strip is convex). They get area 1 at the pixel centre without
        // walking the bottom edge through them.
        let (full0, full1) = full_run(&s.strip, y0, i0, i1);
        let moments = &mut s.moments[i0..i1];
        moments.fill([0.0; 3]);
        let strip = s.strip.vertices();
        let mut p = strip[strip.len() - 1];
        for &q in strip {
            let (a, b) = ([p[0], p[1] - y0], [q[0], q[1] - y0]);
            if a[1] == 1.0 && b[1] == 1.0 && full0 < full1 {
                // The bottom edge: only its parts outside the full run.
                let (f0, f1) = (full0 as f64, full1 as f64);
                let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
                let dir = |u: f64, v: f64| if a[0] < b[0] { (u, v) } else { (v, u) };
                if lo < f0 {
                    let (u, v) = dir(lo, hi.min(f0));
                    add_edge(moments, i0, [u, 1.0], [v, 1.0]);
                }
                if hi > f1 {
                    let (u, v) = dir(lo.max(f1), hi);
                    add_edge(moments, i0, [u, 1.0], [v, 1.0]);
                }
            } else {
                add_edge(moments, i0, a, b);
            }
            p = q;
        }
        let row = sums.row(j, i0, i1);
        for (k, m) in moments.iter().enumerate() {
            let i = i0 + k;
            if i >= full0 && i < full1 {
                continue; // the full run, below
            }
            // −∮ y dx is the area for one winding and minus it for the other.
            let area = tri.winding * m[0];
            #[allow(
                clippy::neg_cmp_op_on_partial_ord,
                reason = "`!(area > 0)` also skips NaN"
            )]
            if !(area > 0.0) {
                continue;
            }
            // First moments / area, both with the same sign: the centroid, in the pixel.
            let centroid = [
                i as f64 + (m[1] / m[0]).clamp(0.0, 1.0),
                y0 + (m[2] / m[0]).clamp(0.0, 1.0),
            ];
            let value = shader.shade(&tri.interpolate(centroid));
            let px = &mut row[k];
            for c in 0..3 {
                px[c] += area * f64::from(value[c]);
            }
        }
        if full0 < full1 {
            // Pixels wholly inside: area 1 at the centre. The attributes are affine in x, so
            // they step by a constant from one centre to the next (the centres are inside the
            // triangle, where no clamping applies).
            let a = tri.interpolate([full0 as f64 + 0.5, y0 + 0.5]);
            sample_run(&mut row[full0 - i0..full1 - i0], a, &tri.x_step(), |a| {
                shader.shade(a)
            });
        }
    }
}

/// Adds one triangle to the pixels of one tile by point sampling ([`Coverage::Sampled`]):
/// every pixel `(i, j)` whose centre `c = (i + ½, j + ½)` has `y_top ≤ c_y < y_bottom` and
/// `x_left ≤ c_x < x_right` gets `shade` at `c`.
///
/// The row's `x_left`, `x_right` are where the two edges spanning `c_y` cross it, each
/// computed from the edge's endpoints in a fixed order (by y, then x) and in absolute pixel
/// coordinates — the same bits in every triangle and tile that share the edge, so the
/// half-open rule leaves no pixel centre out and counts none twice.
fn sample_in_tile<const N: usize, S: Shader<N>>(
    view: &TileView<'_>,
    sums: &mut TileSums,
    p: [[f32; 2]; 3],
    tri: &Setup<N>,
    corners: &[[f32; N]; 3],
    shader: &S,
) {
    let mut v = p.map(|q| [f64::from(q[0]), f64::from(q[1])]);
    v.sort_unstable_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
    let [top, mid, bottom] = v;
    // First row (column) of the tile whose centre is at or after y (x): ⌈y − ½ − origin⌉,
    // clamped to the tile (0 for NaN). Both subtractions are exact where it matters (y ≥ ½,
    // the origin a whole number), so this is a function of `u` alone: the same for every
    // triangle sharing the edge.
    let (x0, y0) = (view.x0 as f64, view.y0 as f64);
    let first = |u: f64, lo: f64, len: usize| -> usize {
        let v = u - 0.5 - lo;
        if v.is_nan() || v <= 0.0 {
            0
        } else if v >= len as f64 {
            len
        } else {
            // 0 < v < len ≤ TILE_SIZE: the narrow cast is exact (and cheaper than a usize).
            let t = v as i32;
            (t + i32::from(f64::from(t) < v)) as usize
        }
    };
    let j0 = first(top[1], y0, view.height);
    let j1 = first(bottom[1], y0, view.height);
    // Each edge's inverse slope, from its sorted endpoints: the same bits wherever the edge
    // is shared (a horizontal edge's is never used: no row centre lies strictly inside it).
    let inverse_slope = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) / (b[1] - a[1]);
    let (long, upper, lower) = (
        inverse_slope(top, bottom),
        inverse_slope(top, mid),
        inverse_slope(mid, bottom),
    );
    let cross = |a: [f64; 2], slope: f64, y: f64| a[0] + (y - a[1]) * slope;
    // The attributes are affine: at a pixel centre, those of vertex 0 plus the steps along x
    // and y times the centre's offset from it (inside the triangle, so no clamping is
    // needed; the offsets, at most a tile across, are exact enough in f32).
    let step = tri.x_step();
    let step_y = tri.y_step();
    let v0 = tri.v[0];
    if j0 >= j1 {
        return;
    }
    let rows = shader.rows(&step, corners);
    for j in j0..j1 {
        let yc = y0 + j as f64 + 0.5;
        let xa = cross(top, long, yc);
        let xb = if yc < mid[1] {
            cross(top, upper, yc)
        } else {
            cross(mid, lower, yc)
        };
        let (xl, xr) = if xa <= xb { (xa, xb) } else { (xb, xa) };
        let i0 = first(xl, x0, view.width);
        let i1 = first(xr, x0, view.width);
        if i0 >= i1 {
            continue;
        }
        let dy = (j as f64 + 0.5 - v0[1]) as f32;
        // Attributes at pixel `i` of the row, from the attribute plane.
        let at = |i: usize| -> [f32; N] {
            let dx = (i as f64 + 0.5 - v0[0]) as f32;
            std::array::from_fn(|k| tri.a0[k] + dx * step[k] + dy * step_y[k])
        };
        let a = at(i0);
        let n = i1 - i0;
        let split = shader.split_row(&rows, &a, &step, n);
        let (l0, l1) = (split.lit.start.min(n), split.lit.end.min(n));
        if l0 >= l1 {
            continue;
        }
        let (mut c0, mut c1) = (split.core.start.max(l0), split.core.end.min(l1));
        if c0 >= c1 {
            (c0, c1) = (l1, l1);
        }
        let row = sums.row(j, i0, i1);
        let start = |k: usize| if k == 0 { a } else { at(i0 + k) };
        sample_run(&mut row[l0..c0], start(l0), &step, |a| shader.shade(a));
        sample_run(&mut row[c0..c1], start(c0), &step, |a| shader.shade_core(a));
        sample_run(&mut row[c1..l1], start(c1), &step, |a| shader.shade(a));
    }
}

/// Adds `shade` of `a`, `a + step`, `a + 2 step`, … to the pixels of `run`.
#[inline(always)]
fn sample_run<const N: usize>(
    run: &mut [[f64; 3]],
    mut a: [f32; N],
    step: &[f32; N],
    shade: impl Fn(&[f32; N]) -> [f32; 3],
) {
    for px in run {
        let value = shade(&a);
        for c in 0..3 {
            px[c] += f64::from(value[c]);
        }
        for (v, d) in a.iter_mut().zip(step) {
            *v += d;
        }
    }
}

/// Adds the boundary integrals of the edge `p → q` (x in tile pixels, y from the row's top,
/// in [0, 1]) to the columns it spans: per column piece `[u, v]` (edge direction) with `y`
/// linear from `yu` to `yv`, `−∫ y dx = −(v − u)(yu + yv)/2`,
/// `−∫ (x − c) y dx = −(v − u)((u − c)(2yu + yv) + (v − c)(yu + 2yv))/6`,
/// `−∫ y²/2 dx = −(v − u)(yu² + yu yv + yv²)/6`, for column `c`.
#[inline]
fn add_edge(moments: &mut [[f64; 3]], i0: usize, p: [f64; 2], q: [f64; 2]) {
    if p[0] == q[0] || (p[1] == 0.0 && q[1] == 0.0) {
        return; // vertical (dx = 0), or on the row's top (y = 0): contributes nothing
    }
    // Walk left to right; `dir` restores the edge's direction.
    let (a, b, dir) = if p[0] < q[0] {
        (p, q, -1.0)
    } else {
        (q, p, 1.0)
    };
    let slope = (b[1] - a[1]) / (b[0] - a[0]);
    let first = floor_index(a[0]);
    let last = ceil_index(b[0]).max(first + 1);
    let mut u = a[0];
    let mut yu = a[1];
    for c in first..last {
        let cf = c as f64;
        let (v, yv) = if cf + 1.0 >= b[0] {
            (b[0], b[1])
        } else {
            (cf + 1.0, a[1] + (cf + 1.0 - a[0]) * slope)
        };
        let dx = dir * (v - u);
        let (xu, xv) = (u - cf, v - cf);
        // The edge lies within the strip's columns [i0, i1), as do its ends.
        if let Some(m) = moments.get_mut(c.wrapping_sub(i0)) {
            m[0] += dx * (yu + yv) * 0.5;
            m[1] += dx * (xu * (2.0 * yu + yv) + xv * (yu + 2.0 * yv)) * (1.0 / 6.0);
            m[2] += dx * (yu * yu + yu * yv + yv * yv) * (1.0 / 6.0);
        }
        u = v;
        yu = yv;
    }
}

/// The columns `[full0, full1)` within `[i0, i1)` whose pixel lies wholly inside the strip
/// polygon between `y0` and `y0 + 1`: those inside both its top and bottom cross-sections,
/// which are spanned by the vertices lying exactly on those lines (clipping puts them there
/// exactly). An empty range when the strip does not reach both lines.
fn full_run(strip: &Polygon, y0: f64, i0: usize, i1: usize) -> (usize, usize) {
    let y1 = y0 + 1.0;
    let (mut top, mut bottom) = (
        [f64::INFINITY, f64::NEG_INFINITY],
        [f64::INFINITY, f64::NEG_INFINITY],
    );
    for p in strip.vertices() {
        if p[1] == y0 {
            top = [top[0].min(p[0]), top[1].max(p[0])];
        } else if p[1] == y1 {
            bottom = [bottom[0].min(p[0]), bottom[1].max(p[0])];
        }
    }
    // A missing cross-section leaves ±∞ here, so lo > hi (vertices are finite: no NaN).
    let (lo, hi) = (top[0].max(bottom[0]), top[1].min(bottom[1]));
    if lo > hi {
        return (i1, i1);
    }
    let full0 = ceil_index(lo).max(i0);
    let full1 = floor_index(hi).min(i1);
    if full0 < full1 {
        (full0, full1)
    } else {
        (i1, i1)
    }
}

/// `⌊x⌋` as an index, for `x ≥ 0` (0 for negative or NaN): a truncating cast, since
/// `f64::floor` is a libm call on baseline x86-64.
#[inline]
fn floor_index(x: f64) -> usize {
    x as usize
}

/// `⌈x⌉` as an index, for `x ≥ 0` (0 for negative or NaN).
#[inline]
fn ceil_index(x: f64) -> usize {
    let t = x as usize;
    if (t as f64) < x { t + 1 } else { t }
}

#[cfg(test)]
mod tests;

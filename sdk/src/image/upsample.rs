//! Coarse images of a frame and their bilinear upsampling: large, smooth ghosts are drawn
//! into a coarse copy of the frame and added back at full resolution.
//!
//! A [`CoarseGrid`] with factor `f` covers the full-resolution frame (`w × h` pixels) with
//! `⌈w/f⌉ × ⌈h/f⌉` coarse pixels, centred on it: coarse pixel `(I, J)` covers full-resolution
//! `[I·f − ox, (I + 1)·f − ox) × [J·f − oy, (J + 1)·f − oy)` with `ox = (⌈w/f⌉·f − w)/2` (and
//! likewise `oy`), so the two frames share their centre. A coarse pixel holds the energy of
//! its `f²` full-resolution pixels; [`add_upsampled`] reconstructs the density by bilinear
//! interpolation between coarse pixel centres (constant beyond the outermost centres) and
//! divides by `f²`. A constant image is reproduced exactly; total energy is kept up to the
//! interpolation's error at the frame border.

use rayon::prelude::*;

use super::HdrImage;

/// A coarse copy of a `width × height` frame (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseGrid {
    /// Full-resolution pixels per coarse pixel, along each axis (≥ 1).
    pub factor: usize,
    /// Coarse size in pixels.
    pub width: usize,
    pub height: usize,
    /// Full-resolution pixels by which the coarse grid starts before the frame, `[ox, oy]`.
    pub offset: [f64; 2],
}

impl CoarseGrid {
    /// The coarse grid of factor `factor` (at least 1) for a `width × height` frame.
    pub fn for_frame(width: usize, height: usize, factor: usize) -> CoarseGrid {
        let f = factor.max(1);
        let (w, h) = (width.div_ceil(f), height.div_ceil(f));
        CoarseGrid {
            factor: f,
            width: w,
            height: h,
            offset: [(w * f - width) as f64 * 0.5, (h * f - height) as f64 * 0.5],
        }
    }
}

/// Per full-resolution pixel along one axis: the coarse index below its centre and the
/// weight of the next one.
fn axis_weights(
    full: usize,
    coarse: usize,
    factor: usize,
    offset: f64,
) -> Vec<(usize, usize, f32)> {
    let f = factor as f64;
    let last = coarse.saturating_sub(1);
    (0..full)
        .map(|x| {
            let u = (x as f64 + 0.5 + offset) / f - 0.5;
            if u <= 0.0 {
                (0, 0, 0.0)
            } else if u >= last as f64 {
                (last, last, 0.0)
            } else {
                let i = u as usize;
                (i, i + 1, (u - i as f64) as f32)
            }
        })
        .collect()
}

/// The full-resolution pixels of a row grouped by the two coarse pixels they interpolate
/// between (consecutive, since the weights are monotone), and each pixel's weight.
struct Runs {
    spans: Vec<Run>,
    tx: Vec<f32>,
}

/// Pixels `[x0, x1)` interpolate between coarse pixels `i0` and `i1`.
struct Run {
    x0: usize,
    x1: usize,
    i0: usize,
    i1: usize,
}

impl Runs {
    fn new(xs: &[(usize, usize, f32)]) -> Runs {
        let mut spans: Vec<Run> = Vec::new();
        for (x, &(i0, i1, _)) in xs.iter().enumerate() {
            match spans.last_mut() {
                Some(r) if (r.i0, r.i1) == (i0, i1) => r.x1 = x + 1,
                _ => spans.push(Run {
                    x0: x,
                    x1: x + 1,
                    i0,
                    i1,
                }),
            }
        }
        Runs {
            spans,
            tx: xs.iter().map(|w| w.2).collect(),
        }
    }
}

/// Adds `coarse` (laid out by `grid`) to `dst` at full resolution: bilinear interpolation of
/// the coarse density, divided by `factor²` so that energy is kept.
///
/// # Panics
/// If `coarse` is not `grid.width × grid.height`.
pub fn add_upsampled(dst: &mut HdrImage, coarse: &HdrImage, grid: &CoarseGrid) {
    add_upsampled_into(&mut dst.pixels, dst.width, coarse, grid);
}

/// [`add_upsampled`] into a row-major pixel buffer `width` pixels wide (a host's buffer, say),
/// whose height is `dst.len() / width`.
///
/// # Panics
/// If `coarse` is not `grid.width × grid.height`, or `dst.len()` is not a multiple of `width`.
pub fn add_upsampled_into(
    dst: &mut [[f32; 3]],
    width: usize,
    coarse: &HdrImage,
    grid: &CoarseGrid,
) {
    add_upsampled_levels_into(dst, width, &[(coarse, grid)]);
}

/// Adds several coarse images (each laid out by its grid, any factors) to `dst` in one pass
/// over it: each pixel gets the sum of every level's bilinear interpolation, as
/// [`add_upsampled_into`] level by level would give (up to the order of the f32 sums), but
/// reading and writing the full-resolution buffer once.
///
/// # Panics
/// If a coarse image is not its grid's size, or `dst.len()` is not a multiple of `width`.
pub fn add_upsampled_levels_into(
    dst: &mut [[f32; 3]],
    width: usize,
    levels: &[(&HdrImage, &CoarseGrid)],
) {
    upsample_levels_into(dst, width, levels, Blend::Add);
}

/// What an upsampling pass does with what the full-resolution buffer held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Adds the levels to it.
    Add,
    /// Discards it: every pixel is written, black where no level is lit. The buffer needs no
    /// clearing first, and the pass only writes it (a frame kept from frame to frame is
    /// cleared and refilled in one pass instead of two).
    Replace,
}

/// [`add_upsampled_levels_into`], adding to `dst` or replacing it as `blend` says.
///
/// # Panics
/// If a coarse image is not its grid's size, or `dst.len()` is not a multiple of `width`.
pub fn upsample_levels_into(
    dst: &mut [[f32; 3]],
    width: usize,
    levels: &[(&HdrImage, &CoarseGrid)],
    blend: Blend,
) {
    let spans: Vec<RowSpans> = levels.iter().map(|(coarse, _)| row_spans(coarse)).collect();
    let levels: Vec<_> = levels
        .iter()
        .zip(&spans)
        .map(|(&(coarse, grid), spans)| (coarse, grid, spans.as_slice()))
        .collect();
    upsample_spans_into(dst, width, &levels, blend);
}

/// Per row of an image, the columns `(first, end)` from its first to past its last pixel with
/// a channel that is not zero (`(0, 0)` for a black row): where an upsampling pass reads it.
pub type RowSpans = Vec<(usize, usize)>;

/// The [`RowSpans`] of `img` (rows in parallel).
pub fn row_spans(img: &HdrImage) -> RowSpans {
    if img.width == 0 {
        return vec![(0, 0); img.height];
    }
    img.pixels.par_chunks(img.width).map(lit_span).collect()
}

/// A coarse image, its grid and spans of its rows holding every lit pixel (its
/// [`RowSpans`], or wider ones): a level of [`upsample_spans_into`].
pub type SpannedLevel<'a> = (&'a HdrImage, &'a CoarseGrid, &'a [(usize, usize)]);

/// [`upsample_levels_into`] with each level's [`RowSpans`] given, as a caller that keeps them
/// does: its own, or any spans holding them (the pixels outside must be black; the
/// interpolation at a span's ends reads the black neighbour next to it).
///
/// # Panics
/// If a coarse image is not its grid's size, its spans are not one per row, or `dst.len()`
/// is not a multiple of `width`.
pub fn upsample_spans_into(
    dst: &mut [[f32; 3]],
    width: usize,
    levels: &[SpannedLevel<'_>],
    blend: Blend,
) {
    for (coarse, grid, spans) in levels {
        assert_eq!(
            (coarse.width, coarse.height),
            (grid.width, grid.height),
            "the coarse image has the grid's size"
        );
        assert_eq!(spans.len(), coarse.height, "one span a row");
    }
    let levels: Vec<_> = levels
        .iter()
        .filter(|(_, g, _)| g.width > 0 && g.height > 0)
        .collect();
    if width == 0 || dst.is_empty() {
        return;
    }
    if levels.is_empty() {
        if blend == Blend::Replace {
            super::fill_black(dst);
        }
        return;
    }
    assert_eq!(dst.len() % width, 0, "whole rows");
    let height = dst.len() / width;
    // Per level: the norm, the weights along each axis, and per coarse row the columns
    // between its first and last non-zero pixel (ghosts cover a part of a frame: a coarse
    // frame is mostly black, and its black parts add nothing).
    let setup: Vec<Level<'_>> = levels
        .iter()
        .map(|(coarse, grid, spans)| Level {
            coarse,
            width: grid.width,
            norm: 1.0 / (grid.factor * grid.factor) as f32,
            runs: Runs::new(&axis_weights(
                width,
                grid.width,
                grid.factor,
                grid.offset[0],
            )),
            ys: axis_weights(height, grid.height, grid.factor, grid.offset[1]),
            spans,
        })
        .collect();
    // Output rows in blocks, each block on one thread: a level's coarse rows are
    // interpolated along x to full width once per block (a coarse row serves `factor`
    // output rows), and each output row adds the two full-width rows it lies between,
    // interpolated along y — contiguous f32s, which the compiler vectorizes.
    dst.par_chunks_mut(width * ROWS_PER_BLOCK)
        .enumerate()
        .for_each(|(block, rows)| {
            // Out of the thread's cell for the block and back after it (a call made from
            // inside a block, were there one, would find the cell empty and make its own).
            let mut buffers = BLOCK_BUFFERS.take();
            let (cache, made) = buffers.prepare(setup.len(), width, blend);
            make_block(
                &setup,
                width,
                block * ROWS_PER_BLOCK,
                rows,
                cache,
                made,
                blend,
            );
            BLOCK_BUFFERS.set(buffers);
        });
}

/// One coarse level of an upsampling pass.
struct Level<'a> {
    coarse: &'a HdrImage,
    /// The coarse frame's width.
    width: usize,
    /// `1 / factor²`.
    norm: f32,
    /// The weights along x, and per output row the coarse rows and weight along y.
    runs: Runs,
    ys: Vec<(usize, usize, f32)>,
    /// Per coarse row, columns holding every non-zero pixel of it (its first to its last
    /// lit one, or wider).
    spans: &'a [(usize, usize)],
}

/// Makes the output rows `rows` (whole rows of `width` pixels, the first one row `y0` of the
/// frame) from `levels`, with `cache` (two full-width rows per level, holding none) and, when
/// replacing, `made` (a row's floats). Compiled for AVX2 and AVX-512 too, chosen at run time: the
/// interpolation is plain f32 arithmetic (no fused multiply–adds), the same bits either way.
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma"
))]
fn make_block(
    levels: &[Level<'_>],
    width: usize,
    y0: usize,
    rows: &mut [[f32; 3]],
    cache: &mut [[WideRow; 2]],
    made: &mut [f32],
    blend: Blend,
) {
    for (k, out_row) in rows.chunks_exact_mut(width).enumerate() {
        let y = y0 + k;
        let out_row = out_row.as_flattened_mut();
        let row: &mut [f32] = match blend {
            Blend::Replace => {
                made.fill(0.0);
                &mut *made
            }
            Blend::Add => out_row,
        };
        for (level, pair) in levels.iter().zip(&mut *cache) {
            let (j0, j1, ty) = level.ys[y];
            let spans = &level.spans;
            if spans[j0].0 >= spans[j0].1 && spans[j1].0 >= spans[j1].1 {
                continue;
            }
            let [w0, w1] = pair;
            // Keep whichever cached row is wanted in the first slot.
            if w1.row == Some(j0) || w0.row == Some(j1) {
                std::mem::swap(w0, w1);
            }
            let (pixels, cw) = (&level.coarse.pixels, level.width);
            let at = |j: usize| &pixels[j * cw..(j + 1) * cw];
            w0.fill(j0, at(j0), spans[j0], &level.runs, level.norm);
            w1.fill(j1, at(j1), spans[j1], &level.runs, level.norm);
            add_between(row, w0, w1, ty);
        }
        if blend == Blend::Replace {
            // SAFETY: the block's rows are fenced below, before this function returns (and
            // rayon hands the memory back).
            unsafe { stream_into(out_row, made) };
        }
    }
    if blend == Blend::Replace {
        stream_fence();
    }
}

thread_local! {
    /// Each thread's buffers for [`upsample_spans_into`]'s blocks, kept from call to call (a
    /// frame's pass is some 34 blocks; fresh buffers for each were freshly mapped pages,
    /// zeroed by the kernel, every frame). They grow to the widest frame and the most levels
    /// a thread has made: for 1920 pixels and three levels, 160 KB.
    static BLOCK_BUFFERS: std::cell::Cell<BlockBuffers> =
        const { std::cell::Cell::new(BlockBuffers { rows: Vec::new(), made: Vec::new() }) };
}

/// A block's two cached full-width rows per level, and (replacing) the row being made.
#[derive(Default)]
struct BlockBuffers {
    rows: Vec<[WideRow; 2]>,
    made: Vec<f32>,
}

impl BlockBuffers {
    /// The buffers for a block of `levels` levels and `width` pixels, every cached row
    /// forgotten (the coarse frames are another call's, or another block's rows).
    fn prepare(
        &mut self,
        levels: usize,
        width: usize,
        blend: Blend,
    ) -> (&mut [[WideRow; 2]], &mut [f32]) {
        if self.rows.len() < levels {
            self.rows.resize_with(levels, Default::default);
        }
        for w in self.rows.iter_mut().flatten() {
            w.forget(width);
        }
        let made_len = match blend {
            Blend::Replace => 3 * width,
            Blend::Add => 0,
        };
        if self.made.len() < made_len {
            self.made.resize(made_len, 0.0);
        }
        (&mut self.rows[..levels], &mut self.made[..made_len])
    }
}

/// Copies `src` into `dst` (the same length) with stores that bypass the cache where the
/// target has them (x86-64's `movntps`): a frame replaced row by row is written without being
/// read first, half the memory traffic of an ordinary store's read-for-ownership.
///
/// # Safety
/// Streaming stores are weakly ordered: the calling thread must call [`stream_fence`] after
/// it and before `dst` is accessed again (by any thread) — once for many rows is enough.
#[inline(always)]
unsafe fn stream_into(dst: &mut [f32], src: &[f32]) {
    assert_eq!(dst.len(), src.len(), "same length");
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_loadu_ps, _mm_stream_ps};
        // Up to the first 16-byte boundary by ordinary stores.
        let head = dst.as_ptr().align_offset(16).min(dst.len());
        dst[..head].copy_from_slice(&src[..head]);
        let n = dst.len();
        let (body, tail) = dst[head..].split_at_mut((n - head) / 4 * 4);
        for (d, s) in body.chunks_exact_mut(4).zip(src[head..].chunks_exact(4)) {
            // SAFETY: `d` is 4 f32s at a 16-byte aligned address (from `head`; the chunks
            // keep the alignment) and `s` 4 readable f32s; SSE is part of x86-64.
            unsafe { _mm_stream_ps(d.as_mut_ptr(), _mm_loadu_ps(s.as_ptr())) };
        }
        let done = head + body.len();
        tail.copy_from_slice(&src[done..]);
    }
    #[cfg(not(target_arch = "x86_64"))]
    dst.copy_from_slice(src);
}

/// Orders the streaming stores of [`stream_into`] before whatever the thread does next (a
/// streaming store is weakly ordered): called once per block of rows.
fn stream_fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `sfence` only orders stores; SSE is part of x86-64.
    unsafe {
        std::arch::x86_64::_mm_sfence()
    };
}

/// The pixels of `row` from its first to its last with a channel that is not zero (`(0, 0)`
/// when there is none). The floats are tested by their bits, 16 at a time (a value is zero
/// when all but its sign bit are: `v != 0.0`, NaN included), which the compiler vectorizes:
/// most of a coarse frame is black and is read only here.
fn lit_span(row: &[[f32; 3]]) -> (usize, usize) {
    const CHUNK: usize = 16;
    let floats = row.as_flattened();
    let lit = |v: &f32| v.to_bits() << 1 != 0;
    let any_lit = |c: &[f32]| c.iter().fold(0_u32, |acc, v| acc | (v.to_bits() << 1)) != 0;
    // The first lit float: past whole black chunks, then one by one.
    let black = floats.chunks(CHUNK).take_while(|c| !any_lit(c)).count();
    let head = (black * CHUNK).min(floats.len());
    let Some(first) = floats[head..].iter().position(lit).map(|k| head + k) else {
        return (0, 0);
    };
    // The last lit float, from the end (which `first` bounds).
    let rest = &floats[first..];
    let black_tail = rest.rchunks(CHUNK).take_while(|c| !any_lit(c)).count() * CHUNK;
    let body = &rest[..rest.len() - black_tail.min(rest.len())];
    let last = first + body.iter().rposition(lit).unwrap_or(0);
    (first / 3, last / 3 + 1)
}

/// Adds `(1 − t) a + t b` to `row`, where `a` and `b` are zero outside their lit ranges.
#[inline(always)]
fn add_between(row: &mut [f32], a: &WideRow, b: &WideRow, t: f32) {
    let (la, lb) = (a.lit.clone(), b.lit.clone());
    let both = la.start.max(lb.start)..la.end.min(lb.end);
    if both.start < both.end {
        let (va, vb) = (&a.values[both.clone()], &b.values[both.clone()]);
        for ((p, &x), &y) in row[both.clone()].iter_mut().zip(va).zip(vb) {
            *p += x + t * (y - x);
        }
    }
    // Where only one of the two is lit (each lit range less the overlap: up to two pieces).
    for (w, wide) in [(1.0 - t, a), (t, b)] {
        let lit = &wide.lit;
        let pieces = if both.start < both.end {
            [lit.start..both.start, both.end..lit.end]
        } else {
            [lit.clone(), 0..0]
        };
        for piece in pieces {
            if piece.start < piece.end {
                for (p, &x) in row[piece.clone()].iter_mut().zip(&wide.values[piece]) {
                    *p += w * x;
                }
            }
        }
    }
}

/// Output rows per block of [`upsample_levels_into`]'s pass (each block reuses its
/// levels' full-width rows).
const ROWS_PER_BLOCK: usize = 32;

/// One coarse row interpolated along x to the full width (three f32s a pixel, already
/// divided by `factor²`): zero outside `lit` (indices into `values`), where `values` holds
/// whatever an earlier row left and is not read.
#[derive(Default)]
struct WideRow {
    row: Option<usize>,
    values: Vec<f32>,
    lit: std::ops::Range<usize>,
}

impl WideRow {
    /// Holds no row, with room for `width` pixels.
    fn forget(&mut self, width: usize) {
        self.row = None;
        self.lit = 0..0;
        // One float of slack: `fill` writes a pixel's three as four.
        if self.values.len() < 3 * width + 1 {
            self.values.resize(3 * width + 1, 0.0);
        }
    }

    /// Makes this coarse row `j` (`pixels`, lit over columns `span`), unless it already is.
    #[inline(always)]
    fn fill(
        &mut self,
        j: usize,
        pixels: &[[f32; 3]],
        span: (usize, usize),
        runs: &Runs,
        norm: f32,
    ) {
        if self.row == Some(j) {
            return;
        }
        self.row = Some(j);
        self.lit = 0..0;
        let (c0, c1) = span;
        if c0 >= c1 {
            return;
        }
        // The runs that read a lit column (the weights are monotone in x).
        let first = runs.spans.partition_point(|r| r.i1 < c0);
        let (mut start, mut end) = (usize::MAX, 0);
        for r in &runs.spans[first..] {
            if r.i0 >= c1 {
                break;
            }
            let (a, b) = (pixels[r.i0], pixels[r.i1]);
            // `a + tx (b − a)`, scaled, as four lanes (the fourth is zero): each pixel written
            // by one 16-byte store whose last float the next pixel's store (or the row's
            // slack) takes.
            let base = [norm * a[0], norm * a[1], norm * a[2], 0.0];
            let rise = [
                norm * (b[0] - a[0]),
                norm * (b[1] - a[1]),
                norm * (b[2] - a[2]),
                0.0,
            ];
            let out = &mut self.values[3 * r.x0..3 * r.x1 + 1];
            for (k, &tx) in runs.tx[r.x0..r.x1].iter().enumerate() {
                let v: [f32; 4] = std::array::from_fn(|c| base[c] + tx * rise[c]);
                out[3 * k..3 * k + 4].copy_from_slice(&v);
            }
            start = start.min(3 * r.x0);
            end = 3 * r.x1;
        }
        if start < end {
            self.lit = start..end;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_share_the_frame_centre() {
        let g = CoarseGrid::for_frame(1920, 1080, 16);
        assert_eq!((g.width, g.height), (120, 68));
        assert_eq!(g.offset, [0.0, 4.0]);
        // Coarse centre (68 / 2 = 34 coarse px) is at 34·16 − 4 = 540 full px.
        assert_eq!(g.height as f64 * 0.5 * 16.0 - g.offset[1], 540.0);
        let g = CoarseGrid::for_frame(7, 5, 1);
        assert_eq!((g.width, g.height, g.offset), (7, 5, [0.0, 0.0]));
    }

    #[test]
    fn a_constant_is_reproduced_exactly_and_energy_kept() {
        let grid = CoarseGrid::for_frame(64, 48, 4);
        let mut coarse = HdrImage::new(grid.width, grid.height);
        for p in &mut coarse.pixels {
            *p = [16.0, 32.0, 48.0];
        }
        let mut dst = HdrImage::new(64, 48);
        add_upsampled(&mut dst, &coarse, &grid);
        assert!(dst.pixels.iter().all(|p| *p == [1.0, 2.0, 3.0]));
        assert_eq!(dst.sum()[0], coarse.sum()[0]);
    }

    #[test]
    fn a_linear_ramp_is_interpolated_exactly_inside() {
        // Coarse energy 4·(I + 0.5) per pixel ⇒ density (I + 0.5)/… : linear in x.
        let grid = CoarseGrid::for_frame(32, 8, 2);
        let mut coarse = HdrImage::new(grid.width, grid.height);
        for (k, p) in coarse.pixels.iter_mut().enumerate() {
            let i = (k % grid.width) as f32;
            *p = [4.0 * i; 3];
        }
        let mut dst = HdrImage::new(32, 8);
        add_upsampled(&mut dst, &coarse, &grid);
        // Full pixel x has coarse coordinate u = (x + 0.5)/2 − 0.5: density = u.
        for x in 1..31 {
            let u = (x as f32 + 0.5) / 2.0 - 0.5;
            assert!((dst.get(x, 3).unwrap()[0] - u).abs() < 1e-6, "x {x}");
        }
    }

    #[test]
    fn odd_sizes_and_factor_one() {
        let grid = CoarseGrid::for_frame(5, 3, 1);
        let mut coarse = HdrImage::new(5, 3);
        coarse.pixels[7] = [1.0, 0.0, 0.0];
        let mut dst = HdrImage::new(5, 3);
        add_upsampled(&mut dst, &coarse, &grid);
        assert_eq!(dst, coarse);
        let grid = CoarseGrid::for_frame(5, 3, 8);
        assert_eq!((grid.width, grid.height), (1, 1));
        let mut coarse = HdrImage::new(1, 1);
        coarse.pixels[0] = [64.0; 3];
        let mut dst = HdrImage::new(5, 3);
        add_upsampled(&mut dst, &coarse, &grid);
        assert!(dst.pixels.iter().all(|p| *p == [1.0; 3]));
    }

    #[test]
    fn levels_in_one_pass_match_each_level_interpolated_alone() {
        let (w, h) = (37, 23);
        let mut seq = HdrImage::new(w, h);
        for (k, p) in seq.pixels.iter_mut().enumerate() {
            *p = [k as f32 * 0.01, 1.0, 0.5];
        }
        let mut fused = seq.clone();
        let levels: Vec<(HdrImage, CoarseGrid)> = [1, 2, 4, 8, 16]
            .iter()
            .map(|&f| {
                let grid = CoarseGrid::for_frame(w, h, f);
                let mut img = HdrImage::new(grid.width, grid.height);
                for (k, p) in img.pixels.iter_mut().enumerate() {
                    let v = ((k * 7919 + f) % 13) as f32;
                    *p = [v, 2.0 * v, f as f32];
                }
                (img, grid)
            })
            .collect();
        for (img, grid) in &levels {
            dense(&mut seq.pixels, w, img, grid);
        }
        let refs: Vec<(&HdrImage, &CoarseGrid)> = levels.iter().map(|(i, g)| (i, g)).collect();
        add_upsampled_levels_into(&mut fused.pixels, w, &refs);
        for (a, b) in seq.pixels.iter().zip(&fused.pixels) {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-5 * a[c].abs().max(1.0),
                    "{a:?} {b:?}"
                );
            }
        }
        // No levels: nothing changes.
        let before = fused.clone();
        add_upsampled_levels_into(&mut fused.pixels, w, &[]);
        assert_eq!(fused, before);
    }

    #[test]
    fn a_row_s_lit_span_is_its_first_to_last_pixel_with_a_channel_not_zero() {
        let naive = |row: &[[f32; 3]]| {
            let lit = |p: &[f32; 3]| p.iter().any(|&v| v != 0.0);
            match row.iter().position(lit) {
                Some(first) => (first, row.iter().rposition(lit).unwrap_or(first) + 1),
                None => (0, 0),
            }
        };
        let odd = [1.0, -0.0, f32::NAN, 1e-45, -3.0, f32::INFINITY];
        for len in [0, 1, 2, 5, 6, 16, 17, 33, 100] {
            let mut row = vec![[0.0_f32; 3]; len];
            assert_eq!(lit_span(&row), naive(&row), "black, {len}");
            for a in 0..len {
                for b in [a, (a + 7) % len, len - 1] {
                    for (k, &v) in odd.iter().enumerate() {
                        row.fill([0.0; 3]);
                        row[a][k % 3] = v;
                        row[b][(k + 1) % 3] = odd[(k + 1) % odd.len()];
                        assert_eq!(lit_span(&row), naive(&row), "{len} {a} {b} {v}");
                    }
                }
            }
        }
    }

    #[test]
    fn streamed_copies_are_exact_at_any_alignment_and_length() {
        let src: Vec<f32> = (0..67).map(|k| k as f32 * 0.5 - 3.0).collect();
        for start in 0..4 {
            for len in [0, 1, 3, 4, 5, 17, 63] {
                let mut dst = vec![f32::NAN; 70];
                // SAFETY: fenced before `dst` is read.
                unsafe { stream_into(&mut dst[start..start + len], &src[..len]) };
                stream_fence();
                assert_eq!(&dst[start..start + len], &src[..len], "{start} {len}");
                assert!(dst[..start].iter().all(|v| v.is_nan()));
                assert!(dst[start + len..].iter().all(|v| v.is_nan()));
            }
        }
    }

    #[test]
    fn spans_wider_than_the_lit_ones_give_the_same_image() {
        let (w, h) = (41, 23);
        let grid = CoarseGrid::for_frame(w, h, 4);
        let mut coarse = HdrImage::new(grid.width, grid.height);
        coarse.pixels[grid.width + 3] = [4.0, 8.0, 16.0];
        coarse.pixels[3 * grid.width + 7] = [1.0, 0.0, 2.0];
        let mut own = HdrImage::new(w, h);
        upsample_levels_into(&mut own.pixels, w, &[(&coarse, &grid)], Blend::Replace);
        let wide = vec![(0, grid.width); grid.height];
        let mut wider = HdrImage::new(w, h);
        wider.pixels.fill([f32::NAN; 3]);
        upsample_spans_into(
            &mut wider.pixels,
            w,
            &[(&coarse, &grid, &wide)],
            Blend::Replace,
        );
        assert!(own.pixels == wider.pixels);
        assert!(own.luminance_sum() > 0.0);
    }

    #[test]
    fn replacing_equals_adding_to_black_whatever_the_buffer_held() {
        // Two row blocks and a bit, sparse levels: some output rows see no lit level.
        let (w, h) = (41, 2 * ROWS_PER_BLOCK + 5);
        let levels: Vec<(HdrImage, CoarseGrid)> = [2, 8]
            .iter()
            .map(|&f| {
                let grid = CoarseGrid::for_frame(w, h, f);
                let mut img = HdrImage::new(grid.width, grid.height);
                img.pixels[grid.width + 1] = [f as f32, 1.0, 0.25];
                (img, grid)
            })
            .collect();
        let refs: Vec<(&HdrImage, &CoarseGrid)> = levels.iter().map(|(i, g)| (i, g)).collect();
        let mut added = HdrImage::new(w, h);
        upsample_levels_into(&mut added.pixels, w, &refs, Blend::Add);
        assert!(added.sum()[0] > 0.0);
        let mut stale = HdrImage::new(w, h);
        stale.pixels.fill([7.0, f32::NAN, -3.0]);
        upsample_levels_into(&mut stale.pixels, w, &refs, Blend::Replace);
        assert_eq!(stale, added);
        // No levels: replacing clears.
        upsample_levels_into(&mut stale.pixels, w, &[], Blend::Replace);
        assert_eq!(stale, HdrImage::new(w, h));
    }

    /// Every pixel of every level interpolated, black or not: what the span-skipping pass
    /// must reproduce.
    fn dense(dst: &mut [[f32; 3]], width: usize, coarse: &HdrImage, grid: &CoarseGrid) {
        let height = dst.len() / width;
        let norm = 1.0 / (grid.factor * grid.factor) as f32;
        let xs = axis_weights(width, grid.width, grid.factor, grid.offset[0]);
        let ys = axis_weights(height, grid.height, grid.factor, grid.offset[1]);
        for (y, row) in dst.chunks_mut(width).enumerate() {
            let (j0, j1, ty) = ys[y];
            for (p, &(i0, i1, tx)) in row.iter_mut().zip(&xs) {
                let at = |j: usize, i: usize| coarse.pixels[j * grid.width + i];
                for (c, v) in p.iter_mut().enumerate() {
                    let a = at(j0, i0)[c] + ty * (at(j1, i0)[c] - at(j0, i0)[c]);
                    let b = at(j0, i1)[c] + ty * (at(j1, i1)[c] - at(j0, i1)[c]);
                    *v += norm * (a + tx * (b - a));
                }
            }
        }
    }

    proptest::proptest! {
        /// Sparse levels of any factors over frames of several row blocks: the pass (rows
        /// interpolated along x once per block and thread, then along y; each lit range and
        /// their overlap apart) gives every pixel what interpolating every level densely does.
        #[test]
        fn sparse_levels_match_dense_interpolation(
            w in 1_usize..150,
            h in 1_usize..120,
            factors in proptest::collection::vec(0_u32..5, 1..4),
            lit in proptest::collection::vec((0.0_f64..1.0, 0.0_f64..1.0, 0.1_f32..10.0), 1..40),
        ) {
            let mut want = HdrImage::new(w, h);
            let mut got = HdrImage::new(w, h);
            let mut levels = Vec::new();
            for (n, f) in factors.iter().enumerate() {
                let grid = CoarseGrid::for_frame(w, h, 1 << f);
                let mut img = HdrImage::new(grid.width, grid.height);
                for (k, &(x, y, v)) in lit.iter().enumerate().filter(|(k, _)| k % factors.len() == n) {
                    let (i, j) = ((x * grid.width as f64) as usize, (y * grid.height as f64) as usize);
                    img.pixels[j * grid.width + i] = [v, 1.0 + k as f32, 0.5 * v];
                }
                dense(&mut want.pixels, w, &img, &grid);
                levels.push((img, grid));
            }
            let refs: Vec<(&HdrImage, &CoarseGrid)> = levels.iter().map(|(i, g)| (i, g)).collect();
            add_upsampled_levels_into(&mut got.pixels, w, &refs);
            for (a, b) in want.pixels.iter().zip(&got.pixels) {
                for c in 0..3 {
                    proptest::prop_assert!((a[c] - b[c]).abs() <= 1e-5 * a[c].abs().max(1.0), "{:?} {:?}", a, b);
                }
            }
        }
    }

    #[test]
    fn black_parts_of_sparse_levels_are_skipped_without_changing_the_sum() {
        let (w, h) = (53, 31);
        let mut want = HdrImage::new(w, h);
        let mut got = HdrImage::new(w, h);
        let mut levels = Vec::new();
        for (f, lit) in [
            (2, [(3, 4), (3, 5), (9, 0)]),
            (4, [(0, 0), (13, 7), (6, 3)]),
        ] {
            let grid = CoarseGrid::for_frame(w, h, f);
            let mut img = HdrImage::new(grid.width, grid.height);
            for (i, j) in lit {
                let (i, j) = (i.min(grid.width - 1), j.min(grid.height - 1));
                img.pixels[j * grid.width + i] = [1.0 + i as f32, 2.0, j as f32];
            }
            dense(&mut want.pixels, w, &img, &grid);
            levels.push((img, grid));
        }
        let refs: Vec<(&HdrImage, &CoarseGrid)> = levels.iter().map(|(i, g)| (i, g)).collect();
        add_upsampled_levels_into(&mut got.pixels, w, &refs);
        for (a, b) in want.pixels.iter().zip(&got.pixels) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-6, "{a:?} {b:?}");
            }
        }
        assert!(got.sum()[0] > 0.0);
    }
}

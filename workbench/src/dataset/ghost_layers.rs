//! A sample's ghost layers made from its ghosts drawn alone
//! (`ghost_raytrace::tiles::render_ghost_tiles`, each in the window it lights): the ghosts'
//! sum, each light's ghosts' sum and the ID layer.
//!
//! Every pixel adds its ghosts in plan order, so the layers do not depend on the thread count
//! (rows are spread over the cores, each row's pixels made by one thread). The ID layer holds,
//! per pixel, the `id` (1-based, plan order) of the ghost adding the most luminance there; the
//! first in plan order on a tie; 0 where none lights it.

use flarebench_sdk::color::srgb::luminance_f32;
use flarebench_sdk::image::HdrImage;
use ghost_raytrace::tiles::GhostTile;
use rayon::prelude::*;

/// Adds each tile of `tiles` (in the order given) to `out`, pixel by pixel.
pub fn add_tiles(out: &mut HdrImage, tiles: &[&GhostTile]) {
    let width = out.width;
    if width == 0 {
        return;
    }
    out.pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            for t in tiles {
                if let Some(src) = tile_row(t, y) {
                    for (o, p) in row[t.x0..t.x0 + src.len()].iter_mut().zip(src) {
                        for c in 0..3 {
                            o[c] += p[c];
                        }
                    }
                }
            }
        });
}

/// The ID layer of `tiles` (plan order) on a `width × height` frame, row-major.
pub fn ghost_ids(width: usize, height: usize, tiles: &[GhostTile]) -> Vec<u32> {
    let mut ids = vec![0u32; width * height];
    if width == 0 {
        return ids;
    }
    ids.par_chunks_mut(width)
        .enumerate()
        .for_each_init(Vec::new, |best, (y, row)| {
            best.clear();
            best.resize(width, 0f32);
            for (k, t) in tiles.iter().enumerate() {
                if let Some(src) = tile_row(t, y) {
                    let span = t.x0..t.x0 + src.len();
                    for ((p, b), i) in src.iter().zip(&mut best[span.clone()]).zip(&mut row[span]) {
                        let l = luminance_f32(*p);
                        if l > *b {
                            *b = l;
                            *i = k as u32 + 1;
                        }
                    }
                }
            }
        });
    ids
}

/// Row `y` of the frame within `t`'s window, or `None` when the window misses it.
fn tile_row(t: &GhostTile, y: usize) -> Option<&[[f32; 3]]> {
    let w = t.image.width;
    (y >= t.y0 && y < t.y0 + t.image.height && w > 0)
        .then(|| &t.image.pixels[(y - t.y0) * w..(y - t.y0 + 1) * w])
}

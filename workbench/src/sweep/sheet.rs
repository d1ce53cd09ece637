//! Thumbnails of a sweep's images and the contact sheet that tiles them, each under its
//! label, time and error.

use flarebench_sdk::image::HdrImage;

use crate::label;

/// Widest thumbnail (pixels).
pub const THUMB_WIDTH: usize = 240;

/// `img` shrunk by the smallest whole factor that makes it at most `max_width` wide, each
/// thumbnail pixel the mean of its block (energy per pixel kept).
pub fn thumbnail(img: &HdrImage, max_width: usize) -> HdrImage {
    let f = img.width.div_ceil(max_width.max(1)).max(1);
    let (w, h) = (img.width / f, img.height / f);
    let mut out = HdrImage::new(w, h);
    let inv = 1.0 / (f * f) as f32;
    for y in 0..h {
        for x in 0..w {
            let mut s = [0.0f32; 3];
            for dy in 0..f {
                let row = (y * f + dy) * img.width + x * f;
                for p in &img.pixels[row..row + f] {
                    for c in 0..3 {
                        s[c] += p[c];
                    }
                }
            }
            out.pixels[y * w + x] = [s[0] * inv, s[1] * inv, s[2] * inv];
        }
    }
    out
}

/// One tile of a contact sheet.
#[derive(Debug)]
pub struct Tile<'a> {
    pub image: Option<&'a HdrImage>,
    /// Up to two lines of text above the image.
    pub lines: [String; 2],
}

const SCALE: usize = 2;
const LINE: usize = label::GLYPH_H * SCALE + 4;
const GAP: usize = 6;

/// The tiles in rows of `columns`, each `w × h` under its two lines; text drawn at `white`
/// (a linear value above the tone curve's white point). Missing images stay black.
pub fn contact_sheet(
    tiles: &[Tile<'_>],
    columns: usize,
    w: usize,
    h: usize,
    white: f32,
) -> HdrImage {
    let columns = columns.clamp(1, tiles.len().max(1));
    let rows = tiles.len().div_ceil(columns);
    let (tw, th) = (w + GAP, 2 * LINE + h + GAP);
    let mut out = HdrImage::new(columns * tw + GAP, rows * th + GAP);
    let chars = w / (label::ADVANCE * SCALE);
    for (i, t) in tiles.iter().enumerate() {
        let (x0, y0) = (GAP + (i % columns) * tw, GAP + (i / columns) * th);
        for (k, line) in t.lines.iter().enumerate() {
            let text: String = line.chars().take(chars).collect();
            label::draw(&mut out, x0, y0 + k * LINE, &text, SCALE, [white; 3]);
        }
        if let Some(img) = t.image {
            for y in 0..h.min(img.height) {
                for x in 0..w.min(img.width) {
                    out.pixels[(y0 + 2 * LINE + y) * out.width + x0 + x] =
                        img.pixels[y * img.width + x];
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thumbnail_keeps_the_mean() {
        let mut img = HdrImage::new(960, 540);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [(i % 7) as f32, 1.0, 0.0];
        }
        let t = thumbnail(&img, 240);
        assert_eq!((t.width, t.height), (240, 135));
        let mean = |im: &HdrImage| {
            im.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / im.pixels.len() as f64
        };
        assert!(
            (mean(&t) - mean(&img)).abs() < 1e-3,
            "{} {}",
            mean(&t),
            mean(&img)
        );
        assert_eq!(thumbnail(&img, 2000).width, 960);
    }

    #[test]
    fn tiles_are_placed_in_rows_with_their_images() {
        let mut a = HdrImage::new(10, 5);
        a.pixels.iter_mut().for_each(|p| *p = [2.0; 3]);
        let tiles: Vec<Tile<'_>> = (0..3)
            .map(|i| Tile {
                image: (i != 1).then_some(&a),
                lines: [format!("t{i}"), String::new()],
            })
            .collect();
        let s = contact_sheet(&tiles, 2, 10, 5, 9.0);
        assert_eq!(s.width, 2 * (10 + GAP) + GAP);
        assert_eq!(s.height, 2 * (2 * LINE + 5 + GAP) + GAP);
        // Tile 0's image, tile 1's missing one, tile 2's on the second row.
        let at = |x: usize, y: usize| s.pixels[y * s.width + x][0];
        assert_eq!(at(GAP, GAP + 2 * LINE), 2.0);
        assert_eq!(at(GAP + 16, GAP + 2 * LINE), 0.0);
        assert_eq!(at(GAP, GAP + (2 * LINE + 5 + GAP) + 2 * LINE + 4), 2.0);
    }
}

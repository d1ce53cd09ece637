//! Text labels drawn into images: a 3 × 5 pixel font (our own, capitals style, for the
//! `compare` tiles), scaled up by whole pixels.

use flarebench_sdk::image::HdrImage;

/// Glyph width and height in font pixels, and the advance from one glyph to the next.
pub const GLYPH_W: usize = 3;
pub const GLYPH_H: usize = 5;
pub const ADVANCE: usize = 4;

/// Rows top to bottom separated by spaces, `#` lit.
fn glyph_rows(c: char) -> &'static str {
    match c.to_ascii_lowercase() {
        'a' => ".#. #.# ### #.# #.#",
        'b' => "##. #.# ##. #.# ##.",
        'c' => ".## #.. #.. #.. .##",
        'd' => "##. #.# #.# #.# ##.",
        'e' => "### #.. ##. #.. ###",
        'f' => "### #.. ##. #.. #..",
        'g' => ".## #.. #.# #.# .##",
        'h' => "#.# #.# ### #.# #.#",
        'i' => "### .#. .#. .#. ###",
        'j' => "..# ..# ..# #.# .#.",
        'k' => "#.# #.# ##. #.# #.#",
        'l' => "#.. #.. #.. #.. ###",
        'm' => "#.# ### ### #.# #.#",
        'n' => "##. #.# #.# #.# #.#",
        'o' => ".#. #.# #.# #.# .#.",
        'p' => "##. #.# ##. #.. #..",
        'q' => ".#. #.# #.# ##. .##",
        'r' => "##. #.# ##. #.# #.#",
        's' => ".## #.. .#. ..# ##.",
        't' => "### .#. .#. .#. .#.",
        'u' => "#.# #.# #.# #.# ###",
        'v' => "#.# #.# #.# #.# .#.",
        'w' => "#.# #.# ### ### #.#",
        'x' => "#.# #.# .#. #.# #.#",
        'y' => "#.# #.# .#. .#. .#.",
        'z' => "### ..# .#. #.. ###",
        '0' => "### #.# #.# #.# ###",
        '1' => ".#. ##. .#. .#. ###",
        '2' => "##. ..# .#. #.. ###",
        '3' => "##. ..# .#. ..# ##.",
        '4' => "#.# #.# ### ..# ..#",
        '5' => "### #.. ##. ..# ##.",
        '6' => ".## #.. ### #.# ###",
        '7' => "### ..# .#. .#. .#.",
        '8' => "### #.# ### #.# ###",
        '9' => "### #.# ### ..# ##.",
        '-' => "... ... ### ... ...",
        '_' => "... ... ... ... ###",
        ':' => "... .#. ... .#. ...",
        '=' => "... ### ... ### ...",
        '.' => "... ... ... ... .#.",
        ',' => "... ... ... .#. #..",
        '(' => ".#. #.. #.. #.. .#.",
        ')' => ".#. ..# ..# ..# .#.",
        '/' => "..# ..# .#. #.. #..",
        '%' => "#.# ..# .#. #.. #.#",
        '*' => "#.# .#. #.# ... ...",
        '+' => "... .#. ### .#. ...",
        ' ' => "... ... ... ... ...",
        _ => "##. ..# .#. ... .#.",
    }
}

/// Whether font pixel (`gx`, `gy`) of `c` is lit.
pub fn lit(c: char, gx: usize, gy: usize) -> bool {
    let rows = glyph_rows(c);
    gx < GLYPH_W && gy < GLYPH_H && rows.as_bytes()[gy * (GLYPH_W + 1) + gx] == b'#'
}

/// Width in image pixels of `text` at `scale`.
pub fn text_width(text: &str, scale: usize) -> usize {
    let n = text.chars().count();
    if n == 0 { 0 } else { (n * ADVANCE - 1) * scale }
}

/// Draws `text` with its top-left corner at (`x0`, `y0`), each font pixel `scale` × `scale`
/// image pixels set to `value`; whatever falls outside the image is left out.
pub fn draw(img: &mut HdrImage, x0: usize, y0: usize, text: &str, scale: usize, value: [f32; 3]) {
    for (i, c) in text.chars().enumerate() {
        for gy in 0..GLYPH_H {
            for gx in 0..GLYPH_W {
                if !lit(c, gx, gy) {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let x = x0 + (i * ADVANCE + gx) * scale + dx;
                        let y = y0 + gy * scale + dy;
                        if let Some(p) = img.get_mut(x, y) {
                            *p = value;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_lights_exactly_its_glyph_pixels_times_the_scale_squared() {
        let mut img = HdrImage::new(64, 16);
        draw(&mut img, 2, 3, "h1", 2, [1.0; 3]);
        // h: 11 lit font pixels, 1: 8.
        let lit_count = img.pixels.iter().filter(|p| p[0] == 1.0).count();
        assert_eq!(lit_count, (11 + 8) * 4);
        // The top-left pixel of `h` is lit, its top middle is not.
        assert_eq!(img.get(2, 3), Some([1.0; 3]));
        assert_eq!(img.get(4, 3), Some([0.0; 3]));
        assert_eq!(text_width("h1", 2), 14);
    }

    #[test]
    fn every_glyph_has_five_rows_of_three() {
        for c in "abcdefghijklmnopqrstuvwxyz0123456789-_:=.,()/% ?".chars() {
            let rows: Vec<&str> = glyph_rows(c).split(' ').collect();
            assert_eq!(rows.len(), GLYPH_H, "{c}");
            assert!(rows.iter().all(|r| r.len() == GLYPH_W), "{c}");
        }
    }
}

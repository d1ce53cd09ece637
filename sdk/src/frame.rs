//! The output image and the part of the sensor it shows: the mapping between sensor
//! millimetres and pixels that every renderer, the plugin ABI and the starburst share.
//!
//! **Image orientation.** The output is the photograph: the sensor image turned by 180°, so a
//! point at sensor (x, y) mm lands at pixel ((0.5 − x/W)·w, (0.5 + y/H)·h), pixel rows downward.

use crate::image::CoarseGrid;

/// The output image and the part of the sensor it shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub film_width_mm: f64,
    pub film_height_mm: f64,
}

impl Frame {
    /// A `width × height` image across a film `film_width_mm` wide, with square pixels (the
    /// film's height follows the image's aspect).
    pub fn across_film(width: usize, height: usize, film_width_mm: f64) -> Frame {
        Frame {
            width,
            height,
            film_width_mm,
            film_height_mm: film_width_mm * height as f64 / width as f64,
        }
    }

    /// Pixel coordinates of sensor point (x, y) mm (photograph orientation).
    pub fn to_pixel(&self, x: f64, y: f64) -> [f32; 2] {
        [
            ((0.5 - x / self.film_width_mm) * self.width as f64) as f32,
            ((0.5 + y / self.film_height_mm) * self.height as f64) as f32,
        ]
    }

    /// Area of one pixel on the sensor (mm²).
    pub fn pixel_area_mm2(&self) -> f64 {
        (self.film_width_mm / self.width as f64) * (self.film_height_mm / self.height as f64)
    }

    /// The frame of the coarse grid `grid` (from [`CoarseGrid::for_frame`] on this frame's
    /// size): same centre and pixel aspect, `grid.factor` times larger pixels, extended to
    /// whole coarse pixels.
    pub fn coarse(&self, grid: &CoarseGrid) -> Frame {
        let f = grid.factor as f64;
        Frame {
            width: grid.width,
            height: grid.height,
            film_width_mm: self.film_width_mm * (grid.width as f64 * f) / self.width as f64,
            film_height_mm: self.film_height_mm * (grid.height as f64 * f) / self.height as f64,
        }
    }

    /// Size of one pixel on the sensor (mm), the larger of its two sides.
    pub fn pixel_mm(&self) -> f64 {
        (self.film_width_mm / self.width as f64).max(self.film_height_mm / self.height as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame across a film keeps square pixels.
    #[test]
    fn a_frame_across_a_film_has_square_pixels() {
        let f = Frame::across_film(1920, 1080, 36.0);
        assert_eq!((f.width, f.height, f.film_width_mm), (1920, 1080, 36.0));
        assert!((f.film_height_mm - 20.25).abs() < 1e-12);
        assert!((f.pixel_area_mm2() - f.pixel_mm() * f.pixel_mm()).abs() < 1e-15);
    }
}

//! An axis-aligned rectangle (mm): the ghost bounds' entrance and sensor regions, and what the
//! bounds files store. A foundation type, so the tracer, the file readers and the ghost
//! machinery share it without depending on one another.

use serde::{Deserialize, Serialize};

/// An axis-aligned rectangle (mm).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rect {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl Rect {
    /// A square of half-size `h` about (cx, cy).
    pub fn square(cx: f64, cy: f64, h: f64) -> Rect {
        Rect {
            x0: cx - h,
            y0: cy - h,
            x1: cx + h,
            y1: cy + h,
        }
    }
    pub fn width(&self) -> f64 {
        self.x1 - self.x0
    }
    pub fn height(&self) -> f64 {
        self.y1 - self.y0
    }
    pub fn area(&self) -> f64 {
        self.width().max(0.0) * self.height().max(0.0)
    }
    /// True when the rectangle has no area (or is not finite).
    pub fn is_empty(&self) -> bool {
        !(self.x1 > self.x0 && self.y1 > self.y0)
    }
    /// Grown by `dx`, `dy` on every side.
    pub fn expand(&self, dx: f64, dy: f64) -> Rect {
        Rect {
            x0: self.x0 - dx,
            y0: self.y0 - dy,
            x1: self.x1 + dx,
            y1: self.y1 + dy,
        }
    }
    /// The smallest rectangle holding both.
    pub fn union(&self, o: &Rect) -> Rect {
        Rect {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }
    /// The bounding box of `points`, or `None` when there are none.
    pub fn bounding(points: impl IntoIterator<Item = [f64; 2]>) -> Option<Rect> {
        let mut r: Option<Rect> = None;
        for [x, y] in points {
            let p = Rect {
                x0: x,
                y0: y,
                x1: x,
                y1: y,
            };
            r = Some(r.map_or(p, |r| r.union(&p)));
        }
        r
    }
    /// Rotated by `phi` about the origin: the bounding box of the rotated corners.
    pub fn rotated(&self, phi: f64) -> Rect {
        let (s, c) = phi.sin_cos();
        let corners = [
            [self.x0, self.y0],
            [self.x1, self.y0],
            [self.x0, self.y1],
            [self.x1, self.y1],
        ];
        Rect::bounding(corners.map(|[x, y]| [x * c - y * s, x * s + y * c])).unwrap_or_default()
    }
}

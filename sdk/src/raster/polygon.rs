//! Small convex polygons on the stack, clipped against axis-aligned lines
//! (Sutherland–Hodgman), with their area and centroid. No allocation.

/// At most 12 vertices: a triangle clipped by 8 axis-aligned half-planes (tile, row, column)
/// gains at most one vertex per half-plane, 3 + 8 = 11.
const CAP: usize = 12;

/// A convex polygon of at most [`CAP`] vertices (f64 pixel coordinates), either winding.
#[derive(Clone, Copy, Debug)]
pub(super) struct Polygon {
    pub(super) len: usize,
    pub(super) v: [[f64; 2]; CAP],
}

impl Polygon {
    pub(super) const EMPTY: Polygon = Polygon {
        len: 0,
        v: [[0.0; 2]; CAP],
    };

    pub(super) fn triangle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Polygon {
        let mut p = Polygon::EMPTY;
        p.v[0] = a;
        p.v[1] = b;
        p.v[2] = c;
        p.len = 3;
        p
    }

    pub(super) fn vertices(&self) -> &[[f64; 2]] {
        &self.v[..self.len]
    }

    /// `[min, max]` of the coordinate `AXIS` (0 = x, 1 = y) over the vertices.
    pub(super) fn range<const AXIS: usize>(&self) -> [f64; 2] {
        let mut r = [f64::INFINITY, f64::NEG_INFINITY];
        for p in self.vertices() {
            r[0] = r[0].min(p[AXIS]);
            r[1] = r[1].max(p[AXIS]);
        }
        r
    }

    /// Copies `other` (only its vertices).
    #[inline]
    pub(super) fn set(&mut self, other: &Polygon) {
        self.len = other.len;
        self.v[..other.len].copy_from_slice(other.vertices());
    }

    /// The part of `self` with `lo ≤ coordinate AXIS ≤ hi`, written to `out` (`tmp` is
    /// scratch). Vertices created on a clip line get exactly `lo` or `hi` as that coordinate.
    pub(super) fn clip_slab<const AXIS: usize>(
        &self,
        lo: f64,
        hi: f64,
        out: &mut Polygon,
        tmp: &mut Polygon,
    ) {
        let [min, max] = self.range::<AXIS>();
        if min >= lo && max <= hi {
            out.set(self);
            return;
        }
        self.clip_half::<AXIS, true>(lo, tmp);
        tmp.clip_half::<AXIS, false>(hi, out);
    }

    /// Sutherland–Hodgman against one line: keeps `coordinate ≥ c` (`KEEP_ABOVE`) or `≤ c`.
    pub(super) fn clip_half<const AXIS: usize, const KEEP_ABOVE: bool>(
        &self,
        c: f64,
        out: &mut Polygon,
    ) {
        out.len = 0;
        let n = self.len;
        if n == 0 {
            return;
        }
        let signed = |p: &[f64; 2]| if KEEP_ABOVE { p[AXIS] - c } else { c - p[AXIS] };
        let mut a = self.v[n - 1];
        let mut da = signed(&a);
        for &b in &self.v[..n] {
            let db = signed(&b);
            if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
                out.push(intersect::<AXIS>(a, b, da, db, c));
            }
            if db >= 0.0 {
                out.push(b);
            }
            a = b;
            da = db;
        }
    }

    #[inline]
    fn push(&mut self, p: [f64; 2]) {
        // A convex polygon clipped by a line gains at most one vertex; the clips applied
        // (4 + 2 + 2 half-planes to a triangle) stay within CAP.
        debug_assert!(self.len < CAP, "polygon capacity exceeded");
        if self.len < CAP {
            self.v[self.len] = p;
            self.len += 1;
        }
    }

    /// `(area, centroid)` by the shoelace formula, computed relative to `origin` for
    /// precision: `2A = Σ (x_i y_{i+1} − x_{i+1} y_i)`,
    /// `C = Σ (p_i + p_{i+1}) (x_i y_{i+1} − x_{i+1} y_i) / (6A)`. Area 0 for a degenerate
    /// polygon (then the centroid is `origin`).
    #[cfg(test)]
    pub(super) fn area_centroid(&self, origin: [f64; 2]) -> (f64, [f64; 2]) {
        let n = self.len;
        if n < 3 {
            return (0.0, origin);
        }
        let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
        let rel = |p: [f64; 2]| [p[0] - origin[0], p[1] - origin[1]];
        let mut p = rel(self.v[n - 1]);
        for &q in &self.v[..n] {
            let q = rel(q);
            let cross = p[0] * q[1] - q[0] * p[1];
            a2 += cross;
            cx += (p[0] + q[0]) * cross;
            cy += (p[1] + q[1]) * cross;
            p = q;
        }
        if a2 == 0.0 {
            return (0.0, origin);
        }
        let k = 1.0 / (3.0 * a2);
        (0.5 * a2.abs(), [origin[0] + cx * k, origin[1] + cy * k])
    }
}

/// The point of segment `a → b` on the line `coordinate AXIS = c`, given the signed distances
/// `da`, `db` (of opposite signs) of its ends; that coordinate is set to `c` exactly.
#[inline]
fn intersect<const AXIS: usize>(a: [f64; 2], b: [f64; 2], da: f64, db: f64, c: f64) -> [f64; 2] {
    let t = da / (da - db);
    let mut p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    p[AXIS] = c;
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_square_clipped_to_half_has_the_right_area_and_centroid() {
        let mut sq = Polygon::EMPTY;
        for p in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
            sq.push(p);
        }
        let (mut half, mut tmp) = (Polygon::EMPTY, Polygon::EMPTY);
        sq.clip_slab::<0>(0.25, 0.75, &mut half, &mut tmp);
        let (a, c) = half.area_centroid([0.0, 0.0]);
        assert!((a - 0.5).abs() < 1e-15);
        assert!((c[0] - 0.5).abs() < 1e-15 && (c[1] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn triangle_area_and_centroid_in_either_winding() {
        let t = Polygon::triangle([0.0, 0.0], [3.0, 0.0], [0.0, 3.0]);
        let r = Polygon::triangle([0.0, 0.0], [0.0, 3.0], [3.0, 0.0]);
        for p in [t, r] {
            let (a, c) = p.area_centroid([10.0, -4.0]);
            assert!((a - 4.5).abs() < 1e-12);
            assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn clipping_to_a_slab_keeps_the_part_inside() {
        let t = Polygon::triangle([0.0, 0.0], [4.0, 0.0], [0.0, 4.0]);
        let (mut s, mut tmp) = (Polygon::EMPTY, Polygon::EMPTY);
        t.clip_slab::<1>(1.0, 2.0, &mut s, &mut tmp);
        // Trapezoid between y = 1 and 2: (3 + 2) / 2 = 2.5.
        assert!((s.area_centroid([0.0, 0.0]).0 - 2.5).abs() < 1e-15);
        let mut none = Polygon::EMPTY;
        t.clip_slab::<0>(5.0, 6.0, &mut none, &mut tmp);
        assert_eq!(none.area_centroid([0.0, 0.0]).0, 0.0);
    }
}

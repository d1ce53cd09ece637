//! The iris: n blades whose tips lie on the unit circle, joined by straight edges or by
//! circular arcs of curvature κ (0 straight, 1 the unit circle) bulging outward.
//!
//! Every edge is the same up to rotation and reflection, so a point is folded into the
//! half-sector between the normal of its nearest edge (the +x axis of the folded frame) and the ray
//! through its blade tip `V = (a, c)`, `a = cos(π/n)`, `c = sin(π/n)`. Mirroring across
//! either side of that wedge never brings a boundary point closer, so the distance to the
//! shape is the distance to that half-edge — exact, inside and outside.
//!
//! The arc has radius `R = 1/κ` and passes through both tips; its centre sits on the edge
//! normal at `x = a − √(R² − c²)` and its middle lies `s = R − √(R² − c²)` beyond the chord
//! (the sagitta). Everything is written with κ instead of R, so κ = 0 (an infinite radius)
//! is the straight edge of the same formulas:
//!
//! - `w = κ·(a − x_centre) = √(1 − κ²c²)`, `s = κc² / (1 + w)`;
//! - a point `(x, y)` beyond the ray from the centre through V (cross product
//!   `w·y − c·(κ(x − a) + w) > 0`) is outside and nearest to V;
//! - otherwise its distance to the arc is `(|p − C|² − R²) / (|p − C| + R)`, which with
//!   `e = x − a − s` is `(κ(e² + y²) + 2e) / (κ|p − C| + 1)`, `κ|p − C| = |(κ(x − a) + w, κy)|`
//!   — no cancellation as κ → 0, where it becomes `e = x − a`.

use std::f64::consts::PI;

#[derive(Clone, Copy, Debug)]
/// An iris's constants, as the signed distance uses them (public for the GPU backend, which
/// evaluates the same formulas).
pub struct IrisGeometry {
    /// Number of blades (at least 3).
    pub n: f64,
    /// Angle of blade tip 0 from the +u axis.
    pub rotation: f64,
    /// 2π/n and π/n.
    pub sector: f64,
    pub half: f64,
    /// cos(π/n) (the straight edge's distance from the centre) and sin(π/n) (half a chord).
    pub a: f64,
    pub c: f64,
    /// Edge curvature relative to the unit circle, 0..=1.
    pub kappa: f64,
    /// √(1 − κ²c²) and the sagitta (module docs).
    pub w: f64,
    pub s: f64,
    /// The first edge's unit normal and the rotation from one edge to the next, (cos, sin):
    /// folding walks the edges and takes the largest `p·normal` — the nearest edge in angle —
    /// instead of an `atan2` (when `by_normals`).
    pub first_normal: [f64; 2],
    pub step: [f64; 2],
    pub by_normals: bool,
}

/// Blade counts up to this fold by walking the edge normals (real irises have 5 to 18
/// blades); more fold through the polar angle.
const MAX_WALK: u32 = 64;

impl IrisGeometry {
    /// The geometry of an iris of `blades` blades (at least 3) turned by `rotation_rad`, its
    /// edges of curvature `roundness` (clamped to 0..=1). Out-of-range values are made usable
    /// (see `Aperture::validate`).
    pub fn new(blades: u32, rotation_rad: f64, roundness: f64) -> Self {
        let n = f64::from(blades.max(3));
        let rotation = if rotation_rad.is_finite() {
            rotation_rad
        } else {
            0.0
        };
        let kappa = if roundness >= 1.0 {
            1.0
        } else if roundness > 0.0 {
            roundness
        } else {
            0.0
        };
        let half = PI / n;
        let (c, a) = half.sin_cos();
        let w = (1.0 - kappa * kappa * c * c).sqrt();
        let (sin0, cos0) = (rotation + half).sin_cos();
        let (sin_step, cos_step) = (2.0 * half).sin_cos();
        IrisGeometry {
            n,
            rotation,
            sector: 2.0 * half,
            half,
            a,
            c,
            kappa,
            w,
            s: kappa * c * c / (1.0 + w),
            first_normal: [cos0, sin0],
            step: [cos_step, sin_step],
            by_normals: blades.max(3) <= MAX_WALK,
        }
    }

    /// `(u, v)` in the folded frame: x along the nearest edge normal, y ≥ 0 across it.
    fn fold(&self, u: f64, v: f64) -> (f64, f64) {
        if self.by_normals {
            // Rotating the normal step by step accumulates about n ulps: nothing at n ≤ 64.
            let [cs, ss] = self.step;
            let mut normal = self.first_normal;
            let mut best = normal;
            let mut x = u * normal[0] + v * normal[1];
            for _ in 1..self.n as u32 {
                normal = [
                    normal[0] * cs - normal[1] * ss,
                    normal[0] * ss + normal[1] * cs,
                ];
                let d = u * normal[0] + v * normal[1];
                if d > x {
                    x = d;
                    best = normal;
                }
            }
            (x, (v * best[0] - u * best[1]).abs())
        } else {
            self.fold_by_angle(u, v)
        }
    }

    /// The same fold through the polar angle (any blade count).
    fn fold_by_angle(&self, u: f64, v: f64) -> (f64, f64) {
        let r = (u * u + v * v).sqrt();
        let psi = (v.atan2(u) - self.rotation).rem_euclid(self.sector);
        let (sin_t, cos_t) = (psi - self.half).abs().sin_cos();
        (r * cos_t, r * sin_t)
    }

    /// Exact signed distance to the edge (negative inside), normalised units.
    /// Signed distance from `(u, v)` to the edge (negative inside), exact.
    pub fn signed_distance(&self, u: f64, v: f64) -> f64 {
        let (x, y) = self.fold(u, v);
        let (a, c, k, w) = (self.a, self.c, self.kappa, self.w);
        let dx = x - a;
        // Plain square roots rather than `hypot`: the terms are far from overflow and
        // `hypot` costs several times more.
        if w * y - c * (k * dx + w) > 0.0 {
            return (dx * dx + (y - c) * (y - c)).sqrt();
        }
        let e = dx - self.s;
        let (kx, ky) = (k * dx + w, k * y);
        let kq = (kx * kx + ky * ky).sqrt();
        (k * (e * e + y * y) + 2.0 * e) / (kq + 1.0)
    }

    /// Open area: the polygon `n·a·c = (n/2) sin(2π/n)` plus n circular segments of radius
    /// 1/κ on chords of half-length c, each `(φ − sin φ cos φ)/κ²` with `sin φ = κc`.
    pub(super) fn area(&self) -> f64 {
        let polygon = self.n * self.a * self.c;
        let (k, c) = (self.kappa, self.c);
        let segment = if k < 1e-6 {
            // Leading order in κ; the next term is smaller by κ²c², below 1e-12.
            2.0 / 3.0 * k * c * c * c
        } else {
            let phi = (k * c).asin();
            let g = if phi < 1e-2 {
                // φ − sin(2φ)/2 by its series: the closed form cancels here. Truncation
                // error below φ⁹/1000, relative 1e-15.
                let p2 = phi * phi;
                phi * p2 * (2.0 / 3.0 - p2 * (2.0 / 15.0 - p2 * (4.0 / 315.0)))
            } else {
                phi - phi.sin() * phi.cos()
            };
            g / (k * k)
        };
        polygon + self.n * segment
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folding_by_normals_equals_folding_by_angle() {
        for blades in [3u32, 5, 8, 13, 64] {
            let g = IrisGeometry::new(blades, 0.7, 0.5);
            assert!(g.by_normals);
            for i in 0..2000 {
                let t = i as f64 * 0.0137;
                let (u, v) = (
                    1.3 * (t * 1.7).sin() * t.cos(),
                    1.3 * (t * 0.9).cos() * t.sin(),
                );
                let (a, b) = (g.fold(u, v), g.fold_by_angle(u, v));
                assert!(
                    (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
                    "{a:?} {b:?}"
                );
            }
        }
        assert!(!IrisGeometry::new(65, 0.0, 0.0).by_normals);
    }
}

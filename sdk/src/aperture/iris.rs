//! The iris: n blades whose tips lie on the unit circle, joined by straight edges or by
//! circular arcs of curvature κ (0 straight, 1 the unit circle) bulging outward.
//!
//! Every edge is the same up to rotation and reflection, so a point is folded into the
//! half-sector between the normal of one edge (the +x axis of the folded frame) and the ray
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
pub(super) struct IrisGeometry {
    /// Number of blades (at least 3).
    n: f64,
    /// Angle of blade tip 0 from the +u axis.
    rotation: f64,
    /// 2π/n and π/n.
    sector: f64,
    half: f64,
    /// cos(π/n) (the straight edge's distance from the centre) and sin(π/n) (half a chord).
    a: f64,
    c: f64,
    /// Edge curvature relative to the unit circle, 0..=1.
    kappa: f64,
    /// √(1 − κ²c²) and the sagitta (module docs).
    w: f64,
    s: f64,
}

impl IrisGeometry {
    /// Out-of-range values are made usable (see `Aperture::validate`).
    pub(super) fn new(blades: u32, rotation_rad: f64, roundness: f64) -> Self {
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
        }
    }

    /// Exact signed distance to the edge (negative inside), normalised units.
    pub(super) fn signed_distance(&self, u: f64, v: f64) -> f64 {
        let r = u.hypot(v);
        let psi = (v.atan2(u) - self.rotation).rem_euclid(self.sector);
        let t = (psi - self.half).abs();
        let (sin_t, cos_t) = t.sin_cos();
        let (x, y) = (r * cos_t, r * sin_t);
        let (a, c, k, w) = (self.a, self.c, self.kappa, self.w);
        let dx = x - a;
        if w * y - c * (k * dx + w) > 0.0 {
            return dx.hypot(y - c);
        }
        let e = dx - self.s;
        let kq = (k * dx + w).hypot(k * y);
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

//! Fresnel reflectance of a bare interface, unpolarised, in the cosine form.
//!
//! With `cos θi` and `cos θt` on either side, `rs = (n1 cos θi − n2 cos θt)/(n1 cos θi + n2 cos θt)`
//! and `rp = (n2 cos θi − n1 cos θt)/(n2 cos θi + n1 cos θt)`; `R = (rs² + rp²)/2`, `T = 1 − R`.
//! Both stay regular at normal incidence (no 0/0 of the tangent form).

/// Reflectances for the two polarisations and their unpolarised mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reflectance {
    pub s: f64,
    pub p: f64,
}

impl Reflectance {
    /// Unpolarised reflectance `(Rs + Rp)/2`.
    pub fn unpolarised(self) -> f64 {
        0.5 * (self.s + self.p)
    }

    /// Unpolarised transmittance `1 − R` (lossless interface).
    pub fn transmittance(self) -> f64 {
        1.0 - self.unpolarised()
    }
}

/// Reflectance of light going from index `n1` into `n2` with `cos_i = cos θi ≥ 0`.
/// Beyond the critical angle it is total: `R = 1`.
pub fn reflectance(n1: f64, n2: f64, cos_i: f64) -> Reflectance {
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return Reflectance { s: 1.0, p: 1.0 };
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    Reflectance {
        s: rs * rs,
        p: rp * rp,
    }
}

/// Unpolarised reflectance, `n1 → n2` at `cos θi`.
pub fn unpolarised(n1: f64, n2: f64, cos_i: f64) -> f64 {
    reflectance(n1, n2, cos_i).unpolarised()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_closed_form() {
        for &(n1, n2) in &[(1.0, 1.5), (1.5, 1.0), (1.0, 1.9), (1.6, 1.5)] {
            let r = unpolarised(n1, n2, 1.0);
            let want = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!((r - want).abs() < 1e-15, "{n1}->{n2}: {r} vs {want}");
        }
    }

    #[test]
    fn brewster_angle_has_no_p_reflection() {
        let (n1, n2): (f64, f64) = (1.0, 1.5168);
        let theta_b = (n2 / n1).atan();
        let r = reflectance(n1, n2, theta_b.cos());
        assert!(r.p < 1e-28, "Rp at Brewster = {}", r.p);
        assert!(r.s > 0.05);
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let (n1, n2): (f64, f64) = (1.5, 1.0);
        let crit = (n2 / n1).asin();
        assert_eq!(unpolarised(n1, n2, (crit + 1e-6).cos()), 1.0);
        assert!(unpolarised(n1, n2, (crit - 1e-3).cos()) < 1.0);
    }

    #[test]
    fn grazing_incidence_reflects_everything() {
        assert!((unpolarised(1.0, 1.5, 0.0) - 1.0).abs() < 1e-12);
    }
}

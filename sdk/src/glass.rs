//! Glass dispersion: the exact two-term Cauchy fit from (nd, Vd) and the refractiveindex.info
//! formulas used by the bundled catalogue (`sdk/data/glass_catalog.csv`, CC0).

mod catalog;

pub use catalog::{CatalogEntry, GlassCatalog, GlassLookupError};

use crate::spectrum::{LAMBDA_C_NM, LAMBDA_D_NM, LAMBDA_F_NM};

/// A refractive index as a function of wavelength. Wavelengths are given in nanometres;
/// the formulas work in micrometres internally, as the catalogue does.
#[derive(Clone, Debug, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength (air, or a glass given by nd alone).
    Constant(f64),
    /// `n(λ) = a + b/λ²`, λ in µm.
    Cauchy { a: f64, b: f64 },
    /// refractiveindex.info formula 1: `n² − 1 = c0 + Σ Bᵢ λ²/(λ² − Cᵢ²)`.
    Sellmeier { c0: f64, terms: Vec<(f64, f64)> },
    /// refractiveindex.info formula 2: `n² − 1 = c0 + Σ Bᵢ λ²/(λ² − Cᵢ)`.
    Sellmeier2 { c0: f64, terms: Vec<(f64, f64)> },
    /// refractiveindex.info formula 3: `n² = c0 + Σ Cᵢ λ^pᵢ`.
    Polynomial { c0: f64, terms: Vec<(f64, f64)> },
    /// refractiveindex.info formula 5: `n = c0 + Σ Cᵢ λ^pᵢ`.
    CauchyGeneral { c0: f64, terms: Vec<(f64, f64)> },
}

impl Dispersion {
    /// The exact two-term Cauchy fit through the d line (nd) whose F − C dispersion gives Vd:
    /// `B = (nd − 1) / (Vd (1/λF² − 1/λC²))`, `A = nd − B/λd²` (docs/physics.md §1).
    /// A non-finite or non-positive Vd gives a non-dispersive medium.
    pub fn cauchy_from_abbe(nd: f64, vd: f64) -> Self {
        if !(vd.is_finite() && vd > 0.0) {
            return Dispersion::Constant(nd);
        }
        let (ld, lf, lc) = (LAMBDA_D_NM * 1e-3, LAMBDA_F_NM * 1e-3, LAMBDA_C_NM * 1e-3);
        let b = (nd - 1.0) / (vd * (1.0 / (lf * lf) - 1.0 / (lc * lc)));
        let a = nd - b / (ld * ld);
        Dispersion::Cauchy { a, b }
    }

    /// Refractive index at `lambda_nm`.
    pub fn index(&self, lambda_nm: f64) -> f64 {
        let l = lambda_nm * 1e-3;
        let l2 = l * l;
        match self {
            Dispersion::Constant(n) => *n,
            Dispersion::Cauchy { a, b } => a + b / l2,
            Dispersion::Sellmeier { c0, terms } => {
                let s: f64 = terms.iter().map(|(b, c)| b * l2 / (l2 - c * c)).sum();
                (1.0 + c0 + s).sqrt()
            }
            Dispersion::Sellmeier2 { c0, terms } => {
                let s: f64 = terms.iter().map(|(b, c)| b * l2 / (l2 - c)).sum();
                (1.0 + c0 + s).sqrt()
            }
            Dispersion::Polynomial { c0, terms } => {
                let s: f64 = terms.iter().map(|(c, p)| c * l.powf(*p)).sum();
                (c0 + s).sqrt()
            }
            Dispersion::CauchyGeneral { c0, terms } => {
                c0 + terms.iter().map(|(c, p)| c * l.powf(*p)).sum::<f64>()
            }
        }
    }

    /// nd, the index at the helium d line.
    pub fn nd(&self) -> f64 {
        self.index(LAMBDA_D_NM)
    }

    /// The Abbe number `Vd = (nd − 1)/(nF − nC)`; infinite for a non-dispersive medium.
    pub fn vd(&self) -> f64 {
        let d = self.index(LAMBDA_F_NM) - self.index(LAMBDA_C_NM);
        if d == 0.0 {
            f64::INFINITY
        } else {
            (self.nd() - 1.0) / d
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cauchy_fit_reproduces_nd_and_vd_exactly() {
        for &(nd, vd) in &[
            (1.5168, 64.17),
            (1.80518, 25.36),
            (1.652, 58.57),
            (1.0, 89.3),
        ] {
            let d = Dispersion::cauchy_from_abbe(nd, vd);
            assert!((d.nd() - nd).abs() < 1e-12, "nd {nd}");
            if nd > 1.0 {
                assert!((d.vd() - vd).abs() < 1e-9, "vd {vd}: {}", d.vd());
            }
        }
    }

    #[test]
    fn air_model_is_non_dispersive() {
        let d = Dispersion::cauchy_from_abbe(1.0, 89.3);
        assert_eq!(d.index(400.0), 1.0);
        assert_eq!(d.index(700.0), 1.0);
        assert_eq!(
            Dispersion::cauchy_from_abbe(1.6, f64::NAN),
            Dispersion::Constant(1.6)
        );
    }
}

//! The monomial basis: every product `x^a · y^b · t^c · l^d` of the four normalised inputs
//! (entrance position x, y, incidence angle t, wavelength l, each in about −1..=1) of total
//! degree `a + b + c + d ≤ degree`.
//!
//! The light lies in the y–z plane (the meridional frame), so the lens is symmetric under
//! x → −x: sensor x and stop u are odd in x, everything else even. [`Monomial::x_odd`] sorts
//! the basis by that parity, which halves each fit's candidates and makes the symmetry exact.

use serde::{Deserialize, Serialize};

/// Number of inputs: x, y, t, l.
pub const INPUTS: usize = 4;
/// Highest total degree the basis is built for.
pub const MAX_DEGREE: usize = 11;

/// One monomial: the exponent of each input.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Monomial(pub [u8; INPUTS]);

impl Monomial {
    /// Total degree.
    pub fn degree(&self) -> usize {
        self.0.iter().map(|&e| e as usize).sum()
    }

    /// True when odd in x.
    pub fn x_odd(&self) -> bool {
        self.0[0] % 2 == 1
    }

    /// Its value from the inputs' powers ([`Powers`]).
    #[inline]
    pub fn eval(&self, p: &Powers) -> f64 {
        let e = self.0;
        p.0[0][e[0] as usize]
            * p.0[1][e[1] as usize]
            * p.0[2][e[2] as usize]
            * p.0[3][e[3] as usize]
    }
}

/// Every monomial of total degree at most `degree` (≤ [`MAX_DEGREE`]), by increasing degree.
pub fn monomials(degree: usize) -> Vec<Monomial> {
    let d = degree.min(MAX_DEGREE);
    let mut out = Vec::new();
    for total in 0..=d {
        for a in 0..=total {
            for b in 0..=total - a {
                for c in 0..=total - a - b {
                    let e = total - a - b - c;
                    out.push(Monomial([a as u8, b as u8, c as u8, e as u8]));
                }
            }
        }
    }
    out
}

/// The powers `0..=MAX_DEGREE` of each input at one point.
#[derive(Clone, Copy, Debug)]
pub struct Powers(pub [[f64; MAX_DEGREE + 1]; INPUTS]);

impl Powers {
    pub fn of(inputs: [f64; INPUTS]) -> Powers {
        let mut p = [[1.0; MAX_DEGREE + 1]; INPUTS];
        for (row, &v) in p.iter_mut().zip(&inputs) {
            for k in 1..=MAX_DEGREE {
                row[k] = row[k - 1] * v;
            }
        }
        Powers(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_basis_of_degree_d_in_four_inputs_has_d_plus_4_choose_4_monomials() {
        for d in 0..=MAX_DEGREE {
            let n = (d + 1) * (d + 2) * (d + 3) * (d + 4) / 24;
            let m = monomials(d);
            assert_eq!(m.len(), n, "degree {d}");
            assert!(m.iter().all(|t| t.degree() <= d));
            let mut unique = m.clone();
            unique.sort_by_key(|t| t.0);
            unique.dedup();
            assert_eq!(unique.len(), n);
        }
    }

    #[test]
    fn a_monomial_evaluates_to_the_product_of_its_powers() {
        let p = Powers::of([0.5, -2.0, 3.0, 0.1]);
        let v = Monomial([2, 1, 0, 3]).eval(&p);
        assert!((v - 0.25 * -2.0 * 0.001).abs() < 1e-15);
    }
}

//! The CIE 1931 2° standard observer: colour-matching functions x̄(λ), ȳ(λ), z̄(λ) from the
//! CIE's 1 nm table (360–830 nm), linearly interpolated, and spectrum → XYZ integration.

use super::tables::{CIE1931_2DEG, CIE1931_2DEG_START_NM, CIE1931_2DEG_STEP_NM};

/// Shortest wavelength of the CIE 1931 table (nm).
pub const CMF_MIN_NM: f64 = 360.0;
/// Longest wavelength of the CIE 1931 table (nm).
pub const CMF_MAX_NM: f64 = 830.0;

/// `[x̄, ȳ, z̄]` of the CIE 1931 2° observer at `lambda_nm`, linearly interpolated in the 1 nm
/// table; zero outside 360–830 nm and for a non-finite wavelength.
pub fn cie1931_xyz_bar(lambda_nm: f64) -> [f64; 3] {
    lerp_rows(
        &CIE1931_2DEG,
        CIE1931_2DEG_START_NM,
        CIE1931_2DEG_STEP_NM,
        lambda_nm,
    )
    .unwrap_or([0.0; 3])
}

/// Tristimulus values `[X, Y, Z]` of the spectrum `s(λ)` (λ in nm):
/// `X = ∫ s(λ) x̄(λ) dλ` (likewise Y, Z), summed over the 1 nm nodes of the CIE table from 360
/// to 830 nm (the trapezoid rule; the end values are negligible). Units: those of `s` × nm.
pub fn spectrum_to_xyz(s: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for (i, row) in CIE1931_2DEG.iter().enumerate() {
        let lambda = CIE1931_2DEG_START_NM + i as f64 * CIE1931_2DEG_STEP_NM;
        let w = if i == 0 || i == CIE1931_2DEG.len() - 1 {
            0.5
        } else {
            1.0
        } * CIE1931_2DEG_STEP_NM;
        let v = s(lambda) * w;
        for c in 0..3 {
            xyz[c] += row[c] * v;
        }
    }
    xyz
}

/// Chromaticity `(x, y) = (X, Y) / (X + Y + Z)`.
pub fn chromaticity(xyz: [f64; 3]) -> [f64; 2] {
    let sum = xyz[0] + xyz[1] + xyz[2];
    [xyz[0] / sum, xyz[1] / sum]
}

/// Linear interpolation in a table of rows sampled every `step` nm from `start`; `None`
/// outside the table (or for NaN).
pub(super) fn lerp_rows<const C: usize>(
    table: &[[f64; C]],
    start: f64,
    step: f64,
    lambda_nm: f64,
) -> Option<[f64; C]> {
    let u = (lambda_nm - start) / step;
    let last = (table.len() - 1) as f64;
    if !(u >= 0.0 && u <= last) {
        return None;
    }
    // u in [0, last]: the cell index is at most len - 2, so i + 1 stays in the table.
    let i = (u.floor() as usize).min(table.len() - 2);
    let t = u - i as f64;
    let (a, b) = (table[i], table[i + 1]);
    Some(std::array::from_fn(|c| a[c] + t * (b[c] - a[c])))
}

/// [`lerp_rows`] for a one-column table.
pub(super) fn lerp(table: &[f64], start: f64, step: f64, lambda_nm: f64) -> Option<f64> {
    let u = (lambda_nm - start) / step;
    let last = (table.len() - 1) as f64;
    if !(u >= 0.0 && u <= last) {
        return None;
    }
    let i = (u.floor() as usize).min(table.len() - 2);
    let t = u - i as f64;
    Some(table[i] + t * (table[i + 1] - table[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CIE table's own values are returned exactly at its nodes.
    #[test]
    fn table_nodes_are_returned_exactly() {
        // CIE 015 tables: x̄ ȳ z̄ at 555 nm and 600 nm.
        assert_eq!(cie1931_xyz_bar(555.0), [0.5120501, 1.0, 0.005749999]);
        assert_eq!(cie1931_xyz_bar(600.0), [1.0622, 0.631, 0.0008]);
        assert_eq!(cie1931_xyz_bar(360.0), [0.0001299, 3.917e-6, 0.0006061]);
        assert_eq!(cie1931_xyz_bar(830.0), [1.251141e-6, 4.5181e-7, 0.0]);
    }

    #[test]
    fn values_between_nodes_are_interpolated_linearly() {
        let (a, b) = (cie1931_xyz_bar(600.0), cie1931_xyz_bar(601.0));
        let m = cie1931_xyz_bar(600.25);
        for c in 0..3 {
            assert!((m[c] - (0.75 * a[c] + 0.25 * b[c])).abs() < 1e-15);
        }
    }

    #[test]
    fn outside_the_table_the_functions_are_zero() {
        assert_eq!(cie1931_xyz_bar(359.999), [0.0; 3]);
        assert_eq!(cie1931_xyz_bar(830.001), [0.0; 3]);
        assert_eq!(cie1931_xyz_bar(f64::NAN), [0.0; 3]);
        assert_eq!(cie1931_xyz_bar(f64::INFINITY), [0.0; 3]);
    }

    /// The three functions have (nearly) equal areas by construction, so illuminant E sits at
    /// x = y = 1/3; ∫ȳ dλ over the 1 nm table is 106.857 (sum of the CIE table).
    #[test]
    fn the_functions_have_the_published_areas() {
        let xyz = spectrum_to_xyz(|_| 1.0);
        // Sums of the 1 nm CIE table minus half of each end value (trapezoid).
        assert!((xyz[0] - 106.865_469).abs() < 1e-3, "{xyz:?}");
        assert!((xyz[1] - 106.856_917).abs() < 1e-3, "{xyz:?}");
        assert!((xyz[2] - 106.892_251).abs() < 1e-3, "{xyz:?}");
        let [x, y] = chromaticity(xyz);
        assert!((x - 1.0 / 3.0).abs() < 1e-4 && (y - 1.0 / 3.0).abs() < 1e-4);
    }
}

//! Orthogonal matching pursuit: a sparse least-squares fit `y ≈ Σ c_j a_j` over a few of many
//! candidate columns `a_j`. Each step adds the column most correlated with the residual
//! (`|a_j · r| / ‖a_j‖`), orthogonalises it against those chosen (modified Gram–Schmidt, twice,
//! in f64), and projects it out of the residual; the coefficients solve `R c = Qᵀ y` at the end.
//! The QR form keeps the conditioning of the chosen columns, not its square (as normal
//! equations would).

/// A fitted sparse combination: the chosen columns (indices into the candidates, in the order
/// chosen) and their coefficients, with the residual's root mean square.
#[derive(Clone, Debug, PartialEq)]
pub struct Pursuit {
    pub chosen: Vec<usize>,
    pub coefficients: Vec<f64>,
    pub rms: f64,
}

/// A column whose part orthogonal to those chosen is below this share of its norm adds
/// nothing but rounding: it is skipped.
const DEPENDENT: f64 = 1e-9;

/// Fits `y` (length N) with at most `budget` of `columns` (each of length N); stops early when
/// the residual's RMS is at most `tolerance` or a step would reduce its square by less than
/// 1e-13 of `‖y‖²` (the fit has stopped improving).
pub fn pursue(columns: &[Vec<f64>], y: &[f64], budget: usize, tolerance: f64) -> Pursuit {
    let n = y.len();
    let norms: Vec<f64> = columns
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let y2: f64 = y.iter().map(|v| v * v).sum();
    let mut r = y.to_vec();
    let mut q: Vec<Vec<f64>> = Vec::new();
    // R, column by column: rcols[k][i] for i ≤ k.
    let mut rcols: Vec<Vec<f64>> = Vec::new();
    let mut z: Vec<f64> = Vec::new();
    let mut chosen = Vec::new();
    let mut skip = vec![false; columns.len()];
    let rms = |r: &[f64]| (r.iter().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt();
    while chosen.len() < budget && rms(&r) > tolerance {
        let mut best: Option<(usize, f64)> = None;
        for (j, col) in columns.iter().enumerate() {
            if skip[j] || norms[j] <= 0.0 {
                continue;
            }
            let c = dot(col, &r).abs() / norms[j];
            if best.is_none_or(|(_, b)| c > b) {
                best = Some((j, c));
            }
        }
        let Some((j, _)) = best else { break };
        skip[j] = true;
        let mut v = columns[j].clone();
        let mut rk = vec![0.0; q.len() + 1];
        for _ in 0..2 {
            for (i, qi) in q.iter().enumerate() {
                let h = dot(qi, &v);
                rk[i] += h;
                axpy(-h, qi, &mut v);
            }
        }
        let nv = dot(&v, &v).sqrt();
        #[allow(
            clippy::neg_cmp_op_on_partial_ord,
            reason = "a NaN norm is dependent too"
        )]
        if !(nv > DEPENDENT * norms[j]) {
            continue;
        }
        for x in &mut v {
            *x /= nv;
        }
        let g = dot(&v, &r);
        if g * g < 1e-13 * y2 {
            break;
        }
        axpy(-g, &v, &mut r);
        rk[q.len()] = nv;
        q.push(v);
        rcols.push(rk);
        z.push(g);
        chosen.push(j);
    }
    // Back substitution: R c = z.
    let k = chosen.len();
    let mut c = vec![0.0; k];
    for i in (0..k).rev() {
        let mut s = z[i];
        for (jj, cj) in c.iter().enumerate().skip(i + 1) {
            s -= rcols[jj][i] * cj;
        }
        c[i] = s / rcols[i][i];
    }
    Pursuit {
        chosen,
        coefficients: c,
        rms: rms(&r),
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn columns(xs: &[f64], degree: usize) -> Vec<Vec<f64>> {
        (0..=degree)
            .map(|k| xs.iter().map(|x| x.powi(k as i32)).collect())
            .collect()
    }

    #[test]
    fn a_sparse_polynomial_is_recovered_with_its_coefficients() {
        let xs: Vec<f64> = (0..200).map(|i| -1.0 + 2.0 * i as f64 / 199.0).collect();
        let y: Vec<f64> = xs.iter().map(|x| 3.0 * x - 0.5 * x.powi(5) + 2.0).collect();
        let p = pursue(&columns(&xs, 9), &y, 10, 1e-12);
        // Greedy selection may pass through a correlated column (x³ before x⁵) on the way:
        // it ends with a coefficient at rounding level.
        assert!(p.chosen.len() <= 6, "{:?}", p.chosen);
        let coef = |k: usize| {
            p.chosen
                .iter()
                .position(|&j| j == k)
                .map_or(0.0, |i| p.coefficients[i])
        };
        for k in 0..=9 {
            let want = match k {
                0 => 2.0,
                1 => 3.0,
                5 => -0.5,
                _ => 0.0,
            };
            assert!(
                (coef(k) - want).abs() < 1e-10,
                "x^{k}: {} vs {want}",
                coef(k)
            );
        }
        assert!(p.rms < 1e-12);
    }

    #[test]
    fn the_budget_bounds_the_terms_and_the_fit_is_least_squares_on_them() {
        let xs: Vec<f64> = (0..100).map(|i| -1.0 + 2.0 * i as f64 / 99.0).collect();
        let y: Vec<f64> = xs.iter().map(|x| x.exp()).collect();
        let p = pursue(&columns(&xs, 8), &y, 2, 0.0);
        assert_eq!(p.chosen.len(), 2);
        // Least squares: the residual is orthogonal to every chosen column.
        let cols = columns(&xs, 8);
        let fit: Vec<f64> = (0..xs.len())
            .map(|i| {
                p.chosen
                    .iter()
                    .zip(&p.coefficients)
                    .map(|(&j, c)| c * cols[j][i])
                    .sum()
            })
            .collect();
        for &j in &p.chosen {
            let g: f64 = (0..xs.len()).map(|i| cols[j][i] * (y[i] - fit[i])).sum();
            assert!(g.abs() < 1e-10, "column {j}: {g}");
        }
    }
}

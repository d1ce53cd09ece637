//! Bounded nonlinear least squares: MINPACK's Levenberg–Marquardt (the `levenberg-marquardt`
//! crate) on parameters mapped into their bounds, with the Jacobian by finite differences
//! (central differences, its columns computed in parallel).
//!
//! A parameter bounded to `[lo, hi]` is `lo + (hi − lo)(1 + sin u)/2` of a free `u` (the
//! mapping MINUIT uses); a positive one is `e^u`. The solver sees only `u`. A problem that
//! knows a cheaper way to its Jacobian than re-evaluating every residual per parameter gives
//! it in the parameters themselves ([`Residuals::jacobian`]); the chain rule takes it to `u`.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;

/// Where a parameter may go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// Between the two (inclusive).
    Range(f64, f64),
    /// Above zero.
    Positive,
}

impl Bound {
    fn to_param(self, u: f64) -> f64 {
        match self {
            Bound::Range(lo, hi) => lo + (hi - lo) * 0.5 * (1.0 + u.sin()),
            Bound::Positive => u.exp(),
        }
    }

    fn to_free(self, p: f64) -> f64 {
        match self {
            Bound::Range(lo, hi) => (2.0 * (p - lo) / (hi - lo) - 1.0).clamp(-1.0, 1.0).asin(),
            Bound::Positive => p.max(f64::MIN_POSITIVE).ln(),
        }
    }

    /// A difference step for `p`: small against its range (or itself).
    pub fn step(self, p: f64) -> f64 {
        match self {
            Bound::Range(lo, hi) => 1e-6 * (hi - lo),
            Bound::Positive => 1e-6 * p.abs().max(1e-12),
        }
    }
}

/// What a minimisation found.
#[derive(Clone, Debug)]
pub struct Minimum {
    pub params: Vec<f64>,
    /// Half the sum of squared residuals there.
    pub cost: f64,
    /// Residual evaluations made (the Jacobian's included).
    pub evaluations: usize,
    /// Why the solver stopped.
    pub termination: String,
    pub converged: bool,
}

/// A least-squares problem: residuals of parameters, and optionally their Jacobian.
pub trait Residuals: Sync {
    fn residuals(&self, p: &[f64]) -> Vec<f64>;

    /// `∂r/∂p` at `p` (rows of residuals × columns of parameters), counted as this many
    /// residual evaluations; `None` (the default) has the solver difference the residuals.
    fn jacobian(&self, _p: &[f64], _bounds: &[Bound]) -> Option<(DMatrix<f64>, usize)> {
        None
    }
}

impl<F: Fn(&[f64]) -> Vec<f64> + Sync> Residuals for F {
    fn residuals(&self, p: &[f64]) -> Vec<f64> {
        self(p)
    }
}

struct Problem<'a> {
    f: &'a dyn Residuals,
    bounds: &'a [Bound],
    u: DVector<f64>,
    evaluations: std::sync::atomic::AtomicUsize,
}

impl Problem<'_> {
    fn params_of(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(self.bounds)
            .map(|(&u, b)| b.to_param(u))
            .collect()
    }

    fn eval(&self, u: &[f64]) -> Vec<f64> {
        self.evaluations
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.f.residuals(&self.params_of(u))
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.u.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.u.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let r = self.eval(self.u.as_slice());
        r.iter()
            .all(|v| v.is_finite())
            .then(|| DVector::from_vec(r))
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        const H: f64 = 1e-6;
        let u = self.u.as_slice();
        if let Some((mut jac, cost)) = self.f.jacobian(&self.params_of(u), self.bounds) {
            self.evaluations
                .fetch_add(cost, std::sync::atomic::Ordering::Relaxed);
            for (j, (&u, b)) in u.iter().zip(self.bounds).enumerate() {
                let dp_du = match *b {
                    Bound::Range(lo, hi) => (hi - lo) * 0.5 * u.cos(),
                    Bound::Positive => u.exp(),
                };
                jac.column_mut(j).scale_mut(dp_du);
            }
            return jac.iter().all(|v| v.is_finite()).then_some(jac);
        }
        let columns: Vec<Vec<f64>> = (0..u.len())
            .into_par_iter()
            .map(|j| {
                let mut up = u.to_vec();
                let mut down = u.to_vec();
                up[j] += H;
                down[j] -= H;
                let (a, b) = (self.eval(&up), self.eval(&down));
                a.iter().zip(&b).map(|(a, b)| (a - b) / (2.0 * H)).collect()
            })
            .collect();
        let m = columns.first().map_or(0, Vec::len);
        let jac = DMatrix::from_fn(m, u.len(), |i, j| columns[j][i]);
        jac.iter().all(|v| v.is_finite()).then_some(jac)
    }
}

/// Minimises `½ Σ f(p)ᵢ²` over `p` within `bounds`, from `start` (clamped into the bounds),
/// with at most 30 × (parameters + 1) evaluations of `f` besides the Jacobian's: a start still
/// crawling along a valley by then is in one that loses to the fit's other starts.
pub fn minimise(f: &dyn Residuals, start: &[f64], bounds: &[Bound]) -> Minimum {
    let problem = Problem {
        f,
        bounds,
        u: DVector::from_iterator(
            start.len(),
            start.iter().zip(bounds).map(|(&p, b)| b.to_free(p)),
        ),
        evaluations: 0.into(),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(30)
        .with_ftol(1e-10)
        .with_xtol(1e-9)
        .minimize(problem);
    let params = problem.params_of(problem.u.as_slice());
    let r = f.residuals(&params);
    Minimum {
        cost: 0.5 * r.iter().map(|v| v * v).sum::<f64>(),
        params,
        evaluations: problem.evaluations.into_inner() + 1,
        converged: report.termination.was_successful(),
        termination: format!("{:?}", report.termination),
    }
}

/// The Jacobian of `f` at `p` in the parameters themselves (central differences, each step
/// [`Bound::step`]), as rows of residuals × columns of parameters.
pub fn jacobian_at(
    f: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    p: &[f64],
    bounds: &[Bound],
) -> DMatrix<f64> {
    let columns: Vec<Vec<f64>> = (0..p.len())
        .into_par_iter()
        .map(|j| {
            let h = bounds[j].step(p[j]);
            let mut up = p.to_vec();
            let mut down = p.to_vec();
            up[j] += h;
            down[j] -= h;
            let (a, b) = (f(&up), f(&down));
            a.iter().zip(&b).map(|(a, b)| (a - b) / (2.0 * h)).collect()
        })
        .collect();
    let m = columns.first().map_or(0, Vec::len);
    DMatrix::from_fn(m, p.len(), |i, j| columns[j][i])
}

//! The floating-point types the tracer runs in: `f32` and `f64`.

use num_traits::Float;

/// A float the tracer can run in. Implemented for `f32` and `f64` only.
pub trait Real: Float + Send + Sync + std::fmt::Debug + Default + 'static {
    /// Converts from `f64` (rounding for `f32`).
    fn of(v: f64) -> Self;
    /// Converts to `f64`.
    fn to_f64(self) -> f64;
    /// Tolerance (mm) for the asphere Newton iteration.
    const NEWTON_TOL: Self;
    /// Truncates a non-negative value to an index (saturating; NaN gives 0).
    fn to_index(self) -> usize;
}

impl Real for f32 {
    fn of(v: f64) -> Self {
        v as f32
    }
    fn to_f64(self) -> f64 {
        self as f64
    }
    const NEWTON_TOL: Self = 1e-5;
    fn to_index(self) -> usize {
        self as u32 as usize
    }
}

impl Real for f64 {
    fn of(v: f64) -> Self {
        v
    }
    fn to_f64(self) -> f64 {
        self
    }
    const NEWTON_TOL: Self = 1e-12;
    fn to_index(self) -> usize {
        self as u32 as usize
    }
}

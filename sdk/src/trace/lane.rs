//! The per-ray physics of one step, shared by the scalar and the batched tracers.
//!
//! Written without early returns so that, inlined into a loop over a packet of rays, it
//! compiles to straight-line SIMD code for spherical and conic surfaces.

#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "`!(a >= b)` is deliberate: it is true for NaN, which must count as a failure"
)]

use super::real::Real;
use super::sequence::Step;

/// Maximum Newton iterations for an even asphere.
const NEWTON_MAX_ITER: usize = 32;

/// What one step did to one ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StepOut<T> {
    /// The ray's line does not meet the surface.
    pub missed: bool,
    /// Total internal reflection.
    pub tir: bool,
    /// The asphere iteration failed.
    pub no_convergence: bool,
    /// Squared radial distance of the hit from the axis.
    pub r2: T,
    /// |cos| of the angle of incidence (for Fresnel).
    pub cos_i: T,
}

/// Interaction codes for the const-generic kernel.
pub(crate) const REFRACT: u8 = 0;
pub(crate) const REFLECT: u8 = 1;
pub(crate) const SENSOR: u8 = 2;

/// Surface shape codes for the const-generic kernel.
pub(crate) const SPHERE: u8 = 0;
pub(crate) const CONIC: u8 = 1;
pub(crate) const ASPHERE: u8 = 2;

/// The shape code of a step.
#[inline]
pub(crate) fn shape<T: Real>(s: &Step<T>) -> u8 {
    if s.aspheric {
        ASPHERE
    } else if s.k != T::zero() {
        CONIC
    } else {
        SPHERE
    }
}

/// Calls `$f::<T, MODE, SHAPE>($args)` with the step's interaction and shape as constants.
macro_rules! dispatch_step {
    ($s:expr, $f:ident, $($arg:expr),*) => {{
        use $crate::trace::lane::{ASPHERE, CONIC, REFLECT, REFRACT, SENSOR, SPHERE};
        use $crate::trace::sequence::Interaction;
        match ($s.interaction, $crate::trace::lane::shape($s)) {
            (Interaction::Refract, SPHERE) => $f::<T, REFRACT, SPHERE>($($arg),*),
            (Interaction::Refract, CONIC) => $f::<T, REFRACT, CONIC>($($arg),*),
            (Interaction::Refract, _) => $f::<T, REFRACT, ASPHERE>($($arg),*),
            (Interaction::Reflect, SPHERE) => $f::<T, REFLECT, SPHERE>($($arg),*),
            (Interaction::Reflect, CONIC) => $f::<T, REFLECT, CONIC>($($arg),*),
            (Interaction::Reflect, _) => $f::<T, REFLECT, ASPHERE>($($arg),*),
            (Interaction::Sensor, _) => $f::<T, SENSOR, SPHERE>($($arg),*),
        }
    }};
}
pub(crate) use dispatch_step;

/// [`advance`] with the interaction and the shape chosen at run time (scalar use).
#[inline]
pub(crate) fn advance_dyn<T: Real>(s: &Step<T>, p: &mut [T; 3], d: &mut [T; 3]) -> StepOut<T> {
    dispatch_step!(s, advance, s, p, d)
}

/// Intersects the ray `(p, d)` (`d` a unit vector) with the surface of `s` and applies the
/// interaction `MODE` (`REFRACT`, `REFLECT`, `SENSOR`) for a surface of shape `SHAPE`
/// (`SPHERE`, `CONIC`, `ASPHERE`; the sensor plane is a sphere of curvature 0). `p` and `d`
/// are updated in place; on failure they hold unspecified values and the flags say why.
#[inline(always)]
pub(crate) fn advance<T: Real, const MODE: u8, const SHAPE: u8>(
    s: &Step<T>,
    p: &mut [T; 3],
    d: &mut [T; 3],
) -> StepOut<T> {
    let one = T::one();
    let zero = T::zero();
    let two = one + one;
    let [dx, dy, dz] = *d;
    let (c, k) = (s.c, s.k);
    let ck = c * (one + k);
    // 1. The ray's point in vertex-local coordinates, and where the ray crosses the vertex
    //    tangent plane (`t0` along it; `x`, `y` there).
    let (px, py, pz) = (p[0], p[1], p[2] - s.z);
    let t0 = -pz / dz;
    let x = px + t0 * dx;
    let y = py + t0 * dy;
    // 2. The conic F(h) = c(x² + y²) + c(1+k)z² − 2z = 0 along the ray h = P + t·d, from the
    //    ray's own point: A t² − 2B t + C = 0 with
    //    A = c(dx² + dy² + (1+k)dz²), B = N(P)·d, C = F(P),
    //    N(h) = (−c·x, −c·y, 1 − c(1+k)z) the unnormalised normal. (A takes |d| as it is, so a
    //    direction a few ulps from unit length moves nothing.)
    let a = c * (dx * dx + dy * dy) + ck * dz * dz;
    let b = dz - c * (px * dx + py * dy) - ck * pz * dz;
    let cc = c * (px * px + py * py) + (ck * pz - two) * pz;
    let disc = b * b - a * cc;
    let sq = disc.max(zero).sqrt();
    // 3. Which root. B is linear along the ray (B(t) = B − A t) and at a root equals ∓√disc:
    //    the two roots lie on either side of the point where it changes sign (a sphere's chord's
    //    midpoint). The sheet through the vertex is the root on the side of the ray's crossing
    //    of the tangent plane, where B is `b_vertex` (Spencer & Murty start there and take the
    //    root with B(t) of its sign): the root near P, `C / (B ± √disc)`, when `b_vertex` has
    //    B's sign, else the far one, `(B ± √disc) / A`. Both forms add quantities of one sign.
    //    Starting from the tangent plane itself would be the same root but not the same
    //    numbers: a ray running nearly parallel to it (`dz` small: between the steep faces of
    //    a meniscus, a ghost's rays travel almost across the axis) crosses it hundreds of mm
    //    away, and the hit, found back from there, loses its digits in the cancellation of two
    //    long, nearly opposite distances (f32 rays landing up to 0.6 mm from f64's, or missing
    //    a surface f64 meets).
    let b_vertex = b - a * t0;
    let den = b + sq.copysign(b);
    let near = one.copysign(b_vertex) == one.copysign(b);
    let t = if near { cc / den } else { den / a };
    let mut hx = px + t * dx;
    let mut hy = py + t * dy;
    // On a plane (c = 0) the hit is on it by definition.
    let mut hz = if c == zero { zero } else { pz + t * dz };
    // Non-short-circuit `|` keeps the lane code branch-free.
    let mut missed = !(disc >= zero) | !t.is_finite() | !t0.is_finite();
    let mut no_convergence = false;
    // 4. Surface normal (unnormalised), pointing to +z at the vertex.
    let (mut nx, mut ny, mut nz) = (-c * hx, -c * hy, one - ck * hz);
    if SHAPE == ASPHERE {
        // Start from the conic hit, or from the tangent plane when the conic was missed.
        let start = if missed { [x, y, zero] } else { [hx, hy, hz] };
        match refine_asphere(s, start, [dx, dy, dz]) {
            Some((h, n)) => {
                [hx, hy, hz] = h;
                [nx, ny, nz] = n;
                missed = !t0.is_finite();
            }
            None => no_convergence = true,
        }
    }
    // On a sphere (−cx, −cy, 1 − cz) is already a unit vector: |N|² − 1 = c·F(x, y, z) = 0.
    let (nx, ny, nz) = if SHAPE == SPHERE {
        (nx, ny, nz)
    } else {
        let inv = one / (nx * nx + ny * ny + nz * nz).sqrt();
        (nx * inv, ny * inv, nz * inv)
    };
    let dn = dx * nx + dy * ny + dz * nz;
    let cos_i = dn.abs();
    // 5. Interaction.
    let mut tir = false;
    match MODE {
        REFRACT => {
            let eta = s.eta;
            let kk = one - eta * eta * (one - cos_i * cos_i);
            tir = !(kk >= zero);
            let cos_t = kk.max(zero).sqrt();
            // Normal oriented along the travel direction.
            let g = (cos_t - eta * cos_i) * one.copysign(dn);
            *d = [eta * dx + g * nx, eta * dy + g * ny, eta * dz + g * nz];
        }
        REFLECT => {
            let g = two * dn;
            *d = [dx - g * nx, dy - g * ny, dz - g * nz];
        }
        _ => {}
    }
    *p = [hx, hy, hz + s.z];
    StepOut {
        missed,
        tir,
        no_convergence,
        r2: hx * hx + hy * hy,
        cos_i,
    }
}

/// Newton's method on `F(t) = z(t) − sag(r(t)²)` from the conic hit `h` (vertex-local).
/// Returns the hit and the unnormalised normal, or `None` when it does not converge.
#[inline(never)]
fn refine_asphere<T: Real>(s: &Step<T>, h: [T; 3], d: [T; 3]) -> Option<([T; 3], [T; 3])> {
    let one = T::one();
    let two = one + one;
    let (c, k) = (s.c, s.k);
    let sag_and_slope = |r2: T| -> Option<(T, T)> {
        // Conic part and d(sag)/d(r²).
        let arg = one - (one + k) * c * c * r2;
        if !(arg >= T::zero()) {
            return None;
        }
        let root = arg.sqrt();
        let mut sag = c * r2 / (one + root);
        let mut slope = if root > T::zero() {
            c / (two * root)
        } else {
            T::infinity()
        };
        let mut pw = one; // (r²)^(i−1)
        for (i, &a) in s.asph.iter().enumerate() {
            let ii = T::of((i + 1) as f64);
            slope = slope + ii * a * pw;
            pw = pw * r2;
            sag = sag + a * pw;
        }
        Some((sag, slope))
    };
    let [mut x, mut y, mut z] = h;
    // If the conic itself was missed, start from the tangent-plane point instead.
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return None;
    }
    for _ in 0..NEWTON_MAX_ITER {
        let r2 = x * x + y * y;
        let (sag, slope) = sag_and_slope(r2)?;
        let f = z - sag;
        let fp = d[2] - slope * two * (x * d[0] + y * d[1]);
        if !(fp.abs() > T::zero()) {
            return None;
        }
        let dt = f / fp;
        x = x - dt * d[0];
        y = y - dt * d[1];
        z = z - dt * d[2];
        if dt.abs() <= T::NEWTON_TOL {
            let r2 = x * x + y * y;
            let (_, slope) = sag_and_slope(r2)?;
            let g = two * slope;
            return Some(([x, y, z], [-g * x, -g * y, one]));
        }
    }
    None
}

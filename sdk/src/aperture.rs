//! The aperture stop's opening — one model shared by the ghost renderer and the starburst: a
//! circle, an iris of straight or rounded blades, or a transmission mask image.
//!
//! **Coordinates.** `(u, v)` are positions on the stop divided by the stop's working radius
//! (`paraxial::stop_opening`), `u` along x and `v` along y of the lens frame. The opening is
//! inscribed in the unit circle: the circle *is* the unit circle, an iris's blade tips (the
//! polygon's vertices) lie on it, and a mask covers the square [-1, 1]².
//!
//! **Signed distance** (negative inside, in the same normalised units) is exact for the circle
//! and the iris; for a mask it comes from a distance transform computed when the mask is built
//! ([`ApertureMask`]), good to about a texel.
//!
//! **Soft edges.** [`Aperture::transmission_soft`] replaces the step at the edge by a smooth
//! ramp of width `feather` centred on the edge: `t = clamp(1/2 − d/feather, 0, 1)`,
//! `T = t²(3 − 2t)`. The ramp is odd about the edge (`T(−d) = 1 − T(d)`), so a straight edge
//! gains outside exactly what it loses inside. Corners and curvature do not cancel: for a
//! convex opening the integral of `T` is the open area plus `(2π + 2Σ tan(θᵢ/2))·feather²/80`
//! (θᵢ the exterior angles of its corners; `π·feather²/20` for the circle) — relative 1e-5 at
//! a feather of 1/64. The ghost renderer feathers over about one output pixel
//! (`ghost::triangles::edge_feathers`).
//!
//! **Dust and scratches** are not part of the opening: they are an optional overlay, an
//! [`ApertureMask`] over the same square whose transmission multiplies the opening's at the
//! same `(u, v)` ([`Aperture::rasterize_with_overlay`]; the starburst takes it, so dust shows
//! as the fine streaks and speckle it adds to a starburst).

pub mod iris;
use iris::IrisGeometry;
mod mask;
#[cfg(test)]
pub(crate) mod tests;

pub use mask::{ApertureMask, MAX_MASK_TEXELS, OLF_DISTANCE_CLIP, check_mask_size};

/// Area of a simple polygon (shoelace formula), in the square of its coordinates' unit;
/// either winding.
pub fn polygon_area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        .abs()
}

/// The shape of the aperture stop's opening, in normalised stop coordinates (module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Aperture {
    /// The unit circle.
    #[default]
    Circular,
    /// An iris diaphragm of `blades` blades. The blade tips lie on the unit circle at angles
    /// `rotation_rad + 2πk/blades` from the +u axis (counter-clockwise toward +v).
    /// `roundness` is the curvature of each blade's edge relative to the unit circle: the edge
    /// between two tips is a circular arc of radius `1/roundness` bulging outward, so 0 gives
    /// straight blades (a regular polygon) and 1 the unit circle. For a real iris it is the
    /// opening radius over the blades' radius of curvature, so it grows as the iris closes.
    Iris {
        blades: u32,
        rotation_rad: f64,
        roundness: f64,
    },
    /// A transmission image covering [-1, 1]².
    Mask(ApertureMask),
}

/// An aperture or mask description that cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ApertureError {
    #[error("an iris needs at least 3 blades, got {0}")]
    TooFewBlades(u32),
    #[error("iris roundness must lie in 0..=1 (0 straight blades, 1 a circle), got {0}")]
    Roundness(f64),
    #[error("iris rotation must be finite, got {0}")]
    Rotation(f64),
    #[error("a mask needs a positive width and height, got {width} x {height}")]
    EmptyMask { width: usize, height: usize },
    #[error("a mask of {width} x {height} texels is too large (at most {max} texels)")]
    MaskTooLarge {
        width: usize,
        height: usize,
        max: usize,
    },
    #[error("a {width} x {height} mask needs {expected} values, got {got}")]
    MaskLength {
        width: usize,
        height: usize,
        expected: usize,
        got: usize,
    },
    #[error("mask texel at row {row}, column {column} is {value}; transmissions lie in 0..=1")]
    MaskValue {
        row: usize,
        column: usize,
        value: f32,
    },
    #[error("the distance-map threshold must lie in 0..=1, got {0}")]
    DistanceClip(f32),
}

impl Aperture {
    /// Checks the iris parameters (a mask was checked when it was built). Sampling never
    /// panics on unchecked values: blades below 3 count as 3, roundness is clamped to 0..=1
    /// and a non-finite rotation counts as 0.
    pub fn validate(&self) -> Result<(), ApertureError> {
        if let Aperture::Iris {
            blades,
            rotation_rad,
            roundness,
        } = *self
        {
            if blades < 3 {
                return Err(ApertureError::TooFewBlades(blades));
            }
            if !(0.0..=1.0).contains(&roundness) {
                return Err(ApertureError::Roundness(roundness));
            }
            if !rotation_rad.is_finite() {
                return Err(ApertureError::Rotation(rotation_rad));
            }
        }
        Ok(())
    }

    /// A sampler with the shape's constants worked out once; use it in loops.
    pub fn sampler(&self) -> ApertureSampler<'_> {
        let shape = match self {
            Aperture::Circular => Shape::Circle,
            Aperture::Iris {
                blades,
                rotation_rad,
                roundness,
            } => Shape::Iris(IrisGeometry::new(*blades, *rotation_rad, *roundness)),
            Aperture::Mask(mask) => Shape::Mask(mask),
        };
        ApertureSampler { shape }
    }

    /// Transmission (0..=1) at `(u, v)`: 1 inside the circle or iris (edge included), 0
    /// outside; a mask is sampled bilinearly.
    pub fn transmission(&self, u: f32, v: f32) -> f32 {
        self.sampler().transmission(u, v)
    }

    /// Transmission with the edge smoothed over a band of width `feather` (normalised units)
    /// centred on the edge (module docs). `feather <= 0` (or NaN) gives [`Self::transmission`].
    pub fn transmission_soft(&self, u: f32, v: f32, feather: f32) -> f32 {
        self.sampler().transmission_soft(u, v, feather)
    }

    /// Signed distance from `(u, v)` to the edge of the opening (normalised units, negative
    /// inside): exact for the circle and the iris, to about a texel for a mask.
    pub fn signed_distance(&self, u: f32, v: f32) -> f32 {
        self.sampler().signed_distance(u, v)
    }

    /// The open area in normalised units (the physical area is this times the working radius
    /// squared): π for the circle; for an iris of n blades with tips on the unit circle,
    /// `(n/2) sin(2π/n)` for straight blades plus n circular segments for rounded ones; for a
    /// mask the integral of its bilinear transmission, `Σ T × texel area`.
    pub fn open_area(&self) -> f64 {
        match self.sampler().shape {
            Shape::Circle => std::f64::consts::PI,
            Shape::Iris(g) => g.area(),
            Shape::Mask(m) => m.open_area(),
        }
    }

    /// Renders the opening into a `width` × `height` mask over [-1, 1]² (row 0 at v = +1),
    /// each texel the soft transmission at its centre feathered over one texel — an
    /// antialiased image whose area matches [`Self::open_area`] to first order. The starburst
    /// takes its Fourier transform.
    pub fn rasterize(&self, width: usize, height: usize) -> Result<ApertureMask, ApertureError> {
        self.rasterize_with_overlay(width, height, None)
    }

    /// [`Self::rasterize`], each texel multiplied by an optional dust/scratch overlay's
    /// bilinear transmission at the texel centre (module docs).
    pub fn rasterize_with_overlay(
        &self,
        width: usize,
        height: usize,
        overlay: Option<&ApertureMask>,
    ) -> Result<ApertureMask, ApertureError> {
        check_mask_size(width, height)?;
        let sampler = self.sampler();
        let (du, dv) = (2.0 / width as f64, 2.0 / height as f64);
        let feather = du.max(dv) as f32;
        let mut data = Vec::with_capacity(width * height);
        for row in 0..height {
            let v = 1.0 - (row as f64 + 0.5) * dv;
            for col in 0..width {
                let u = -1.0 + (col as f64 + 0.5) * du;
                let dust = overlay.map_or(1.0, |m| m.transmission(u as f32, v as f32));
                data.push(sampler.transmission_soft(u as f32, v as f32, feather) * dust);
            }
        }
        ApertureMask::from_luma_f32(width, height, &data)
    }
}

/// An [`Aperture`] with its constants precomputed (the iris's trigonometry); cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct ApertureSampler<'a> {
    shape: Shape<'a>,
}

#[derive(Clone, Copy, Debug)]
enum Shape<'a> {
    Circle,
    Iris(IrisGeometry),
    Mask(&'a ApertureMask),
}

impl ApertureSampler<'_> {
    /// True when the opening is convex (the circle and the iris; a mask may not be): then a
    /// triangle whose corners lie inside, at least `feather/2` from the edge, lies wholly in
    /// the fully open part, as does every point interpolated between its corners.
    pub fn is_convex(&self) -> bool {
        !matches!(self.shape, Shape::Mask(_))
    }

    /// See [`Aperture::transmission`].
    pub fn transmission(&self, u: f32, v: f32) -> f32 {
        match self.shape {
            Shape::Circle => {
                let (u, v) = (f64::from(u), f64::from(v));
                if u * u + v * v <= 1.0 { 1.0 } else { 0.0 }
            }
            Shape::Iris(g) => {
                if g.signed_distance(f64::from(u), f64::from(v)) <= 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Shape::Mask(m) => m.transmission(u, v),
        }
    }

    /// See [`Aperture::transmission_soft`]. For a mask, a `feather` up to one texel gives the
    /// bilinear transmission (already smooth at that scale); a wider one ramps on the mask's
    /// distance field, which treats the mask as open where it is at least 1/2 — grey levels
    /// inside are not kept (sample grey overlays with [`ApertureMask::transmission`]).
    #[inline]
    pub fn transmission_soft(&self, u: f32, v: f32, feather: f32) -> f32 {
        #[allow(
            clippy::neg_cmp_op_on_partial_ord,
            reason = "NaN feather means no feather"
        )]
        if !(feather > 0.0) {
            return self.transmission(u, v);
        }
        if let Shape::Mask(m) = self.shape {
            let (tu, tv) = m.texel_size();
            if feather <= tu.max(tv) {
                return m.transmission(u, v);
            }
        }
        smooth_edge(f64::from(self.signed_distance(u, v)), f64::from(feather)) as f32
    }

    /// Where [`Self::transmission_soft`] with `feather` is the same at every point within
    /// `radius` of `(u, v)`: `Some(1.0)` wholly open, `Some(0.0)` wholly closed, `None` where
    /// it may vary. Exact for the circle and the iris (their signed distance is a true
    /// distance, whose slope is 1: open where `d + radius ≤ −feather/2`, up to a rounding
    /// slack); conservative for a mask ([`ApertureMask::uniform_around`]). `None` for a
    /// feather that is not positive.
    #[inline]
    pub fn uniform_around(&self, u: f32, v: f32, radius: f32, feather: f32) -> Option<f32> {
        #[allow(
            clippy::neg_cmp_op_on_partial_ord,
            reason = "NaN feather or radius means no answer"
        )]
        if !(feather > 0.0) || !(radius >= 0.0) {
            return None;
        }
        if let Shape::Mask(m) = self.shape {
            return m.uniform_around(u, v, radius, feather);
        }
        let d = f64::from(self.signed_distance(u, v));
        let margin = f64::from(radius) + 0.5 * f64::from(feather) + UNIFORM_SLACK;
        if d <= -margin {
            Some(1.0)
        } else if d >= margin {
            Some(0.0)
        } else {
            None
        }
    }

    /// [`Self::transmission_soft`] at `(u, v)`, and a distance within which it is the same
    /// (0 where this cannot tell, or the transmission is partial there): the reach of
    /// [`Self::uniform_around`]'s answer, from one evaluation, for stepping along a path.
    #[inline]
    pub fn transmission_reach(&self, u: f32, v: f32, feather: f32) -> (f32, f32) {
        #[allow(
            clippy::neg_cmp_op_on_partial_ord,
            reason = "NaN feather means no feather"
        )]
        if !(feather > 0.0) {
            return (self.transmission(u, v), 0.0);
        }
        if let Shape::Mask(m) = self.shape {
            return m.transmission_reach(u, v, feather);
        }
        let d = f64::from(self.signed_distance(u, v));
        let reach = d.abs() - 0.5 * f64::from(feather) - UNIFORM_SLACK;
        let t = smooth_edge(d, f64::from(feather)) as f32;
        (t, if reach > 0.0 { reach as f32 } else { 0.0 })
    }

    /// True when [`Self::transmission_soft`] with `feather` is the feather's smoothstep of
    /// [`Self::signed_distance`] (`smooth_edge`): always for the circle and an iris, for a mask
    /// where the feather is wider than a texel (under it, the bilinear transmission).
    #[inline]
    pub fn soft_is_distance_ramp(&self, feather: f32) -> bool {
        match self.shape {
            Shape::Mask(m) => {
                let (tu, tv) = m.texel_size();
                feather > tu.max(tv)
            }
            _ => feather > 0.0,
        }
    }

    /// See [`Aperture::signed_distance`].
    #[inline]
    pub fn signed_distance(&self, u: f32, v: f32) -> f32 {
        match self.shape {
            Shape::Circle => {
                let (u, v) = (f64::from(u), f64::from(v));
                ((u * u + v * v).sqrt() - 1.0) as f32
            }
            Shape::Iris(g) => g.signed_distance(f64::from(u), f64::from(v)) as f32,
            Shape::Mask(m) => m.signed_distance(u, v),
        }
    }
}

/// Normalised units added to [`ApertureSampler::uniform_around`]'s margin for the roundings
/// of f32 positions and distances (a feather is at least 1e-4).
const UNIFORM_SLACK: f64 = 1e-6;

/// An [`ApertureSampler`] of the circle, borrowing nothing.
pub const CIRCLE_SAMPLER: ApertureSampler<'static> = ApertureSampler {
    shape: Shape::Circle,
};

/// The smooth step across an edge at signed distance `d` over a band of width `feather`:
/// 1 well inside, 0 well outside, 1/2 on the edge, odd about it; a NaN distance gives 0.
#[inline]
pub(crate) fn smooth_edge(d: f64, feather: f64) -> f64 {
    let t = 0.5 - d / feather;
    let t = if t >= 1.0 {
        1.0
    } else if t > 0.0 {
        t
    } else {
        0.0
    };
    t * t * (3.0 - 2.0 * t)
}

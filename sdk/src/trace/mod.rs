//! Sequential ray tracing through a lens, forward, backward and along ghost paths.
//!
//! A [`Sequence`] is the list of surface interactions for one wavelength (refract, reflect,
//! sensor), with the geometry and indices each needs. The same per-ray physics (see `lane`)
//! serves the scalar f64 API ([`Sequence::trace`]) and the batched structure-of-arrays APIs in
//! f32 and f64 ([`RayBatch`], [`Sequence::trace_batch`]).
//!
//! Intersection is vertex-local and curvature-based (after Spencer & Murty 1962): the conic
//! `c(x² + y²) + c(1+k)z² − 2z = 0` is solved along the ray from the ray's own point as
//! `A t² − 2B t + C = 0`, taking the root on the sheet through the vertex in either direction
//! of travel — the root Spencer & Murty's `t = C / (B + sign(B)·√(B² − AC))` gives from the
//! vertex tangent plane — in a form without cancellation (`C / (B ± √…)` or `(B ± √…) / A`),
//! which becomes the plane as `c → 0`. Solving from the tangent plane itself would lose the
//! hit of a ray running nearly parallel to it (see `lane`). Even aspheres are refined by
//! Newton's method from the conic hit, with an iteration cap and a typed failure.

mod batch;
mod fate;
mod lane;
mod real;
mod scalar;
mod sequence;

pub use batch::{LANES, PROBE_CLIP_SLACK, Packet, Probe, RayBatch};
pub use fate::Fate;
pub use real::Real;
pub use scalar::{Hit, Ray, TraceResult};
pub use sequence::{
    Interaction, InterfaceTable, InterfaceTableSet, PathError, Sequence, Step, TABLE_LEN,
};

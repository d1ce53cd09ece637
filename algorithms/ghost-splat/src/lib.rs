//! Ghosts by forward ray splatting: per light, per two-reflection ghost (the paths
//! `flarebench_sdk::ghost::enumerate_ghosts` lists, as the other ghost plugins draw) and per
//! wavelength band, stratified rays over the ghost's entrance region are traced in f64 along
//! its path and each ray's flux — Fresnel/coatings exact, the aperture's transmission at its
//! stop crossing, the light's intensity and cos θ — is splatted where it lands, in the band's
//! colour, into an HDR image in the ray-traced renderer's units (an image's sum is the flux it
//! carries into the frame).
//!
//! The rays are the sdk's independent Monte-Carlo reference's
//! (`flarebench_sdk::ghost::monte_carlo::GhostRays`: its pilot, strata and random streams),
//! so the image is an unbiased estimate of the ghosts (apart from the kernel's blur) whose
//! error falls as 1/√rays, with no grid to fold over itself: caustics and ghosts whose ray grid
//! folds cost the same as any other.
//!
//! - [`colour`]: each ghost's colour per band, integrated over the band in 5 nm steps.
//! - [`kernel`]: the splat kernel (box, or a tent of stated half-width).
//! - [`render`]: tracing every ghost's rays and splatting them, deterministically.
//! - [`error`]: what can go wrong.
//! - [`plugin`]: the plugin (ABI v1), its parameters `rays`, `kernel_px`, `bands`, `seed`.

pub mod colour;
pub mod error;
pub mod kernel;
pub mod plugin;
pub mod render;

pub use error::SplatError;

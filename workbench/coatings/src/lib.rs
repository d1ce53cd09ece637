//! Anti-reflection coatings against a lens's flare.
//!
//! Coatings change how much light of each wavelength a ghost carries, hardly where it lands:
//! each ghost's image at each traced band is rendered once ([`basis`]) and any choice of
//! coatings re-weights those images ([`model`]). On that:
//!
//! - [`catalogue`]: the anti-reflection designs a surface can take (bare to a six-layer
//!   multicoat), their layers for a surface's glass, and their cost ranks.
//! - [`choice`]: each surface's design from the catalogue that cuts the flare over a set of
//!   light angles, within a budget of premium surfaces.
//! - [`fit`]: the coatings, and the light's intensity and colour, that reproduce a linear
//!   image of a lens's flare, with uncertainties and what the image does not constrain.
//! - [`reweight`]: the colours a basis's images take under given coatings.
//! - [`solve`]: the bounded Levenberg–Marquardt both use.

pub mod basis;
pub mod catalogue;
pub mod choice;
pub mod fit;
pub mod model;
pub mod reweight;
pub mod solve;

use ghost_raytrace::GhostRenderError;

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum CoatingError {
    #[error(transparent)]
    Render(#[from] GhostRenderError),
    #[error("no light to render the flare of")]
    NoLight,
    #[error("lens `{0}` has no surface between air and glass to coat")]
    NothingToCoat(String),
    #[error("the mask's size differs from the image's")]
    MaskSize,
    #[error("no starting point to fit from")]
    NoStart,
    #[error("the ghosts' colours or images could not be used (non-finite values)")]
    Colours,
    #[error(
        "lens `{0}` has a sensor stack: fitting and choosing coatings model the lens's own surfaces only; remove it (`--sensor-stack none` on `convert`) first"
    )]
    SensorStack(String),
}

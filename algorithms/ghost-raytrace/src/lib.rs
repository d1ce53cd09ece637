//! Ghost flares by sparse ray grids (Hullin et al. 2011): for a lens and a scene of lights,
//! plan which ghosts and wavelengths are needed, trace each ghost's grid and rasterize it into
//! a linear HDR image.
//!
//! - [`scene`]: lights and quality presets.
//! - [`plan`]: which ghosts and wavelengths each light needs, and what is left out (with its
//!   energy share).
//! - [`colour`]: each ghost's colour per traced band, integrated in 5 nm steps.
//! - [`method`]: how each ghost is drawn (meshed or splatted), by a per-ghost cost and error
//!   model within the preset's error budget.
//! - [`ghosts`]: carrying out a plan into a linear HDR image.
//! - [`tiles`]: every planned ghost drawn alone, into the window of the frame it lights.
//! - [`reference`]: the dense reference renderer behind every error figure.
//! - [`crosscheck`]: every ghost by the independent Monte-Carlo reference, the mesh reference
//!   and the renderer, side by side.
//! - [`error`]: what can go wrong.
//! - [`plugin`]: the same renderer as a plugin (ABI v1), for `flarebench compare`.

pub mod colour;
pub mod crosscheck;
pub mod error;
pub mod ghosts;
pub mod method;
pub mod plan;
pub mod plugin;
pub mod reference;
pub mod scene;
pub mod tiles;

pub use error::GhostRenderError;

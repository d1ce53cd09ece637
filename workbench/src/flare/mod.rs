//! The application layer of a flare frame: a scene (lens, lights, aperture, frame, what the
//! flare is made of), a preset (how it is planned and drawn), and [`Flare`], which runs the
//! pipeline — plan, backend render, exposure, starbursts — with what it keeps from frame to
//! frame. The commands (`render`, `apply`, `bench`, `sweep`) and the viewer describe frames
//! and call [`Flare::render`]; none spells the pipeline out.
//!
//! - [`scene`]: what a frame is of — [`Scene`], [`StarburstMode`], [`frame_for`].
//! - [`preset`]: how a frame is drawn — [`Preset`].
//! - [`renderer`]: the pipeline — [`Flare`], and what a frame gives ([`Rendered`]).
//! - [`backend`]: where ghosts are drawn (CPU rasterizer or GPU), [`GhostBackend`].
//! - [`exposure`]: the automatic exposure.
//! - [`compose`]: starbursts added to the ghosts' image, the flare added onto a background.

pub mod backend;
pub mod compose;
pub mod exposure;
pub mod preset;
pub mod renderer;
pub mod scene;

pub use backend::{BackendChoice, BackendReport, GhostBackend};
pub use preset::Preset;
pub use renderer::{Flare, FrameTimings, Rendered};
pub use scene::{Scene, StarburstMode, frame_for};

//! Rendering lens flare for a scene: parse the scene, plan what it needs, render, report.
//!
//! - [`scene`]: lights, output frame and quality presets.
//! - [`plan`]: which ghosts and wavelengths each light needs, and what is left out (with its
//!   energy share).
//! - [`colour`]: each ghost's colour per traced band, integrated in 5 nm steps.
//! - [`ghosts`]: carrying out a plan into a linear HDR image.
//! - [`report`]: timings, counts, energies and errors, as text or JSON.

pub mod colour;
pub mod ghosts;
pub mod plan;
pub mod report;
pub mod scene;

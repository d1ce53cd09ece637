//! Flare datasets (`flarebench dataset`): many flares drawn at random from the bundled lenses,
//! apertures and lights, each rendered with its layers and an exact annotation, for training
//! flare-removal networks. docs/datasets.md describes the sampler, the files and their
//! schema.
//!
//! Every sample is a pure function of `(seed, index)` and the sampler: its random numbers come
//! from a stream of its own ([`rng`]), it is rendered on the CPU, and its files hold nothing of
//! the machine or the time — so it is the same bytes whatever the thread count, the shard or
//! a resumed run.
//!
//! - [`config`]: the sampler's TOML file, its fields and defaults.
//! - [`sampler`]: [`Sampler::from_toml_str`] and [`Sampler::sample`]`(seed, index)` →
//!   [`SampleSpec`].
//! - [`sample`]: [`render_sample`]`(&SampleSpec)` → [`SampleOutput`], the layers and the
//!   annotation.
//! - [`ghost_layers`]: the ghost layers summed from each ghost drawn alone in its window.
//! - [`annotation`]: the annotation's schema, ghost energies and boxes.
//! - [`layers`]: the EXR (named channels) and PNG files of a sample.
//! - [`manifest`]: the directory's layout, records, the manifest, resuming.
//! - [`verify`]: `dataset verify`.

pub mod annotation;
pub mod config;
pub mod ghost_layers;
pub mod layers;
pub mod manifest;
pub mod rng;
pub mod sample;
pub mod sampler;
pub mod verify;

pub use annotation::{Annotation, GhostAnnotation, GhostMeasure};
pub use config::SamplerConfig;
pub use sample::{SampleOutput, render_sample};
pub use sampler::{SampleSpec, Sampler, SamplerError};
pub use verify::{VerifyReport, verify};

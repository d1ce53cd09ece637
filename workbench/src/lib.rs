//! flarebench, the application: command line, lens resolution, reports.
//!
//! The optics live in `flarebench-sdk`; this crate turns them into commands.

pub mod algo_spec;
pub mod aperture_file;
pub mod cli;
pub mod curation;
pub mod dataset;
pub mod document;
#[cfg(feature = "tui")]
pub mod edit;
pub mod file_watch;
pub mod flare;
pub mod gallery;
pub mod input_image;
pub mod label;
pub mod lens_drawing;
pub mod lens_library;
pub mod lens_listing;
pub mod light_path;
pub mod link;
pub mod output;
pub mod panics;
pub mod plugin_dirs;
pub mod plugin_template;
pub mod precomputed;
pub mod reference_file;
pub mod report;
pub mod sensor_stack;
pub mod sequence;
pub mod sources;
pub mod stability;
pub mod stats;
pub mod sweep;
pub mod table;
#[cfg(feature = "window")]
pub mod viewer;

// The backend and composition modules' earlier paths (`flarebench::backend`,
// `flarebench::compose`), kept for code written against them.
pub use flare::{backend, compose};

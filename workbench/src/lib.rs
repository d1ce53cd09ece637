//! flarebench, the application: command line, lens resolution, reports.
//!
//! The optics live in `flarebench-sdk`; this crate turns them into commands.

pub mod aperture_file;
pub mod cli;
pub mod compose;
pub mod input_image;
pub mod lens_library;
pub mod output;
pub mod report;
pub mod sources;
pub mod table;

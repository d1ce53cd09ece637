//! Lens file formats.

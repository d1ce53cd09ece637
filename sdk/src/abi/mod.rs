//! The plugin interface: a hand-written, versioned C ABI and the safe Rust layers on both
//! sides of it (docs/plugins.md is the author's guide).
//!
//! - [`v1`]: the `#[repr(C)]` types and constants that cross the library boundary (ABI 1.x).
//! - [`author`]: what a plugin author implements — the [`author::FlarePlugin`] trait, parameter
//!   specifications, the scene and output views.
//! - [`export`]: the thunks behind [`export_plugin!`](crate::export_plugin): pointer checks,
//!   `catch_unwind` around every call, errors as status + message.
//! - `host` (cargo feature `host`, which plugins leave off): loading a plugin library (never
//!   unloaded), checking its header, calling it, and validating what it returns.
//! - [`params`]: parameter values from `key=value` text, checked against the descriptors.

pub mod author;
pub mod export;
#[cfg(feature = "host")]
pub mod host;
pub mod params;
pub mod v1;

//! Sequential ray tracing.

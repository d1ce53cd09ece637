//! Paraxial analysis.

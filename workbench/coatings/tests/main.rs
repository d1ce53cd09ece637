//! The coatings crate's tests, one binary (docs/tests.md).

mod catalogue;
mod fit;

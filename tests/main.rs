//! The integration tests of the workspace, one test binary (`cargo test -p flarebench-tests --test
//! workspace`): each file of this directory is a module, so the crate and its dependencies are
//! linked, and its generic code instantiated, once instead of once per file.
//!
//! Run one file's tests by its module path: `cargo test -p flarebench-tests --test workspace source_focal_lengths::`.

mod build_features;
mod flaresim_render;
mod oracle;
mod plugin_host;
mod precision;
mod source_focal_lengths;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    flarebench_test_support::assert_every_test_file_is_a_module(dir, &[]);
}

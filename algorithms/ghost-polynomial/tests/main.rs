//! The integration tests of the polynomial renderer, one test binary (`cargo test -p flarebench-ghost-polynomial --test
//! polynomial`): each file of this directory is a module, so the crate and its dependencies are
//! linked, and its generic code instantiated, once instead of once per file.
//!
//! Run one file's tests by its module path: `cargo test -p flarebench-ghost-polynomial --test polynomial heliar::`.

mod cache;
mod closed_forms;
mod heliar;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled), but `plugin.rs`: a binary of its own, as its
/// test sets an environment variable before any other thread runs.
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    flarebench_test_support::assert_every_test_file_is_a_module(&dir, &["plugin"]);
}

//! The coatings crate's tests, one binary (docs/tests.md).

mod catalogue;
mod fit;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    flarebench_test_support::assert_every_test_file_is_a_module(&dir, &[]);
}

//! The integration tests of the sdk, one test binary (`cargo test -p flarebench-sdk --test
//! sdk`): each file of this directory is a module, so the crate and its dependencies are
//! linked, and its generic code instantiated, once instead of once per file.
//!
//! Run one file's tests by its module path: `cargo test -p flarebench-sdk --test sdk zemax_pbrt::`.

mod abi_layout;
mod analytic_optics;
mod bounds_monte_carlo;
mod chief_ray;
mod flaresim;
mod flaresim_corpus;
mod four_reflection_bound;
mod ghost_render;
mod ghosts;
mod layering;
mod lens_library;
mod olf_table;
mod properties;
mod raster;
mod self_contained;
mod sensor_stack;
mod starburst;
mod zemax_pbrt;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    flarebench_test_support::assert_every_test_file_is_a_module(&dir, &[]);
}

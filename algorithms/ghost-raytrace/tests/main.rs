//! The integration tests of the ray-grid renderer, one test binary (`cargo test -p flarebench-ghost-raytrace --test
//! raytrace`): each file of this directory is a module, so the crate and its dependencies are
//! linked, and its generic code instantiated, once instead of once per file.
//!
//! Run one file's tests by its module path: `cargo test -p flarebench-ghost-raytrace --test raytrace sink::`.

mod draw_methods;
mod four_reflections;
mod frame_reuse;
mod fringe_apertures;
mod monte_carlo;
mod outside_field;
mod plan_grids;
mod plugin;
mod precision;
mod reference;
mod sink;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    flarebench_test_support::assert_every_test_file_is_a_module(&dir, &[]);
}

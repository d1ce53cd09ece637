//! The workbench's integration tests, one test binary (`cargo test -p flarebench --test
//! workbench`): each file of this directory is a module. One binary links wgpu, egui and winit
//! once instead of once per file.
//!
//! Run one file's tests by its module path: `cargo test -p flarebench --test workbench render::`.

mod common;
#[cfg(feature = "window")]
mod offscreen_viewer;

mod cli;
mod coatings;
mod convert;
mod dataset;
#[cfg(feature = "tui")]
mod edit_app;
#[cfg(feature = "tui")]
mod edit_cells;
mod edit_document;
#[cfg(feature = "tui")]
mod edit_robustness;
#[cfg(feature = "tui")]
mod edit_tmux;
mod fit;
mod gallery;
mod golden;
mod gpu;
mod lens_drawing;
mod lens_library;
mod plugin_loop;
mod plugins;
mod readme;
mod render;
mod sensor_stack;
mod sequence;
mod stability;
mod starburst;
mod sweep;
#[cfg(feature = "window")]
mod viewer;
#[cfg(feature = "window")]
mod viewer_plugins;
#[cfg(feature = "window")]
mod window;

/// Every test file of this directory is a module above (the package sets `autotests = false`,
/// so a file left out would never be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let files = flarebench_test_support::assert_every_test_file_is_a_module(&dir, &[]);
    assert!(files > 20, "{files} test files");
}

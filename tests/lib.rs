//! Shared helpers for the workspace integration tests: the bundled lens library.

use std::path::{Path, PathBuf};

use flarebench_sdk::LensSystem;
use flarebench_sdk::io::read_lens;

/// The repository's `lenses/` directory.
pub fn lenses_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses")
}

/// Loads `lenses/<stem>.xml`, panicking with the loader's message on failure.
pub fn load_lens(stem: &str) -> LensSystem {
    let path = lenses_dir().join(format!("{stem}.xml"));
    read_lens(&path).unwrap_or_else(|e| panic!("{e}")).system
}

/// The stems of every bundled lens, sorted.
pub fn library_stems() -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(lenses_dir())
        .expect("lenses/ exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .filter_map(|p| p.file_stem()?.to_str().map(str::to_string))
        .collect();
    stems.sort();
    stems
}

/// The target directory this test binary was built into (`target/debug`), where
/// `cargo build --workspace` puts the plugin libraries (`cdylib`s).
pub fn build_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary has a path");
    // target/debug/deps/<test>-<hash> → target/debug
    exe.parent()
        .and_then(Path::parent)
        .expect("test binaries live in <target>/<profile>/deps")
        .to_path_buf()
}

/// The built plugin library of crate lib `name` (`libNAME.so` on Linux), panicking with the
/// command to run when it has not been built.
pub fn plugin_library(name: &str) -> PathBuf {
    let path = build_dir().join(format!(
        "{}{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    assert!(
        path.is_file(),
        "{} is missing: run `cargo build --workspace` before `cargo test --workspace`",
        path.display()
    );
    path
}

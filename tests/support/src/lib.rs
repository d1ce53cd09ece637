//! Helpers shared by the workspace's tests and benches (a dev-dependency of every crate that
//! tests against the bundled lenses or the built plugin libraries): the lens library,
//! FlareSim's library in `tests/data/`, the plugin libraries `cargo build --workspace` puts in
//! the target directory, and the fixtures several crates' tests share.

use std::path::{Path, PathBuf};

use flarebench_sdk::io::{
    LensFileError, LoadedLens, ReadOptions, parse_flaresim, read_lens, read_lens_with,
};
use flarebench_sdk::{LensSystem, Medium, Surface};

/// The repository's `lenses/` directory.
pub fn lenses_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../lenses")
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

/// FlareSim's lens library, `tests/data/flaresim-lenses/lens_files/` (1,373 `.lens` files,
/// MIT; source and licence in `tests/data/flaresim-lenses/`).
pub fn flaresim_library_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/flaresim-lenses/lens_files")
}

/// Every file of FlareSim's library, sorted.
pub fn flaresim_library_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(flaresim_library_dir())
        .expect("the library is in tests/data/flaresim-lenses")
        .map(|e| e.expect("directory entry").path())
        .collect();
    files.sort();
    files
}

/// Reads one file of FlareSim's library as a user would, by its `.lens` extension; the three
/// whose names were cut short before `.lens` (a `/` in the lens's name) are read as `.lens`
/// text with `parse_flaresim`. `lenient` clamps clear apertures that are still impossible.
pub fn read_flaresim_library_file(path: &Path, lenient: bool) -> Result<LoadedLens, LensFileError> {
    if path.extension().is_some_and(|e| e == "lens") {
        let options = ReadOptions {
            lenient_apertures: lenient,
            ..ReadOptions::default()
        };
        return read_lens_with(path, &options);
    }
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| LensFileError::io(&label, &e))?;
    parse_flaresim(&text, &label, None, lenient)
}

/// The target directory the running test or bench was built into (`target/debug`,
/// `target/release`), where `cargo build --workspace` puts the plugin libraries (`cdylib`s)
/// and the `flarebench` binary.
pub fn build_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary has a path");
    // target/debug/deps/<test>-<hash> → target/debug
    exe.parent()
        .and_then(Path::parent)
        .expect("test binaries live in <target>/<profile>/deps")
        .to_path_buf()
}

/// The file name of a shared library of lib name `name` on this platform (`libNAME.so`).
pub fn library_file_name(name: &str) -> String {
    format!(
        "{}{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )
}

/// The built plugin library of crate lib `name` in [`build_dir`], panicking with the command
/// to run when it has not been built.
pub fn plugin_library(name: &str) -> PathBuf {
    let path = build_dir().join(library_file_name(name));
    assert!(
        path.is_file(),
        "{} is missing: run `cargo build --workspace` before `cargo test --workspace`",
        path.display()
    );
    path
}

/// A stop of radius 2 mm, 5 mm of air, a 3 mm plane-parallel plate of n = 1.5 (no
/// dispersion, semi-diameter 10 mm), 10 mm of air, the sensor, on a 20 × 20 mm film: its
/// ghosts and their energies have closed forms.
pub fn plate() -> LensSystem {
    let mut sys = LensSystem::new(
        "plate",
        vec![
            Surface::stop(5.0, 2.0),
            Surface::spherical(0.0, 3.0, Medium::Model { nd: 1.5, vd: None }, 10.0),
            Surface::spherical(0.0, 10.0, Medium::Air, 10.0),
            Surface::sensor(15.0),
        ],
    );
    sys.film_width_mm = 20.0;
    sys.film_height_mm = 20.0;
    sys
}

/// Checks that every test file of the directory `tests` (a `.rs` file, or a folder with a
/// `mod.rs`) but those named in `own_binaries` (test targets of their own in the package's
/// `Cargo.toml`) is a module of its `main.rs`: a package with `autotests = false` and one test
/// binary would never compile a file left out. Panics naming the first file that is not;
/// returns how many are.
pub fn assert_every_test_file_is_a_module(tests: &Path, own_binaries: &[&str]) -> usize {
    let main = std::fs::read_to_string(tests.join("main.rs"))
        .unwrap_or_else(|e| panic!("{}: {e}", tests.join("main.rs").display()));
    let mut files = 0;
    for entry in std::fs::read_dir(tests).expect("the tests directory is readable") {
        let path = entry.expect("a directory entry").path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        let is_module = if path.is_dir() {
            path.join("mod.rs").is_file()
        } else {
            path.extension().is_some_and(|e| e == "rs") && stem != "main"
        };
        if is_module && !own_binaries.contains(&stem) {
            files += 1;
            assert!(
                main.contains(&format!("\nmod {stem};\n")),
                "{} is not a module of {}",
                path.display(),
                tests.join("main.rs").display()
            );
        }
    }
    files
}

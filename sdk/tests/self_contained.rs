//! The sdk packages on its own (`cargo package -p flarebench-sdk`): every file its sources
//! compile in with `include_str!`/`include_bytes!` lies inside the crate's directory, and the
//! plugin host (libloading) is an optional feature that plugins leave off.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let p = entry.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn every_included_file_lies_inside_the_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .canonicalize()
        .unwrap();
    let mut files = Vec::new();
    for dir in ["src", "tests", "benches", "examples"] {
        rust_files(&root.join(dir), &mut files);
    }
    let mut includes = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for macro_name in ["include_str!(\"", "include_bytes!(\""] {
            for (at, _) in text.match_indices(macro_name) {
                let rest = &text[at + macro_name.len()..];
                let rel = &rest[..rest.find('"').unwrap()];
                let target = file.parent().unwrap().join(rel);
                let target = target
                    .canonicalize()
                    .unwrap_or_else(|e| panic!("{}: {rel}: {e}", file.display()));
                assert!(
                    target.starts_with(&root),
                    "{} includes {}, outside the sdk crate",
                    file.display(),
                    target.display()
                );
                includes += 1;
            }
        }
    }
    // The glass catalogue and the catalogue test table at least.
    assert!(includes >= 2, "{includes} includes found");
}

#[test]
fn the_plugin_host_is_an_optional_feature() {
    let manifest =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml")).unwrap();
    let line = manifest
        .lines()
        .find(|l| l.starts_with("libloading"))
        .expect("libloading is a dependency of the host");
    assert!(line.contains("optional = true"), "{line}");
    assert!(
        manifest.contains("host = [\"dep:libloading\"]"),
        "{manifest}"
    );
}

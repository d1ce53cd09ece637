//! The sdk's modules form layers: a module may use modules of lower layers only, never one of
//! its own layer or above, so no two modules depend on each other, however indirectly.
//!
//! Every `crate::…` path in `src/**/*.rs` (comments left out) names the top-level module it
//! reaches; the names `lib.rs` re-exports at the crate root (`crate::LensSystem`) count as
//! their own modules. A failure names the file, the line and the import.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The layers, lowest first.
const LAYERS: &[&[&str]] = &[
    // Foundation types and tables: no dependencies inside the crate.
    &[
        "hash",
        "spectrum",
        "rect",
        "ghost_path",
        "color",
        "aperture",
        "lens_kind",
    ],
    // Images, glasses, bare interfaces.
    &["image", "glass", "fresnel"],
    // Frames and the rasterizer (on images); coatings (on glasses and interfaces).
    &["frame", "raster", "coating"],
    // The lens prescription.
    &["system"],
    // First-order analysis of a lens.
    &["paraxial"],
    // Lens and bounds files.
    &["io"],
    // The ray tracer; the lens fingerprint (hashes `io`'s canonical XML).
    &["trace", "fingerprint"],
    // Ghosts: paths, grids, bounds, tables, meshes.
    &["ghost"],
    // The diffraction starburst (uses the ghost grid tracer for its chief ray).
    &["starburst"],
    // The plugin interface.
    &["abi"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("reading src") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The line without its `//` comment (doc comments included).
fn code_of(line: &str) -> &str {
    line.split_once("//").map_or(line, |(code, _)| code)
}

/// The identifiers following each `crate::` in `code`; for `crate::{a, b::c}` each of `a`, `b`.
fn crate_targets(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let after = &rest[at + "crate::".len()..];
        if let Some(group) = after.strip_prefix('{') {
            let inner = group.split('}').next().unwrap_or("");
            for item in inner.split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
        rest = after;
    }
    out
}

/// The crate root's re-exports (`pub use module::{A, B};`): name → module.
fn root_reexports(lib: &str) -> HashMap<String, String> {
    let mut map = HashMap::new();
    for line in lib.lines() {
        let Some(rest) = line.trim().strip_prefix("pub use ") else {
            continue;
        };
        let rest = rest.trim_end_matches(';');
        let Some((module, names)) = rest.split_once("::") else {
            continue;
        };
        for name in names.trim_matches(|c| c == '{' || c == '}').split(',') {
            let name = name.trim();
            if !name.is_empty() {
                map.insert(name.to_string(), module.to_string());
            }
        }
    }
    map
}

#[test]
fn every_module_uses_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("reading lib.rs");
    let reexports = root_reexports(&lib);
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut problems = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&src).expect("under src");
        if rel == Path::new("lib.rs") {
            continue;
        }
        let first = rel.components().next().expect("a path").as_os_str();
        let module = first.to_string_lossy().trim_end_matches(".rs").to_string();
        let Some(own) = layer_of(&module) else {
            problems.push(format!(
                "{}: module `{module}` is in no layer (add it to LAYERS)",
                rel.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(file).expect("reading a source file");
        for (n, line) in text.lines().enumerate() {
            for target in crate_targets(code_of(line)) {
                let target = reexports.get(&target).cloned().unwrap_or(target);
                if target == module {
                    continue;
                }
                match layer_of(&target) {
                    Some(l) if l < own => {}
                    Some(l) => problems.push(format!(
                        "{}:{}: `{module}` (layer {own}) imports `{target}` (layer {l}): `{}`",
                        rel.display(),
                        n + 1,
                        line.trim()
                    )),
                    // A macro's `$crate::` from another crate's view, or a name that is no
                    // module (e.g. `crate::` in a string): only modules are layered.
                    None => {}
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "the sdk's module layers are broken:\n{}",
        problems.join("\n")
    );
}

#[test]
fn every_top_level_module_is_layered() {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"))
        .expect("reading lib.rs");
    for line in lib.lines() {
        if let Some(name) = line.trim().strip_prefix("pub mod ") {
            let name = name.trim_end_matches(';');
            assert!(
                layer_of(name).is_some(),
                "module `{name}` is in no layer of tests/layering.rs"
            );
        }
    }
}

#[test]
fn the_import_scanner_reads_groups_and_paths() {
    assert_eq!(
        crate_targets("use crate::{ghost::GhostPath, io};"),
        ["ghost", "io"]
    );
    assert_eq!(
        crate_targets("let x = crate::io::read(crate::paraxial::f());"),
        ["io", "paraxial"]
    );
}

//! The README's test command is `cargo build --workspace && cargo test --workspace`. The second
//! reuses what the first built only if every dependency is built with the same features in
//! both: a dev-dependency that turns on a feature of a shared crate (criterion turning on
//! serde's `alloc`, say) makes `cargo test` rebuild that crate and everything above it —
//! the sdk, the renderers, the GPU backend and the workbench, about two minutes of a clean
//! 2-core run. This test compares the features `cargo tree` resolves without and with the
//! dev-dependencies and names every crate whose features differ.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Package (`name vX.Y.Z`, with its `(proc-macro)` or path marker) → the feature lists
/// `cargo tree` printed for it.
fn resolved_features(edges: &str) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../Cargo.toml");
    let output = Command::new(cargo)
        .args([
            "tree",
            "--workspace",
            "--offline",
            "--manifest-path",
            manifest,
            "--prefix",
            "none",
            "--format",
            "{p}|{f}",
            "-e",
            edges,
        ])
        .output()
        .expect("cargo tree runs");
    assert!(
        output.status.success(),
        "cargo tree -e {edges} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut packages: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let line = line.trim().trim_end_matches(" (*)");
        if let Some((package, features)) = line.split_once('|') {
            packages
                .entry(package.to_string())
                .or_default()
                .insert(features.to_string());
        }
    }
    packages
}

#[test]
fn dev_dependencies_turn_on_no_feature_of_a_shared_crate() {
    let build = resolved_features("normal,build");
    let test = resolved_features("normal,build,dev");
    assert!(
        build.keys().any(|p| p.starts_with("flarebench-sdk ")),
        "cargo tree listed no flarebench-sdk: {build:?}"
    );
    let differing: Vec<String> = build
        .iter()
        .filter_map(|(package, features)| {
            let with_dev = test.get(package)?;
            (with_dev != features)
                .then(|| format!("{package}: build {features:?}, test {with_dev:?}"))
        })
        .collect();
    assert!(
        differing.is_empty(),
        "these crates get other features under `cargo test` than under `cargo build`, so the \
         README's test command builds them (and all above them) twice; turn the features on in \
         the workspace's [workspace.dependencies]:\n{}",
        differing.join("\n")
    );
}

//! Helpers shared by the end-to-end tests: run the built `flarebench` binary.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

/// Runs `flarebench` with `args`.
pub fn flarebench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flarebench"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// Runs `flarebench` with `args`, asserts success and parses its standard output as JSON.
pub fn json(args: &[&str]) -> Value {
    let out = flarebench(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

/// A directory of this test process for files it writes (`tag` keeps test binaries apart).
pub fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flarebench-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

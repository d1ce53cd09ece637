//! Helpers shared by the end-to-end tests: run the built `flarebench` binary.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::process::{Command, Output};

pub mod x11;

use serde_json::Value;

/// The reference cache the tests' runs share (`FLAREBENCH_REFERENCE_CACHE`): in the target
/// directory, not the user's own cache.
pub const REFERENCE_CACHE: &str = concat!(env!("CARGO_TARGET_TMPDIR"), "/reference-cache");

/// The built `flarebench` binary as a command, with the tests' reference cache.
pub fn command() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flarebench"));
    c.env("FLAREBENCH_REFERENCE_CACHE", REFERENCE_CACHE);
    c
}

/// Runs `flarebench` with `args`.
pub fn flarebench(args: &[&str]) -> Output {
    command().args(args).output().expect("binary runs")
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

/// A fresh directory for the files one test writes, `flarebench-{tag}-…` in the system's
/// temporary directory. It is removed when the returned `TempDir` is dropped: keep it alive
/// for as long as the test (and any process it runs) uses `.path()`.
pub fn temp_dir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("flarebench-{tag}-"))
        .tempdir()
        .unwrap()
}

//! What the command line's integration tests share: running the built binary (in the
//! current folder or in a given one), asserting success or failure, and reading a field
//! file written one value per line.
//!
//! Each test file includes it with `mod common;` and uses a part of it.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::{Command, Output};

/// The `spectral-mesh` binary built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_spectral-mesh"))
}

/// Runs `spectral-mesh ARGS` in the tests' working folder.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

/// Runs `spectral-mesh ARGS` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

fn succeeded(args: &[&str], o: Output) -> String {
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn failed(args: &[&str], o: Output) -> String {
    assert!(!o.status.success(), "{args:?} should fail");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `spectral-mesh ARGS`, asserts it succeeded, returns its standard output.
pub fn ok(args: &[&str]) -> String {
    succeeded(args, run(args))
}

/// As [`ok`], in `dir`.
pub fn ok_in(dir: &Path, args: &[&str]) -> String {
    succeeded(args, run_in(dir, args))
}

/// Runs `spectral-mesh ARGS`, asserts it failed, returns its standard error.
pub fn err(args: &[&str]) -> String {
    failed(args, run(args))
}

/// As [`err`], in `dir`.
pub fn err_in(dir: &Path, args: &[&str]) -> String {
    failed(args, run_in(dir, args))
}

/// The values of a field file (one per line; `#` lines skipped).
pub fn values(p: &Path) -> Vec<f64> {
    std::fs::read_to_string(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.trim().parse().unwrap())
        .collect()
}

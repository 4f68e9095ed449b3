//! What the command line's integration tests share: running the built binary (in the
//! current folder or in a given one), asserting success or failure, and reading a field
//! file written one value per line.
//!
//! The `*_with` forms take the command as one line of words with `{}` where a path goes:
//! `ok_with("heat sphere:res=2 -o {}", &[&out])`.
//!
//! Each test file includes it with `mod common;` and uses a part of it.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
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

/// The words of `line` (split at white space), each `{}` replaced by the next of `paths`
/// (a path stays one argument, spaces and all).
pub fn argv(line: &str, paths: &[&Path]) -> Vec<String> {
    let mut next = paths.iter();
    let words: Vec<String> = line
        .split_whitespace()
        .map(|w| match w {
            "{}" => next
                .next()
                .expect("a path for each {}")
                .to_str()
                .expect("a UTF-8 path")
                .to_owned(),
            w => w.to_owned(),
        })
        .collect();
    assert!(next.next().is_none(), "more paths than {{}} in {line:?}");
    words
}

fn with<T>(line: &str, paths: &[&Path], f: impl FnOnce(&[&str]) -> T) -> T {
    let words = argv(line, paths);
    f(&words.iter().map(String::as_str).collect::<Vec<_>>())
}

/// As [`run`], the arguments as in [`argv`].
pub fn run_with(line: &str, paths: &[&Path]) -> Output {
    with(line, paths, run)
}

/// As [`run_in`], the arguments as in [`argv`].
pub fn run_in_with(dir: &Path, line: &str, paths: &[&Path]) -> Output {
    with(line, paths, |a| run_in(dir, a))
}

/// As [`ok`], the arguments as in [`argv`].
pub fn ok_with(line: &str, paths: &[&Path]) -> String {
    with(line, paths, ok)
}

/// As [`ok_in`], the arguments as in [`argv`].
pub fn ok_in_with(dir: &Path, line: &str, paths: &[&Path]) -> String {
    with(line, paths, |a| ok_in(dir, a))
}

/// As [`err`], the arguments as in [`argv`].
pub fn err_with(line: &str, paths: &[&Path]) -> String {
    with(line, paths, err)
}

/// As [`err_in`], the arguments as in [`argv`].
pub fn err_in_with(dir: &Path, line: &str, paths: &[&Path]) -> String {
    with(line, paths, |a| err_in(dir, a))
}

/// A fresh temporary folder (removed when dropped) and the paths of `names` in it.
pub fn temp_paths<const N: usize>(names: [&str; N]) -> (tempfile::TempDir, [PathBuf; N]) {
    let dir = tempfile::tempdir().unwrap();
    let paths = names.map(|n| dir.path().join(n));
    (dir, paths)
}

/// Runs [`ok_with`] with the paths of `names` in a fresh temporary folder for its `{}`
/// (in that order); returns the folder (removed when dropped), the standard output and
/// the paths: `let (_dir, out, [txt]) = ok_writing("heat sphere:res=2 -o {}", ["h.txt"])`.
pub fn ok_writing<const N: usize>(
    line: &str,
    names: [&str; N],
) -> (tempfile::TempDir, String, [PathBuf; N]) {
    let (dir, paths) = temp_paths(names);
    let out = ok_with(line, &paths.each_ref().map(PathBuf::as_path));
    (dir, out, paths)
}

/// A fresh temporary folder (removed when dropped) holding one file, `name` with `text`.
pub fn folder_with(name: &str, text: impl AsRef<[u8]>) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write_in(dir.path(), name, text);
    dir
}

/// Writes `text` to the file `name` in `dir`.
pub fn write_in(dir: &Path, name: &str, text: impl AsRef<[u8]>) {
    std::fs::write(dir.join(name), text).unwrap();
}

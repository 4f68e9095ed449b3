//! What the `io_*` integration tests share: asserting that an error names the file, the
//! line and the problem.
#![allow(dead_code)]

use spectral_mesh::io::IoError;

/// Asserts `path:line: ...problem...`.
pub fn check(e: &IoError, prefix: &str, problem: &str) {
    let s = e.to_string();
    assert!(s.starts_with(prefix), "{s:?} should start with {prefix:?}");
    assert!(s.contains(problem), "{s:?} should mention {problem:?}");
}

/// Each `(source, prefix, problem)`: reading `source` with `read`, as the file named by
/// `prefix` up to its first `:`, fails with `prefix...problem...`.
pub fn check_all<S: AsRef<[u8]>>(read: fn(&[u8], &str) -> IoError, cases: &[(S, &str, &str)]) {
    for (src, prefix, problem) in cases {
        let name = prefix.split(':').next().unwrap_or_default();
        check(&read(src.as_ref(), name), prefix, problem);
    }
}

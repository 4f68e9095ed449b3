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

/// Each `(source, name, prefix, problem)`: reading `source` as file `name` with `read`
/// fails with `prefix...problem...`.
pub fn check_all<S: AsRef<[u8]>>(
    read: fn(&[u8], &str) -> IoError,
    cases: &[(S, &str, &str, &str)],
) {
    for (src, name, prefix, problem) in cases {
        check(&read(src.as_ref(), name), prefix, problem);
    }
}

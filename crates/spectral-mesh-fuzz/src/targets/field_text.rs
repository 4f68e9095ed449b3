//! The per-vertex field parser `io::read_field_text`: an error names `f.txt` and an existing
//! line; a result is finite, has the expected count when one is given, and writes
//! (`io::field_to_text`) as text that reads back bit for bit.

use spectral_mesh::io::{field_to_text, read_field_text};

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let lines = text.lines().count();
    let v = match read_field_text(text, "f.txt", None) {
        Ok(v) => v,
        Err(e) => {
            assert_eq!(e.path(), "f.txt");
            let line = e.line().expect("a parse error names its line");
            assert!(line >= 1 && line <= lines, "line {line} of {lines}: {e}");
            return;
        }
    };
    assert!(v.len() <= lines);
    assert!(v.iter().all(|x| x.is_finite()));
    let same = read_field_text(text, "f.txt", Some(v.len())).expect("the count matches");
    assert_eq!(same.len(), v.len());
    assert!(read_field_text(text, "f.txt", Some(v.len() + 1)).is_err());
    if !v.is_empty() {
        assert!(read_field_text(text, "f.txt", Some(v.len() - 1)).is_err());
    }
    let written = field_to_text(&v).expect("finite values write");
    let back = read_field_text(&written, "rt", Some(v.len())).expect("written text reads");
    let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&back), bits(&v), "round trip is not bit-exact");
}

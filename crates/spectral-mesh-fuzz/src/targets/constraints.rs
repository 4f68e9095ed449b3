//! The constraint-file parser `fields::harmonic::parse_constraints`, the one-argument form
//! `parse_constraint_arg` on every line, and the resolution of a parsed list against a
//! small mesh (range, unreferenced vertex, conflicting values).

use spectral_mesh::Mesh;
use spectral_mesh::fields::harmonic::{ConstraintSpec, parse_constraint_arg, parse_constraints};

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let lines = text.lines().count().max(1);
    match parse_constraints(&text, "c.txt") {
        Ok(list) => {
            assert!(list.len() <= lines);
            assert!(list.iter().all(|c| c.value.is_finite()));
            // A tetrahedron plus one vertex no triangle uses.
            let mesh = Mesh::new(
                vec![
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [5.0, 5.0, 5.0],
                ],
                vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
            )
            .expect("valid mesh");
            if let Ok(resolved) = ConstraintSpec::Explicit(list.clone()).resolve(&mesh) {
                assert!(resolved.len() <= list.len());
                assert!(resolved.iter().all(|c| c.vertex < 4));
            }
        }
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains("c.txt:"), "error does not name the file: {m}");
        }
    }
    for line in text.lines().take(64) {
        if let Ok(c) = parse_constraint_arg(line) {
            assert!(c.value.is_finite());
        }
    }
}

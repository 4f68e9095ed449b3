//! Built-in shape specs: `shapes::parse_shape`, then `shapes::build_limited` with a budget
//! of 20 000 vertices (a spec asking for more must be refused before the memory is
//! allocated, not built). The canonical text parses back to the same spec; a built
//! regular shape has exactly the vertex count of its formula and the Euler characteristic
//! of its family.

use spectral_mesh::mesh::validate::report;
use spectral_mesh::shapes::{ShapeError, build_limited, is_shape_spec, parse_shape};

const BUDGET: usize = 20_000;

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = is_shape_spec(text);
    let Ok(spec) = parse_shape(text) else {
        return;
    };
    let canonical = spec.to_string();
    let again = parse_shape(&canonical)
        .unwrap_or_else(|e| panic!("{text:?} printed as {canonical:?}, which fails: {e}"));
    assert_eq!(
        again, spec,
        "canonical text {canonical:?} parses to another spec"
    );
    match build_limited(&spec, BUDGET) {
        Ok(mesh) => {
            assert!(mesh.n_vertices() <= BUDGET);
            if let Some(n) = spec.vertex_count() {
                assert_eq!(mesh.n_vertices(), n, "{canonical}: vertex formula");
            }
            let r = report(&mesh);
            let want = spec.kind.expected_topology();
            assert_eq!(
                r.euler_characteristic, want.euler_characteristic,
                "{canonical}"
            );
            assert_eq!(r.boundary_loops, want.boundary_loops, "{canonical}");
            assert!(r.is_clean(), "{canonical}: {:?}", r.problems());
        }
        Err(ShapeError::TooLarge {
            vertices, limit, ..
        }) => {
            assert_eq!(limit, BUDGET);
            assert!(vertices > BUDGET);
        }
        Err(e) => panic!("{canonical}: a validated spec failed to build: {e}"),
    }
}

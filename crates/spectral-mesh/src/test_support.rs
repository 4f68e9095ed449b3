//! Support shared by the library's unit tests: small meshes and a deterministic number
//! stream (one definition each).

use crate::mesh::Mesh;

/// The tetrahedron on the origin and the three unit points, faces oriented outward.
pub(crate) fn tetra() -> Mesh {
    Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
    .unwrap()
}

/// Two triangles in z = 0 that share only vertex 0 (a bow tie: a non-manifold vertex).
pub(crate) fn bow_tie() -> Mesh {
    Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 3, 4]],
    )
    .unwrap()
}

/// The unit square in z = 0 as two triangles split along the diagonal 0-2.
pub(crate) fn unit_square() -> Mesh {
    Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap()
}

/// A deterministic stream of numbers in `[0, 1)` from `seed` (Knuth's MMIX linear
/// congruential generator, the high bits): reproducible test inputs, not statistics.
pub(crate) fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) as f64 / (1u64 << 31) as f64
    }
}

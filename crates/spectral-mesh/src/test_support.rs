//! Support shared by the library's unit tests: small meshes and a deterministic number
//! stream (one definition each).

use crate::mesh::Mesh;

/// The mesh of these positions and triangles (which must make a valid mesh).
fn mesh(positions: &[[f64; 3]], triangles: &[[usize; 3]]) -> Mesh {
    Mesh::new(positions.to_vec(), triangles.to_vec()).unwrap()
}

/// The tetrahedron on the origin and the three unit points, faces oriented outward.
pub(crate) fn tetra() -> Mesh {
    mesh(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
}

/// Two triangles in z = 0 that share only vertex 0 (a bow tie: a non-manifold vertex).
pub(crate) fn bow_tie() -> Mesh {
    mesh(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ],
        &[[0, 1, 2], [0, 3, 4]],
    )
}

/// The unit square in z = 0 as two triangles split along the diagonal 0-2.
pub(crate) fn unit_square() -> Mesh {
    mesh(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        &[[0, 1, 2], [0, 2, 3]],
    )
}

/// The regular octahedron with vertices `+-e_x, +-e_y, +-e_z` (indices `2 a` and `2 a + 1`
/// for the positive and negative end of axis `a`), one triangle per octant, every one
/// oriented outward.
pub(crate) fn octahedron() -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let mut positions = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut p = [0.0; 3];
            p[axis] = sign;
            positions.push(p);
        }
    }
    let mut triangles = Vec::new();
    for octant in 0..8 {
        let [x, y, z] = [0, 1, 2].map(|a| 2 * a + ((octant >> a) & 1));
        // An odd number of negative ends mirrors the octant: reverse the winding.
        let odd = (octant as u32).count_ones() % 2 == 1;
        triangles.push(if odd { [y, x, z] } else { [x, y, z] });
    }
    (positions, triangles)
}

/// An `m x m` grid of vertices (index `j * m + i`, at `position(i, j)`), each cell split
/// into two triangles along its diagonal from `(i, j)` to `(i + 1, j + 1)`, counter-clockwise
/// when `i` and `j` run along x and y.
pub(crate) fn grid(m: usize, mut position: impl FnMut(usize, usize) -> [f64; 3]) -> Mesh {
    let mut p = Vec::with_capacity(m * m);
    for j in 0..m {
        for i in 0..m {
            p.push(position(i, j));
        }
    }
    let mut t = Vec::new();
    for j in 0..m.saturating_sub(1) {
        for i in 0..m - 1 {
            let a = j * m + i;
            t.push([a, a + 1, a + m + 1]);
            t.push([a, a + m + 1, a + m]);
        }
    }
    Mesh::new(p, t).unwrap()
}

/// An `m x m` grid of points with unit spacing, jittered deterministically (each point
/// moved by `amplitude` times an integer in `-5..=5` along x and the opposite along y),
/// at height `z = height(x, y)`; point `(i, j)` has index `i * m + j`.
pub(crate) fn jittered_grid(
    m: usize,
    amplitude: f64,
    height: impl Fn(f64, f64) -> f64,
) -> Vec<[f64; 3]> {
    let mut pts = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m {
            let jit = amplitude * (((i * m + j) * 37 % 11) as f64 - 5.0);
            let (x, y) = (i as f64 + jit, j as f64 - jit);
            pts.push([x, y, height(x, y)]);
        }
    }
    pts
}

/// The states of Knuth's MMIX linear congruential generator after `seed`.
fn mmix(seed: u64) -> impl FnMut() -> u64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        state
    }
}

/// A deterministic stream of numbers in `[0, 1)` from `seed` (the high 31 bits of
/// [`mmix`]): reproducible test inputs, not statistics.
pub(crate) fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut next = mmix(seed);
    move || (next() >> 33) as f64 / (1u64 << 31) as f64
}

/// [`lcg`] with the full precision of an `f64` (the high 53 bits): for tests whose inputs
/// should use every bit of the mantissa.
pub(crate) fn lcg53(seed: u64) -> impl FnMut() -> f64 {
    let mut next = mmix(seed);
    move || (next() >> 11) as f64 / (1u64 << 53) as f64
}

/// Two fans of five triangles sharing vertex 0 (at the origin), one at z = 1 and one at
/// z = -1: vertex 0 is non-manifold (two link cycles). Positions and triangles, for tests
/// that add to them.
pub(crate) fn two_fans() -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let mut p = vec![[0.0, 0.0, 0.0]];
    let mut t = Vec::new();
    for (side, z) in [(0usize, 1.0), (1, -1.0)] {
        for i in 0..5 {
            let a = i as f64 * std::f64::consts::TAU / 5.0;
            p.push([a.cos(), a.sin(), z]);
        }
        for i in 0..5 {
            t.push([0, 1 + 5 * side + i, 1 + 5 * side + (i + 1) % 5]);
        }
    }
    (p, t)
}

//! Small mesh generators shared by the `fields_*` integration tests.
#![allow(dead_code, clippy::unwrap_used)]

use spectral_mesh::Mesh;

/// Deterministic pseudo-random numbers in [0, 1) (splitmix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A torus in the xy plane (major radius `big_r`, minor `r`) on a staggered grid of
/// `nu x nv` vertices (`nv` even), so that the triangles are close to equilateral.
pub fn torus(big_r: f64, r: f64, nu: usize, nv: usize) -> Mesh {
    assert!(nv.is_multiple_of(2));
    let mut p = Vec::with_capacity(nu * nv);
    for j in 0..nv {
        let v = std::f64::consts::TAU * j as f64 / nv as f64;
        for i in 0..nu {
            let shift = if j % 2 == 1 { 0.5 } else { 0.0 };
            let u = std::f64::consts::TAU * (i as f64 + shift) / nu as f64;
            let ring = big_r + r * v.cos(); // distance from the axis
            p.push([ring * u.cos(), ring * u.sin(), r * v.sin()]);
        }
    }
    let id = |j: usize, i: usize| (j % nv) * nu + (i % nu);
    let mut t = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            // The quad (a, b) on row j, (c, d) on row j + 1, split along the diagonal that
            // follows the stagger of the rows.
            let (a, b, c, d) = (id(j, i), id(j, i + 1), id(j + 1, i), id(j + 1, i + 1));
            let pair = if j % 2 == 0 {
                [[a, b, c], [c, b, d]]
            } else {
                [[a, b, d], [c, a, d]]
            };
            t.extend(pair);
        }
    }
    Mesh::new(p, t).unwrap()
}

/// The unit square on an `n x n` grid, interior vertices jittered by up to `jitter` of the
/// spacing, each quad split along a random diagonal. Returns the mesh and its boundary
/// vertices.
pub fn flat_square(n: usize, jitter: f64, seed: u64) -> (Mesh, Vec<usize>) {
    let mut rng = Rng(seed);
    let h = 1.0 / (n - 1) as f64;
    let mut p = Vec::new();
    let mut boundary = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let on_b = i == 0 || j == 0 || i == n - 1 || j == n - 1;
            let (mut x, mut y) = (i as f64 * h, j as f64 * h);
            if on_b {
                boundary.push(j * n + i);
            } else {
                x += (rng.next() - 0.5) * 2.0 * jitter * h;
                y += (rng.next() - 0.5) * 2.0 * jitter * h;
            }
            p.push([x, y, 0.0]);
        }
    }
    let mut t = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i + 1,
                (j + 1) * n + i,
            );
            if rng.next() < 0.5 {
                t.push([a, b, c]);
                t.push([a, c, d]);
            } else {
                t.push([a, b, d]);
                t.push([b, c, d]);
            }
        }
    }
    (Mesh::new(p, t).unwrap(), boundary)
}

/// An icosphere of radius 1 (`levels` subdivisions of the icosahedron), rotated by a
/// generic rotation so that no two vertices share a coordinate.
pub fn icosphere(levels: usize) -> Mesh {
    let sphere = spectral_mesh::shapes::build_str(&format!("sphere:res={levels}")).unwrap();
    // Rotate generically (about x, then y).
    let (a, b) = (0.3f64, 0.7f64);
    let p = sphere
        .positions()
        .iter()
        .map(|&q| {
            let q = [
                q[0],
                a.cos() * q[1] - a.sin() * q[2],
                a.sin() * q[1] + a.cos() * q[2],
            ];
            [
                b.cos() * q[0] + b.sin() * q[2],
                q[1],
                -b.sin() * q[0] + b.cos() * q[2],
            ]
        })
        .collect();
    Mesh::new(p, sphere.triangles().to_vec()).unwrap()
}

/// The disjoint union of two meshes (the second's indices shifted).
pub fn union(a: &Mesh, b: &Mesh, offset: [f64; 3]) -> Mesh {
    let n = a.n_vertices();
    let mut p = a.positions().to_vec();
    p.extend(
        b.positions()
            .iter()
            .map(|q| [q[0] + offset[0], q[1] + offset[1], q[2] + offset[2]]),
    );
    let mut t = a.triangles().to_vec();
    t.extend(b.triangles().iter().map(|tri| tri.map(|v| v + n)));
    Mesh::new(p, t).unwrap()
}

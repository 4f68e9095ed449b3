//! Shared helpers of the spectral tests: small meshes and dense linear algebra.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::{Eigenbasis, Laplacian, Mesh, Operators, SparseMatrix};

/// Deterministic pseudo-random numbers in [0, 1).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn index(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// Icosphere of radius 1 with `level` subdivisions (12, 42, 162, 642 vertices): the
/// library's built-in `sphere:res=level`.
pub fn icosphere(level: usize) -> Mesh {
    spectral_mesh::shapes::build_str(&format!("sphere:res={level}")).unwrap()
}

/// Torus grid with `nu x nv` vertices, radii `big` and `small`, optionally jittered.
pub fn torus(nu: usize, nv: usize, big: f64, small: f64, jitter: f64, seed: u64) -> Mesh {
    let mut rng = Lcg(seed);
    let mut pos = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let u = (i as f64 + jitter * (rng.next() - 0.5)) / nu as f64 * std::f64::consts::TAU;
            let v = (j as f64 + jitter * (rng.next() - 0.5)) / nv as f64 * std::f64::consts::TAU;
            pos.push([
                (big + small * v.cos()) * u.cos(),
                (big + small * v.cos()) * u.sin(),
                small * v.sin(),
            ]);
        }
    }
    let id = |i: usize, j: usize| (i % nu) * nv + (j % nv);
    let mut tris = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh::new(pos, tris).unwrap()
}

/// An irregular planar patch (bordered): a jittered `m x m` grid with alternating
/// diagonals and a slight bump so the mesh is not symmetric.
pub fn planar_patch(m: usize, seed: u64) -> Mesh {
    let mut rng = Lcg(seed);
    let mut pos = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let jx = if i > 0 && i + 1 < m {
                0.3 * (rng.next() - 0.5)
            } else {
                0.0
            };
            let jy = if j > 0 && j + 1 < m {
                0.3 * (rng.next() - 0.5)
            } else {
                0.0
            };
            let x = (i as f64 + jx) / (m - 1) as f64 * 1.3;
            let y = (j as f64 + jy) / (m - 1) as f64;
            pos.push([x, y, 0.1 * (x * x - 0.5 * y)]);
        }
    }
    let id = |i: usize, j: usize| i * m + j;
    let mut tris = Vec::new();
    for i in 0..m - 1 {
        for j in 0..m - 1 {
            if (i + j) % 2 == 0 {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                tris.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                tris.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    Mesh::new(pos, tris).unwrap()
}

pub fn fem(mesh: &Mesh) -> Operators {
    Operators::new(mesh, Laplacian::Fem)
}

/// The FEM operators of `mesh` and their full dense eigenbasis (all `n` pairs).
pub fn fem_full_basis(mesh: &Mesh) -> (Operators, Eigenbasis) {
    let ops = fem(mesh);
    let basis = Eigenbasis::dense(&ops, ops.n()).unwrap();
    (ops, basis)
}

/// Dense row-major copy.
pub fn dense(a: &SparseMatrix) -> Vec<Vec<f64>> {
    a.to_dense()
}

/// Inverse of a symmetric positive definite matrix by Cholesky (row-major, small n);
/// `None` when not positive definite.
pub fn cholesky(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// Inverse of an SPD matrix through its Cholesky factor.
pub fn spd_inverse(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let l = cholesky(a).expect("SPD");
    let mut inv = vec![vec![0.0; n]; n];
    for c in 0..n {
        // Solve L y = e_c, then L^T x = y.
        let mut y = vec![0.0; n];
        for i in 0..n {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for k in 0..i {
                s -= l[i][k] * y[k];
            }
            y[i] = s / l[i][i];
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            let mut s = y[i];
            for k in i + 1..n {
                s -= l[k][i] * x[k];
            }
            x[i] = s / l[i][i];
        }
        for i in 0..n {
            inv[i][c] = x[i];
        }
    }
    inv
}

pub fn matmul(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let (n, m, p) = (a.len(), b.len(), b[0].len());
    let mut c = vec![vec![0.0; p]; n];
    for i in 0..n {
        for k in 0..m {
            let aik = a[i][k];
            if aik != 0.0 {
                for j in 0..p {
                    c[i][j] += aik * b[k][j];
                }
            }
        }
    }
    c
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

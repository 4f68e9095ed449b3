//! Shapes with a closed-form surface: torus, spheres, disk, cylinder.

use std::f64::consts::PI;

use super::refine::{Refiner, Surface};
use crate::mesh::{cross, dot, norm, normalize, sub};

/// Raw arrays of a generated mesh.
pub(crate) type Arrays = (Vec<[f64; 3]>, Vec<[usize; 3]>);

/// Triangulates a periodic-in-`i` grid of `ni x nj` vertices (index `j * ni + i`), with
/// `nj_cells` rows of cells (rows wrap when `nj_cells == nj`). Cell corners
/// `(i,j),(i+1,j),(i+1,j+1),(i,j+1)` are taken counter-clockwise.
fn grid_triangles(ni: usize, nj: usize, nj_cells: usize) -> Vec<[usize; 3]> {
    let mut t = Vec::with_capacity(2 * ni * nj_cells);
    for j in 0..nj_cells {
        let j1 = (j + 1) % nj;
        for i in 0..ni {
            let i1 = (i + 1) % ni;
            let quad = [j * ni + i, j * ni + i1, j1 * ni + i1, j1 * ni + i];
            push_quad(&mut t, quad, (i + j) % 2 == 0);
        }
    }
    t
}

/// Splits the cell with counter-clockwise corners `[a, b, c, d]` into two triangles along
/// `a-c` when `even`, else along `b-d`. Alternating `even` in a checkerboard leaves the
/// mesh no preferred direction.
fn push_quad(t: &mut Vec<[usize; 3]>, [a, b, c, d]: [usize; 4], even: bool) {
    if even {
        t.push([a, b, c]);
        t.push([a, c, d]);
    } else {
        t.push([a, b, d]);
        t.push([b, c, d]);
    }
}

/// Ring torus: `nu = 2k` steps around the axis, `nv = k` around the tube, `k = 7 * 2^res`.
pub(crate) fn torus(res: u32, big_r: f64, small_r: f64) -> Arrays {
    let k = 7usize << res;
    let (nu, nv) = (2 * k, k);
    let mut p = Vec::with_capacity(nu * nv);
    for j in 0..nv {
        let v = 2.0 * PI * j as f64 / nv as f64;
        for i in 0..nu {
            let u = 2.0 * PI * i as f64 / nu as f64;
            let rr = big_r + small_r * v.cos();
            p.push([rr * u.cos(), rr * u.sin(), small_r * v.sin()]);
        }
    }
    (p, grid_triangles(nu, nv, nv))
}

/// Open tube: `2k` vertices per ring, `k + 1` rings, `k = 7 * 2^res`.
pub(crate) fn cylinder(res: u32, radius: f64, height: f64) -> Arrays {
    let k = 7usize << res;
    let (ni, nj) = (2 * k, k + 1);
    let mut p = Vec::with_capacity(ni * nj);
    for j in 0..nj {
        let z = -0.5 * height + height * j as f64 / k as f64;
        for i in 0..ni {
            let a = 2.0 * PI * i as f64 / ni as f64;
            p.push([radius * a.cos(), radius * a.sin(), z]);
        }
    }
    (p, grid_triangles(ni, nj, k))
}

/// Latitude/longitude sphere: `k` latitude bands, `2k` meridians, poles at `(0,0,±1)`.
pub(crate) fn uv_sphere(res: u32) -> Arrays {
    let k = 7usize << res;
    let nl = 2 * k;
    let mut p = Vec::with_capacity(nl * (k - 1) + 2);
    p.push([0.0, 0.0, 1.0]);
    for i in 1..k {
        let th = PI * i as f64 / k as f64;
        for j in 0..nl {
            let ph = 2.0 * PI * j as f64 / nl as f64;
            p.push(normalize([
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ]));
        }
    }
    let south = p.len();
    p.push([0.0, 0.0, -1.0]);
    let ring = |i: usize, j: usize| 1 + (i - 1) * nl + j % nl;
    let mut t = Vec::with_capacity(2 * nl * (k - 1));
    for j in 0..nl {
        t.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..k - 1 {
        for j in 0..nl {
            let quad = [
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            ];
            push_quad(&mut t, quad, (i + j) % 2 == 0);
        }
    }
    for j in 0..nl {
        t.push([ring(k - 1, j), south, ring(k - 1, j + 1)]);
    }
    (p, t)
}

/// Unit disk from `k = 6 * 2^res` hexagonal rings (ring `i` has `6i` vertices at radius `i/k`).
pub(crate) fn disk(res: u32) -> Arrays {
    let k = 6usize << res;
    let mut p = Vec::with_capacity(3 * k * (k + 1) + 1);
    p.push([0.0, 0.0, 0.0]);
    for i in 1..=k {
        let r = i as f64 / k as f64;
        for q in 0..6 * i {
            let a = PI / 3.0 * q as f64 / i as f64;
            let (x, y) = if i == k {
                // Exactly on the unit circle.
                let (s, c) = a.sin_cos();
                let l = s.hypot(c);
                (c / l, s / l)
            } else {
                (r * a.cos(), r * a.sin())
            };
            p.push([x, y, 0.0]);
        }
    }
    // Index of the q-th vertex (wrapping) of ring i.
    let vid = |i: usize, q: usize| {
        if i == 0 {
            0
        } else {
            1 + 3 * i * (i - 1) + q % (6 * i)
        }
    };
    let mut t = Vec::with_capacity(6 * k * k);
    for i in 1..=k {
        for s in 0..6 {
            for j in 0..i {
                let o0 = vid(i, s * i + j);
                let o1 = vid(i, s * i + j + 1);
                let i0 = vid(i - 1, s * (i - 1) + j);
                t.push([i0, o0, o1]);
                if j + 1 < i {
                    let i1 = vid(i - 1, s * (i - 1) + j + 1);
                    t.push([i0, o1, i1]);
                }
            }
        }
    }
    (p, t)
}

/// Icosphere: the regular icosahedron, split 1-to-4 `res` times, vertices on the unit sphere.
pub(crate) fn icosphere(res: u32) -> Arrays {
    let phi = 0.5 * (1.0 + 5f64.sqrt());
    let mut p = Vec::with_capacity(12);
    for &a in &[-1.0, 1.0] {
        for &b in &[-phi, phi] {
            p.push([0.0, a, b]);
            p.push([a, b, 0.0]);
            p.push([b, 0.0, a]);
        }
    }
    // Faces: the 20 triples of mutually adjacent vertices (edge length 2), outward.
    let mut t = Vec::with_capacity(20);
    let adj = |i: usize, j: usize| (norm(sub(p[i], p[j])) - 2.0).abs() < 1e-9;
    for a in 0..12 {
        for b in a + 1..12 {
            for c in b + 1..12 {
                if adj(a, b) && adj(b, c) && adj(a, c) {
                    let n = cross(sub(p[b], p[a]), sub(p[c], p[a]));
                    if dot(n, p[a]) > 0.0 {
                        t.push([a, b, c]);
                    } else {
                        t.push([a, c, b]);
                    }
                }
            }
        }
    }
    let p = p.into_iter().map(normalize).collect();
    let mut r = Refiner::new(p, t, Surface::UnitSphere, None);
    for _ in 0..res {
        r.split_all();
    }
    (r.positions, r.triangles)
}

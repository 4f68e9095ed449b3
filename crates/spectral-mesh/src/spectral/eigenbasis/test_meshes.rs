//! Small meshes built in code for the tests.
use crate::mesh::Mesh;

/// An icosphere of radius `r` with `level` subdivisions (12, 42, 162, 642, ... vertices).
pub fn icosphere(level: usize, r: f64) -> Mesh {
    crate::shapes::build_str(&format!("sphere:res={level}"))
        .unwrap()
        .map_positions(|p| [p[0] * r, p[1] * r, p[2] * r])
        .unwrap()
}

/// A disk of radius 1 triangulated from a polar-ish grid: `rings` rings of `6 * ring`
/// vertices around the centre (a bordered surface).
pub fn disk(rings: usize) -> Mesh {
    let mut p = vec![[0.0, 0.0, 0.0]];
    let mut start = vec![0usize];
    for r in 1..=rings {
        start.push(p.len());
        let m = 6 * r;
        for j in 0..m {
            let a = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
            let rad = r as f64 / rings as f64;
            p.push([rad * a.cos(), rad * a.sin(), 0.0]);
        }
    }
    let mut f = Vec::new();
    // Ring 1 to the centre.
    for j in 0..6 {
        f.push([0, 1 + j, 1 + (j + 1) % 6]);
    }
    for r in 1..rings {
        let (ia, ib) = (start[r], start[r + 1]);
        let (ma, mb) = (6 * r, 6 * (r + 1));
        // Merge-walk the two rings by angle.
        let (mut a, mut b) = (0usize, 0usize);
        while a < ma || b < mb {
            let ang_a = (a + 1) as f64 / ma as f64;
            let ang_b = (b + 1) as f64 / mb as f64;
            if b < mb && (a >= ma || ang_b <= ang_a) {
                f.push([ia + a % ma, ib + b, ib + (b + 1) % mb]);
                b += 1;
            } else {
                f.push([ia + a, ib + b % mb, ia + (a + 1) % ma]);
                a += 1;
            }
        }
    }
    Mesh::new(p, f).unwrap()
}

/// Disjoint union of meshes (vertex indices shifted), with the given offsets.
pub fn union(parts: &[(Mesh, [f64; 3])]) -> Mesh {
    let mut p = Vec::new();
    let mut f = Vec::new();
    for (m, off) in parts {
        let base = p.len();
        p.extend(
            m.positions()
                .iter()
                .map(|v| [v[0] + off[0], v[1] + off[1], v[2] + off[2]]),
        );
        f.extend(
            m.triangles()
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    Mesh::new(p, f).unwrap()
}

//! Red-green refinement of a triangle mesh, with new vertices placed on the exact surface
//! (or on a smooth normal-based interpolant when no exact surface is known).
//!
//! Used for uniform subdivision (every triangle marked) and for the irregular variants
//! (nested regions marked). Red: 1-to-4 split, children similar to the parent. Green:
//! bisection from the midpoint of the one split edge to the opposite corner. The closure
//! never bisects a triangle that was already produced by a bisection (it red-splits it
//! instead), so angles degrade at most once.

use std::collections::{HashMap, HashSet};

use crate::mesh::{add, dot, normalize, scale, sub};

/// Where new edge midpoints go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Surface {
    /// Unit sphere about the origin: midpoints are normalised.
    UnitSphere,
    /// Ring torus about the z axis: midpoints go to the closest point on the torus.
    Torus {
        /// Major radius.
        big_r: f64,
        /// Minor radius.
        small_r: f64,
    },
    /// Tube about the z axis: midpoints are pushed radially to the radius.
    Cylinder {
        /// Radius.
        radius: f64,
    },
    /// Unit disk in z = 0: interior midpoints stay, boundary midpoints go to the circle.
    UnitDisk,
    /// No exact surface: curved-edge (PN-triangle) midpoints from vertex normals.
    Smooth,
}

impl Surface {
    fn midpoint(
        self,
        a: [f64; 3],
        b: [f64; 3],
        normals: Option<([f64; 3], [f64; 3])>,
        boundary: bool,
    ) -> [f64; 3] {
        let m = scale(add(a, b), 0.5);
        match self {
            Surface::UnitSphere => normalize(m),
            Surface::Torus { big_r, small_r } => {
                let rho = m[0].hypot(m[1]);
                let c = if rho > 0.0 {
                    [big_r * m[0] / rho, big_r * m[1] / rho, 0.0]
                } else {
                    [big_r, 0.0, 0.0]
                };
                add(c, scale(normalize(sub(m, c)), small_r))
            }
            Surface::Cylinder { radius } => {
                let rho = m[0].hypot(m[1]);
                if rho > 0.0 {
                    [radius * m[0] / rho, radius * m[1] / rho, m[2]]
                } else {
                    m
                }
            }
            Surface::UnitDisk => {
                let rho = m[0].hypot(m[1]);
                if boundary && rho > 0.0 {
                    [m[0] / rho, m[1] / rho, 0.0]
                } else {
                    [m[0], m[1], 0.0]
                }
            }
            Surface::Smooth => match normals {
                Some((na, nb)) => {
                    // Midpoint of the cubic Bezier edge of a PN triangle.
                    let w_ab = dot(sub(b, a), na);
                    let w_ba = dot(sub(a, b), nb);
                    sub(m, scale(add(scale(na, w_ab), scale(nb, w_ba)), 0.125))
                }
                None => m,
            },
        }
    }
}

/// A triangle mesh being refined.
#[derive(Debug, Clone)]
pub(crate) struct Refiner {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles (orientation preserved by refinement).
    pub triangles: Vec<[usize; 3]>,
    /// Unit vertex normals, kept only for [`Surface::Smooth`].
    normals: Option<Vec<[f64; 3]>>,
    /// Triangles produced by a bisection (or red children of one): never bisected again.
    green: Vec<bool>,
    surface: Surface,
}

fn key(a: usize, b: usize) -> (usize, usize) {
    if a < b { (a, b) } else { (b, a) }
}

impl Refiner {
    pub fn new(
        positions: Vec<[f64; 3]>,
        triangles: Vec<[usize; 3]>,
        surface: Surface,
        normals: Option<Vec<[f64; 3]>>,
    ) -> Self {
        let m = triangles.len();
        Self {
            positions,
            triangles,
            normals,
            green: vec![false; m],
            surface,
        }
    }

    /// Splits every triangle 1-to-4.
    pub fn split_all(&mut self) {
        let marked = vec![true; self.triangles.len()];
        self.refine(marked);
    }

    /// Red-splits the marked triangles (plus the closure) and bisects their neighbours.
    pub fn refine(&mut self, mut marked: Vec<bool>) {
        let tris = &self.triangles;
        let m = tris.len();
        let mut split: HashSet<(usize, usize)> = HashSet::new();
        for (t, tri) in tris.iter().enumerate() {
            if marked[t] {
                for k in 0..3 {
                    split.insert(key(tri[k], tri[(k + 1) % 3]));
                }
            }
        }
        // Closure: two split edges, or a split edge on a green triangle, makes it red.
        loop {
            let mut changed = false;
            for t in 0..m {
                if marked[t] {
                    continue;
                }
                let tri = tris[t];
                let c = (0..3)
                    .filter(|&k| split.contains(&key(tri[k], tri[(k + 1) % 3])))
                    .count();
                if c >= 2 || (c == 1 && self.green[t]) {
                    marked[t] = true;
                    changed = true;
                    for k in 0..3 {
                        split.insert(key(tri[k], tri[(k + 1) % 3]));
                    }
                }
            }
            if !changed {
                break;
            }
        }
        // Boundary edges (one triangle) matter only for the disk.
        let boundary: HashSet<(usize, usize)> = if self.surface == Surface::UnitDisk {
            let mut count: HashMap<(usize, usize), u32> = HashMap::new();
            for tri in tris {
                for k in 0..3 {
                    *count.entry(key(tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
                }
            }
            count
                .into_iter()
                .filter(|&(_, c)| c == 1)
                .map(|(e, _)| e)
                .collect()
        } else {
            HashSet::new()
        };

        let mut mid: HashMap<(usize, usize), usize> = HashMap::with_capacity(split.len());
        let positions = &mut self.positions;
        let normals = &mut self.normals;
        let surface = self.surface;
        let mut midpoint = |a: usize, b: usize| -> usize {
            let k = key(a, b);
            if let Some(&v) = mid.get(&k) {
                return v;
            }
            let (pa, pb) = (positions[k.0], positions[k.1]);
            let nrm = normals.as_ref().map(|n| (n[k.0], n[k.1]));
            let p = surface.midpoint(pa, pb, nrm, boundary.contains(&k));
            let v = positions.len();
            positions.push(p);
            if let Some(n) = normals.as_mut() {
                let nm = normalize(add(n[k.0], n[k.1]));
                n.push(nm);
            }
            mid.insert(k, v);
            v
        };

        let mut out = Vec::with_capacity(m + 3 * split.len());
        let mut out_green = Vec::with_capacity(out.capacity());
        for (t, &red) in marked.iter().enumerate() {
            let [a, b, c] = self.triangles[t];
            let g = self.green[t];
            if red {
                let ab = midpoint(a, b);
                let bc = midpoint(b, c);
                let ca = midpoint(c, a);
                out.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
                out_green.extend_from_slice(&[g; 4]);
                continue;
            }
            let tri = [a, b, c];
            match (0..3).find(|&k| split.contains(&key(tri[k], tri[(k + 1) % 3]))) {
                Some(k) => {
                    let (p, q, r) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                    let pq = midpoint(p, q);
                    out.extend_from_slice(&[[p, pq, r], [pq, q, r]]);
                    out_green.extend_from_slice(&[true, true]);
                }
                None => {
                    out.push(tri);
                    out_green.push(g);
                }
            }
        }
        self.triangles = out;
        self.green = out_green;
    }
}

//! The triangle mesh: positions and triangles, plus derived geometry.
//!
//! A [`Mesh`] is the one input type of every operation in this crate. It holds
//! `n` vertex positions and `m` triangles given as vertex-index triples; connectivity
//! queries live in [`topology`], checks and repairs in [`validate`]. A [`PointCloud`]
//! (positions and optional normals, no triangles) is the other input type.

pub mod point_cloud;
pub mod topology;
pub mod validate;

pub use point_cloud::{PointCloud, PointCloudError};

use thiserror::Error;

/// Errors raised when a mesh is built from raw arrays.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no vertices or no triangles.
    #[error("the mesh is empty ({vertices} vertices, {triangles} triangles)")]
    Empty {
        /// Number of vertices.
        vertices: usize,
        /// Number of triangles.
        triangles: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// Offending vertex index.
        index: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} repeats vertex {index}")]
    RepeatedVertex {
        /// Triangle index.
        triangle: usize,
        /// Repeated vertex.
        index: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// Vertex index.
        vertex: usize,
    },
}

/// A triangle mesh: `n` positions in R^3 and `m` triangles (vertex-index triples,
/// counter-clockwise seen from outside when the surface is oriented).
///
/// Construction through [`Mesh::new`] guarantees: at least one vertex and one triangle,
/// finite coordinates, indices in range and three distinct vertices per triangle.
/// Everything else (unreferenced vertices, duplicate or zero-area triangles, non-manifold
/// edges, several components, boundaries) is legal and reported by [`validate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[usize; 3]>,
}

impl Mesh {
    /// Builds a mesh, checking the invariants listed on [`Mesh`].
    pub fn new(positions: Vec<[f64; 3]>, triangles: Vec<[usize; 3]>) -> Result<Self, MeshError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty {
                vertices: positions.len(),
                triangles: triangles.len(),
            });
        }
        if let Some(v) = positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex: v });
        }
        let n = positions.len();
        for (t, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i >= n {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: t,
                        index: i,
                        vertices: n,
                    });
                }
            }
            if tri[0] == tri[1] || tri[0] == tri[2] {
                return Err(MeshError::RepeatedVertex {
                    triangle: t,
                    index: tri[0],
                });
            }
            if tri[1] == tri[2] {
                return Err(MeshError::RepeatedVertex {
                    triangle: t,
                    index: tri[1],
                });
            }
        }
        Ok(Self {
            positions,
            triangles,
        })
    }

    /// Vertex positions, `n` entries.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Triangles as vertex-index triples, `m` entries.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The one content hash of a mesh, which every face uses to name it: blake3 (64
    /// lowercase hex digits) of the positions as little-endian `f64` (x, y, z per vertex,
    /// in order) followed by the triangle indices as little-endian `u64`. Two meshes have
    /// the same hash exactly when they have the same coordinates bit for bit (`0.0` and
    /// `-0.0` differ) and the same triangles in the same order (up to blake3 collisions).
    /// Experiment files record it (`mesh_hash`) and replays check it; the web app's mesh
    /// ids are its first 16 digits; saved and cached bases are keyed by it.
    pub fn content_hash(&self) -> String {
        let mut h = blake3::Hasher::new();
        for p in &self.positions {
            for c in p {
                h.update(&c.to_le_bytes());
            }
        }
        for t in &self.triangles {
            for &v in t {
                h.update(&(v as u64).to_le_bytes());
            }
        }
        h.finalize().to_hex().to_string()
    }

    /// The vertex of largest x (lowest index on ties): the default source and anchor of
    /// every spectral field (0 for an empty mesh).
    pub fn vertex_of_largest_x(&self) -> usize {
        let p = &self.positions;
        (0..p.len()).fold(0, |best, i| if p[i][0] > p[best][0] { i } else { best })
    }

    /// Number of vertices `n`.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles `m`.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Consumes the mesh and returns its arrays.
    pub fn into_parts(self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (self.positions, self.triangles)
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [self.positions[a], self.positions[b], self.positions[c]]
    }

    /// Area of every triangle (`m` entries), from the cross product of two edges.
    pub fn triangle_areas(&self) -> Vec<f64> {
        (0..self.n_triangles())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * norm(cross(sub(b, a), sub(c, a)))
            })
            .collect()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.triangle_areas().iter().sum()
    }

    /// Axis-aligned bounding box as `(min, max)`.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        bounding_box(&self.positions)
    }

    /// Length of the bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        norm(sub(hi, lo))
    }

    /// Mean length of the edges of all triangles (each interior edge counted twice).
    pub fn mean_edge_length(&self) -> f64 {
        let mut s = 0.0;
        for t in 0..self.n_triangles() {
            let [a, b, c] = self.corners(t);
            s += norm(sub(b, a)) + norm(sub(c, b)) + norm(sub(a, c));
        }
        s / (3.0 * self.n_triangles() as f64)
    }

    /// Unit normal of every triangle (zero for a zero-area triangle).
    pub fn triangle_normals(&self) -> Vec<[f64; 3]> {
        (0..self.n_triangles())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                normalize(cross(sub(b, a), sub(c, a)))
            })
            .collect()
    }

    /// Area-weighted unit vertex normals (zero at a vertex with no area around it).
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        let mut nrm = vec![[0.0; 3]; self.n_vertices()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let [a, b, c] = self.corners(t);
            let w = cross(sub(b, a), sub(c, a));
            for &v in tri {
                for d in 0..3 {
                    nrm[v][d] += w[d];
                }
            }
        }
        nrm.into_iter().map(normalize).collect()
    }

    /// Returns a copy with every position transformed by `f`.
    pub fn map_positions(&self, f: impl Fn([f64; 3]) -> [f64; 3]) -> Result<Self, MeshError> {
        Self::new(
            self.positions.iter().map(|&p| f(p)).collect(),
            self.triangles.clone(),
        )
    }

    /// Returns a copy uniformly scaled about the origin so that the total area is 1
    /// (the unit-area normalisation of `docs/MATH.md`), with the factor applied.
    pub fn normalized_to_unit_area(&self) -> (Self, f64) {
        let a = self.area();
        let s = if a > 0.0 { 1.0 / a.sqrt() } else { 1.0 };
        let m = Self {
            positions: self
                .positions
                .iter()
                .map(|p| [p[0] * s, p[1] * s, p[2] * s])
                .collect(),
            triangles: self.triangles.clone(),
        };
        (m, s)
    }
}

/// Axis-aligned bounding box `(min, max)` of points (infinite, inverted for none).
pub fn bounding_box(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// The vertices of a triangle in ascending order (the same for every orientation and
/// rotation of it).
pub(crate) fn sorted_triangle(t: [usize; 3]) -> [usize; 3] {
    let mut s = t;
    s.sort_unstable();
    s
}

/// The sides of every triangle as `(low, high)` vertex pairs, sorted: an edge appears once
/// per triangle that has it (consecutive equal pairs), so `dedup` gives the distinct edges.
pub(crate) fn sorted_edges(triangles: &[[usize; 3]]) -> Vec<(usize, usize)> {
    use rayon::slice::ParallelSliceMut;
    let mut e: Vec<(usize, usize)> = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            e.push((a.min(b), a.max(b)));
        }
    }
    e.par_sort_unstable();
    e
}

/// The coordinates of the points `positions[i]`, `i` in `indices`, relative to `origin` in
/// the frame `(e1, e2)` of a plane (the dot products with `e1` and `e2`).
pub(crate) fn plane_coordinates(
    positions: &[[f64; 3]],
    indices: &[usize],
    origin: [f64; 3],
    [e1, e2]: [[f64; 3]; 2],
) -> Vec<[f64; 2]> {
    indices
        .iter()
        .map(|&i| {
            let d = sub(positions[i], origin);
            [dot(d, e1), dot(d, e2)]
        })
        .collect()
}

/// `a - b`.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + b`.
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `s * a`.
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean norm.
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or zero for the zero vector.
pub fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = norm(a);
    if l > 0.0 { scale(a, 1.0 / l) } else { [0.0; 3] }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Mesh {
        Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap()
    }

    #[test]
    fn the_content_hash_is_the_blake3_of_the_documented_bytes_and_sees_every_change() {
        let m = tri();
        let mut bytes = Vec::new();
        for p in m.positions() {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in m.triangles() {
            for &v in t {
                bytes.extend_from_slice(&(v as u64).to_le_bytes());
            }
        }
        assert_eq!(m.content_hash(), blake3::hash(&bytes).to_hex().to_string());
        assert_eq!(m.content_hash().len(), 64);
        let moved = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1e-300]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_ne!(m.content_hash(), moved.content_hash());
        let flipped = Mesh::new(m.positions().to_vec(), vec![[0, 2, 1]]).unwrap();
        assert_ne!(m.content_hash(), flipped.content_hash());
    }
}

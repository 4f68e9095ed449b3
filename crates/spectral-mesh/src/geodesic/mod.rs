//! Geodesic distance by the heat method (Crane, Weischedel and Wardetzky, "Geodesics in
//! Heat", 2013, and "The Heat Method for Distance Computation", 2017).
//!
//! A [`GeodesicSolver`] factors its matrices once and then answers any number of source
//! sets; the formulas, signs and the boundary rule are in `docs/MATH.md` ("Geodesic distance"):
//!
//! 1. **Heat.** `(B + t S) u = delta`, `t = m h^2` with `h` the mean edge length and `m`
//!    [`GeodesicParams::time_factor`] (1 by default). `delta` is 1 at a source vertex (the
//!    barycentric weights at the corners of a face point), not divided by the mass.
//!    On a mesh with boundary the [`Convention::Crane`] rule averages the Neumann solution
//!    and the Dirichlet one (`u = 0` on the boundary): `u = (u_N + u_D) / 2`.
//! 2. **Direction.** In every triangle, `X = grad u / |grad u|` (zero where `grad u = 0`).
//!    This is minus the paper's `X`; the sign is taken back in step 3.
//! 3. **Poisson.** `S phi = div X` with the integrated divergence
//!    `(div X)_i = sum over triangles, over the two edges i -> j of the triangle, of
//!    w_ij (p_j - p_i) . X`, `w_ij` the half cotangent of the angle opposite the edge (the
//!    weights of S, so that `div grad u = -S u` exactly).
//! 4. **Shift.** `phi` is shifted so that its weighted mean over the sources is 0 (for a
//!    face point, the value expected at each corner is the straight distance inside the
//!    face). Each connected component is shifted on its own; a component with no source gets
//!    `f64::INFINITY` (the heat never reaches it).
//!
//! Which triangles carry the gradient: the input triangles for the cotangent Laplacians;
//! for [`Laplacian::Robust`] the intrinsic Delaunay triangulation of the tufted cover
//! ([`crate::operators::robust`]), so that gradient, divergence and S come from the same
//! triangles (this is what geometry-central's heat-method solver does with its robust
//! Laplacian).

mod sampling;
mod triangles;

use rayon::prelude::*;

use crate::linalg::{CholeskyError, SparseCholesky, SparseMatrix};
use crate::mesh::Mesh;
use crate::mesh::topology::UnionFind;
use crate::operators::robust::{Gluing, MollifyMean, RobustError, RobustParams, robust_with_faces};
use crate::operators::{Laplacian, Operators};
use triangles::FaceFrames;

pub use sampling::farthest_point_sampling;

/// Columns solved together in a block (bounds the memory of many-source calls to
/// `3 n BLOCK` values).
const BLOCK: usize = 32;

/// Which published variant of the heat method.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Convention {
    /// Crane, Weischedel and Wardetzky: on a mesh with boundary the heat is the average of
    /// the Neumann and the Dirichlet solutions; the Poisson problem is solved exactly (one
    /// vertex per component held at 0, then the shift); `h` is the mean length of the input
    /// edges.
    #[default]
    Crane,
    /// geometry-central's `HeatMethodDistanceSolver` (potpourri3d's
    /// `MeshHeatMethodDistanceSolver`): Neumann heat only; the Poisson matrix is its
    /// Laplacian plus `1e-6 I` (with the robust Laplacian, its Laplacian is that of the
    /// whole cover, `2 S`, so ours gets `0.5e-6 I`); with the robust Laplacian, `h` is the
    /// mean edge length of the intrinsic Delaunay cover and the cover is mollified from the
    /// cover's mean edge length. For comparisons with it.
    Potpourri3d,
}

impl Convention {
    /// The name users type (`crane`, `potpourri3d`).
    pub fn name(self) -> &'static str {
        match self {
            Convention::Crane => "crane",
            Convention::Potpourri3d => "potpourri3d",
        }
    }
}

impl std::fmt::Display for Convention {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Convention {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "crane" | "average" => Ok(Convention::Crane),
            "potpourri3d" | "geometry-central" | "neumann" => Ok(Convention::Potpourri3d),
            _ => Err(format!(
                "unknown heat-method convention '{s}': expected crane or potpourri3d"
            )),
        }
    }
}

/// Parameters of the heat method. `Default`: `m = 1`, [`Convention::Crane`], the robust
/// Laplacian's default parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeodesicParams {
    /// `m` in `t = m h^2` (potpourri3d's `t_coef`). Finite and `> 0`.
    pub time_factor: f64,
    /// Boundary rule and Poisson solve.
    pub convention: Convention,
    /// Parameters of the robust Laplacian (used with [`Laplacian::Robust`] only).
    pub robust: RobustParams,
}

impl Default for GeodesicParams {
    fn default() -> Self {
        Self {
            time_factor: crate::analysis::request::DEFAULT_GEODESIC_TIME_FACTOR,
            convention: Convention::Crane,
            robust: RobustParams::default(),
        }
    }
}

/// A source of distance: a vertex, or a point inside a triangle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// A vertex index.
    Vertex(usize),
    /// A point of triangle `face` with barycentric coordinates `bary` (for the triangle's
    /// vertices in order; `>= 0`, summing to 1; they are renormalized).
    FacePoint {
        /// Triangle index.
        face: usize,
        /// Barycentric coordinates.
        bary: [f64; 3],
    },
}

impl From<usize> for Source {
    fn from(v: usize) -> Self {
        Source::Vertex(v)
    }
}

/// Errors of the heat method, each saying what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeodesicError {
    /// A parameter is out of its range.
    #[error("{0}")]
    BadParameter(String),
    /// No source was given.
    #[error("no source given: name at least one vertex or face point")]
    NoSources,
    /// A source vertex does not exist.
    #[error("source vertex {vertex} is out of range: the mesh has {n} vertices")]
    VertexOutOfRange {
        /// The index given.
        vertex: usize,
        /// Vertices.
        n: usize,
    },
    /// A source vertex belongs to no triangle.
    #[error(
        "source vertex {vertex} belongs to no triangle: no distance along the surface starts there"
    )]
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A source triangle does not exist.
    #[error("source triangle {face} is out of range: the mesh has {m} triangles")]
    FaceOutOfRange {
        /// The index given.
        face: usize,
        /// Triangles.
        m: usize,
    },
    /// Barycentric coordinates that are negative, not finite or sum to 0.
    #[error(
        "the barycentric coordinates {bary:?} of the source in triangle {face} must be finite, >= 0 and sum to 1"
    )]
    BadBarycentric {
        /// Triangle.
        face: usize,
        /// The coordinates given.
        bary: [f64; 3],
    },
    /// The chosen Laplacian has no gradient to go with it.
    #[error(
        "the heat method needs a cotangent Laplacian (voronoi-cot, fem, mixed-voronoi, cot or robust); '{0}' has no matching gradient"
    )]
    NotGeometric(Laplacian),
    /// A factorization failed.
    #[error("the heat method could not factor its matrix: {0}")]
    Factorization(#[from] CholeskyError),
    /// The robust Laplacian refused its parameters.
    #[error(transparent)]
    Robust(#[from] RobustError),
}

/// The heat method on one mesh: factored once, then any number of sources
/// (see the module docs).
#[derive(Debug)]
pub struct GeodesicSolver {
    n: usize,
    /// Input triangles and positions (face-point sources and the shift).
    triangles: Vec<[usize; 3]>,
    positions: Vec<[f64; 3]>,
    /// Triangles carrying gradient and divergence.
    frames: FaceFrames,
    /// Component of each vertex (`usize::MAX` for a vertex no triangle uses).
    component: Vec<usize>,
    n_components: usize,
    heat: SparseCholesky,
    /// Dirichlet heat on the interior vertices: (interior vertices, factor).
    dirichlet: Option<(Vec<usize>, SparseCholesky)>,
    poisson: SparseCholesky,
    /// Vertices whose Poisson right-hand side is set to 0: one held vertex per component
    /// (convention `crane`) and the vertices no triangle uses.
    zero_rhs: Vec<usize>,
    h: f64,
    t: f64,
    laplacian: Laplacian,
    params: GeodesicParams,
    factor_len: usize,
}

impl GeodesicSolver {
    /// Assembles the operators of `laplacian` on `mesh` (unscaled: distances are in the
    /// mesh's units) and factors the heat and Poisson matrices.
    pub fn new(
        mesh: &Mesh,
        laplacian: Laplacian,
        params: &GeodesicParams,
    ) -> Result<Self, GeodesicError> {
        if !(params.time_factor.is_finite() && params.time_factor > 0.0) {
            return Err(GeodesicError::BadParameter(format!(
                "the heat-method time factor m (t = m h^2) must be a finite number > 0, got {}",
                params.time_factor
            )));
        }
        if !laplacian.is_cotangent() {
            return Err(GeodesicError::NotGeometric(laplacian));
        }
        let n = mesh.n_vertices();
        let pp3d = params.convention == Convention::Potpourri3d;
        // Operators, the triangles of the gradient, h, and the scale of gc's Laplacian.
        let (stiffness, mass, frames, h, gc_scale) = if laplacian == Laplacian::Robust {
            params.robust.validate()?;
            let mean = if pp3d {
                MollifyMean::Cover
            } else {
                MollifyMean::Distinct
            };
            let (r, faces) = robust_with_faces(
                mesh.positions(),
                mesh.triangles(),
                &params.robust,
                1.0,
                Gluing::Angular,
                mean,
                true,
            );
            let faces = faces.unwrap_or_default();
            let h = if pp3d {
                faces.mean_edge_length
            } else {
                distinct_mean_edge_length(mesh)
            };
            let frames = FaceFrames::from_lengths(&faces.vertices, &faces.lengths, 0.5);
            (r.stiffness, r.mass, frames, h, 2.0)
        } else {
            let ops = Operators::new(mesh, laplacian);
            let frames = FaceFrames::from_mesh(mesh);
            (
                ops.stiffness,
                ops.mass,
                frames,
                distinct_mean_edge_length(mesh),
                1.0,
            )
        };
        let t = params.time_factor * h * h;

        // Components (through triangles) and vertices no triangle uses.
        let mut uf = UnionFind::new(n);
        let mut used = vec![false; n];
        for tri in mesh.triangles() {
            uf.union(tri[0], tri[1]);
            uf.union(tri[1], tri[2]);
            for &v in tri {
                used[v] = true;
            }
        }
        let mut root_id = vec![usize::MAX; n];
        let mut component = vec![usize::MAX; n];
        let mut pinned = Vec::new();
        for v in 0..n {
            if !used[v] {
                continue;
            }
            let r = uf.find(v);
            if root_id[r] == usize::MAX {
                root_id[r] = pinned.len();
                pinned.push(v);
            }
            component[v] = root_id[r];
        }
        let n_components = pinned.len();

        // Heat: B + t S, 1 on the diagonal of unused vertices.
        let unused_diag: Vec<f64> = used.iter().map(|&u| if u { 0.0 } else { 1.0 }).collect();
        let heat_m = mass.add_scaled(1.0, &stiffness, t).add_scaled(
            1.0,
            &SparseMatrix::diagonal(&unused_diag),
            1.0,
        );
        let heat = SparseCholesky::new(&heat_m)?;

        // Dirichlet heat (Crane's rule, meshes with boundary only).
        let dirichlet = if pp3d {
            None
        } else {
            let boundary = boundary_vertices(mesh);
            if boundary.iter().any(|&b| b) {
                let interior: Vec<usize> = (0..n).filter(|&v| !boundary[v]).collect();
                if interior.is_empty() {
                    None
                } else {
                    let sub = heat_m.submatrix(&interior, &interior);
                    Some((interior, SparseCholesky::new(&sub)?))
                }
            } else {
                None
            }
        };

        // Poisson.
        let poisson_m = if pp3d {
            let eps = vec![1e-6 / gc_scale; n];
            stiffness
                .add_scaled(1.0, &SparseMatrix::diagonal(&eps), 1.0)
                .add_scaled(1.0, &SparseMatrix::diagonal(&unused_diag), 1.0)
        } else {
            let mut is_pinned = vec![false; n];
            for &p in &pinned {
                is_pinned[p] = true;
            }
            let mut trip = Vec::with_capacity(stiffness.nnz() + n);
            for c in 0..n {
                let (rows, vals) = stiffness.col(c);
                if is_pinned[c] || !used[c] {
                    continue;
                }
                for (&r, &v) in rows.iter().zip(vals) {
                    if !is_pinned[r] && used[r] {
                        trip.push((r, c, v));
                    }
                }
            }
            for v in 0..n {
                if is_pinned[v] || !used[v] {
                    trip.push((v, v, 1.0));
                }
            }
            SparseMatrix::from_triplets(n, n, &trip)
        };
        let poisson = SparseCholesky::new(&poisson_m)?;
        let mut zero_rhs: Vec<usize> = (0..n).filter(|&v| !used[v]).collect();
        if !pp3d {
            zero_rhs.extend(&pinned);
        }
        let factor_len = heat.factor_len()
            + poisson.factor_len()
            + dirichlet.as_ref().map_or(0, |d| d.1.factor_len());
        Ok(Self {
            n,
            triangles: mesh.triangles().to_vec(),
            positions: mesh.positions().to_vec(),
            frames,
            component,
            n_components,
            heat,
            dirichlet,
            poisson,
            zero_rhs,
            h,
            t,
            laplacian,
            params: *params,
            factor_len,
        })
    }

    /// Number of vertices.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The mean edge length `h` in `t = m h^2`.
    pub fn mean_edge_length(&self) -> f64 {
        self.h
    }

    /// The time step `t = m h^2`.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The Laplacian the solver uses.
    pub fn laplacian(&self) -> Laplacian {
        self.laplacian
    }

    /// The parameters.
    pub fn params(&self) -> &GeodesicParams {
        &self.params
    }

    /// True when Crane's boundary rule is in use (a mesh with boundary, [`Convention::Crane`]).
    pub fn averages_boundary(&self) -> bool {
        self.dirichlet.is_some()
    }

    /// Number of connected components (through triangles).
    pub fn n_components(&self) -> usize {
        self.n_components
    }

    /// Values held by the factors (8 bytes each).
    pub fn factor_len(&self) -> usize {
        self.factor_len
    }

    /// Approximate memory held by the solver, in bytes.
    pub fn memory_bytes(&self) -> usize {
        8 * self.factor_len
            + self.frames.memory_bytes()
            + self.triangles.len() * 24
            + self.positions.len() * 24
            + self.component.len() * 8
    }

    /// Vertices whose distance from `sources` is infinite: those on components without a
    /// source, and vertices no triangle uses. Checks the sources first.
    pub fn unreachable(&self, sources: &[Source]) -> Result<usize, GeodesicError> {
        let rhs = self.prepare(sources)?;
        Ok((0..self.n)
            .filter(|&v| {
                let c = self.component[v];
                c == usize::MAX || !rhs.has_component[c]
            })
            .count())
    }

    /// Distance from the set `sources` (the distance to the nearest of them) at every
    /// vertex; `f64::INFINITY` where no source can be reached.
    pub fn distance(&self, sources: &[Source]) -> Result<Vec<f64>, GeodesicError> {
        let rhs = self.prepare(sources)?;
        Ok(self
            .solve_block(std::slice::from_ref(&rhs))
            .pop()
            .unwrap_or_default())
    }

    /// Distance from one vertex.
    pub fn distance_from_vertex(&self, v: usize) -> Result<Vec<f64>, GeodesicError> {
        self.distance(&[Source::Vertex(v)])
    }

    /// Distances from several source sets at once (block right-hand sides, columns split
    /// over the rayon pool): one vector per set.
    pub fn distances(&self, sets: &[Vec<Source>]) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let rhs: Vec<Rhs> = sets
            .iter()
            .map(|s| self.prepare(s))
            .collect::<Result<_, _>>()?;
        let mut out = Vec::with_capacity(sets.len());
        for chunk in rhs.chunks(BLOCK) {
            out.extend(self.solve_block(chunk));
        }
        Ok(out)
    }

    /// Distances from each vertex of `vertices` on its own: one vector per vertex.
    pub fn distances_from_vertices(
        &self,
        vertices: &[usize],
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let sets: Vec<Vec<Source>> = vertices.iter().map(|&v| vec![Source::Vertex(v)]).collect();
        self.distances(&sets)
    }

    /// The `k x k` matrix of distances between the vertices `samples`: row `i` holds the
    /// distance from `samples[i]` at every sample. The heat method is not exactly
    /// symmetric; with `symmetric` the matrix is replaced by `(D + D^T) / 2`.
    pub fn distance_matrix(
        &self,
        samples: &[usize],
        symmetric: bool,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let k = samples.len();
        let mut d = vec![vec![0.0; k]; k];
        for (c, chunk) in samples.chunks(BLOCK).enumerate() {
            let rows = self.distances_from_vertices(chunk)?;
            for (i, row) in rows.iter().enumerate() {
                for (j, &s) in samples.iter().enumerate() {
                    d[c * BLOCK + i][j] = row[s];
                }
            }
        }
        if symmetric {
            for i in 0..k {
                for j in 0..i {
                    let m = 0.5 * (d[i][j] + d[j][i]);
                    d[i][j] = m;
                    d[j][i] = m;
                }
            }
        }
        Ok(d)
    }

    /// Checks a source set and turns it into the heat right-hand side and the shift data.
    fn prepare(&self, sources: &[Source]) -> Result<Rhs, GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSources);
        }
        let mut points = Vec::with_capacity(sources.len());
        let mut has_component = vec![false; self.n_components];
        for s in sources {
            let (verts, bary, lengths) = match *s {
                Source::Vertex(v) => {
                    if v >= self.n {
                        return Err(GeodesicError::VertexOutOfRange {
                            vertex: v,
                            n: self.n,
                        });
                    }
                    if self.component[v] == usize::MAX {
                        return Err(GeodesicError::IsolatedVertex { vertex: v });
                    }
                    ([v, v, v], [1.0, 0.0, 0.0], [0.0; 3])
                }
                Source::FacePoint { face, bary } => {
                    let Some(&tri) = self.triangles.get(face) else {
                        return Err(GeodesicError::FaceOutOfRange {
                            face,
                            m: self.triangles.len(),
                        });
                    };
                    let sum: f64 = bary.iter().sum();
                    if bary.iter().any(|b| !b.is_finite() || *b < 0.0)
                        || !(sum > 0.0 && sum.is_finite())
                    {
                        return Err(GeodesicError::BadBarycentric { face, bary });
                    }
                    let b = bary.map(|x| x / sum);
                    let p = tri.map(|v| self.positions[v]);
                    let l = std::array::from_fn(|k| {
                        crate::mesh::norm(crate::mesh::sub(p[(k + 1) % 3], p[k]))
                    });
                    (tri, b, l)
                }
            };
            has_component[self.component[verts[0]]] = true;
            points.push(SourcePoint {
                verts,
                bary,
                lengths,
            });
        }
        Ok(Rhs {
            points,
            has_component,
        })
    }

    /// Heat, direction, Poisson and shift for up to [`BLOCK`] source sets.
    fn solve_block(&self, rhs: &[Rhs]) -> Vec<Vec<f64>> {
        let n = self.n;
        let k = rhs.len();
        let mut u = vec![0.0; n * k];
        for (c, r) in rhs.iter().enumerate() {
            for p in &r.points {
                for i in 0..3 {
                    u[c * n + p.verts[i]] += p.bary[i];
                }
            }
        }
        let delta = self.dirichlet.as_ref().map(|_| u.clone());
        self.heat.solve_many_in_place(&mut u, k);
        if let (Some((interior, chol)), Some(delta)) = (&self.dirichlet, delta) {
            let ni = interior.len();
            let mut ud = vec![0.0; ni * k];
            for c in 0..k {
                for (i, &v) in interior.iter().enumerate() {
                    ud[c * ni + i] = delta[c * n + v];
                }
            }
            chol.solve_many_in_place(&mut ud, k);
            u.par_chunks_mut(n)
                .zip(ud.par_chunks(ni))
                .for_each(|(col, d)| {
                    for x in col.iter_mut() {
                        *x *= 0.5;
                    }
                    for (i, &v) in interior.iter().enumerate() {
                        col[v] += 0.5 * d[i];
                    }
                });
        }
        // Direction field and its divergence, one column per task.
        let mut phi = vec![0.0; n * k];
        phi.par_chunks_mut(n)
            .zip(u.par_chunks(n))
            .for_each(|(div, col)| {
                self.frames.normalized_divergence(col, div);
                for &v in &self.zero_rhs {
                    div[v] = 0.0;
                }
            });
        drop(u);
        self.poisson.solve_many_in_place(&mut phi, k);
        phi.par_chunks_mut(n)
            .zip(rhs.par_iter())
            .for_each(|(col, r)| self.shift(col, r));
        phi.chunks(n).map(|c| c.to_vec()).collect()
    }

    /// Shifts each component so that the weighted mean over its sources is 0; infinity on
    /// components without a source and on unused vertices.
    fn shift(&self, phi: &mut [f64], r: &Rhs) {
        let nc = self.n_components;
        let mut diff = vec![0.0; nc];
        let mut weight = vec![0.0; nc];
        for p in &r.points {
            let c = self.component[p.verts[0]];
            for i in 0..3 {
                let w = p.bary[i];
                if w == 0.0 {
                    continue;
                }
                let mut corner = [0.0; 3];
                corner[i] = 1.0;
                let expected = bary_distance(p.bary, corner, p.lengths);
                diff[c] += w * (phi[p.verts[i]] - expected);
                weight[c] += w;
            }
        }
        for (v, x) in phi.iter_mut().enumerate() {
            let c = self.component[v];
            if c == usize::MAX || weight[c] == 0.0 {
                *x = f64::INFINITY;
            } else {
                *x -= diff[c] / weight[c];
            }
        }
    }
}

/// One source point: its corners, barycentric weights and the triangle's edge lengths
/// `[|v0 v1|, |v1 v2|, |v2 v0|]` (a vertex source: weight 1 at corner 0).
#[derive(Debug, Clone)]
struct SourcePoint {
    verts: [usize; 3],
    bary: [f64; 3],
    lengths: [f64; 3],
}

/// A checked source set.
#[derive(Debug, Clone)]
struct Rhs {
    points: Vec<SourcePoint>,
    has_component: Vec<bool>,
}

/// Distance between two points of a triangle given by barycentric coordinates:
/// `|P - Q|^2 = -sum over edges (i, j) of l_ij^2 d_i d_j`, `d = b2 - b1`.
fn bary_distance(b1: [f64; 3], b2: [f64; 3], l: [f64; 3]) -> f64 {
    let d: [f64; 3] = std::array::from_fn(|i| b2[i] - b1[i]);
    let mut s = 0.0;
    for i in 0..3 {
        s += l[i] * l[i] * d[i] * d[(i + 1) % 3];
    }
    if s <= 0.0 { (-s).sqrt() } else { 0.0 }
}

/// Mean length of the distinct edges of `mesh` (geometry-central's mean over the mesh's
/// edges).
pub fn distinct_mean_edge_length(mesh: &Mesh) -> f64 {
    let mut e: Vec<(usize, usize)> = Vec::with_capacity(3 * mesh.n_triangles());
    for t in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            e.push((a.min(b), a.max(b)));
        }
    }
    e.par_sort_unstable();
    e.dedup();
    let p = mesh.positions();
    let s: f64 = e
        .iter()
        .map(|&(a, b)| crate::mesh::norm(crate::mesh::sub(p[a], p[b])))
        .sum();
    s / e.len().max(1) as f64
}

/// `true` for the vertices of edges with exactly one triangle.
fn boundary_vertices(mesh: &Mesh) -> Vec<bool> {
    let mut e: Vec<(usize, usize)> = Vec::with_capacity(3 * mesh.n_triangles());
    for t in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            e.push((a.min(b), a.max(b)));
        }
    }
    e.par_sort_unstable();
    let mut out = vec![false; mesh.n_vertices()];
    let mut i = 0;
    while i < e.len() {
        let mut j = i + 1;
        while j < e.len() && e[j] == e[i] {
            j += 1;
        }
        if j - i == 1 {
            out[e[i].0] = true;
            out[e[i].1] = true;
        }
        i = j;
    }
    out
}

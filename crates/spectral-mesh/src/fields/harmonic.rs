//! Harmonic and bi-harmonic maps with Dirichlet (point) constraints (Sect. 3 of the paper).
//!
//! A harmonic map solves `S f = 0` at the free vertices F with `f` fixed at the constrained
//! vertices I, where S is the stiffness matrix (**positive semi-definite**, the paper's L
//! is `-S`):
//!
//! ```text
//! S_FF f_F = -S_FI f_I                       (order 1, harmonic)
//! Q_FF f_F = -Q_FI f_I,  Q = S B^-1 S        (order 2, bi-harmonic)
//! ```
//!
//! Both systems are solved by a sparse Cholesky factorization of the free block, which is
//! positive definite as soon as every connected component holds a constraint and every
//! free vertex has a triangle with non-zero area.
//!
//! ## Components without a constraint
//! On a connected component that holds no constraint the map is undetermined up to a
//! constant (libigl's solver fails with a singular system there). We do not solve there:
//! the component is reported ([`HarmonicSolver::floating_components`],
//! [`FloatingComponent`]) and holds the mean of the constraint values, and callers leave
//! its vertices out of critical-point counts.
//!
//! ## Which mass the bi-harmonic map uses
//! `B^-1` must be cheap and sparse, so the bi-harmonic operator uses a **lumped**
//! (diagonal) mass: the row sums of the discretization's mass matrix.
//! - `fem`: the row sums of the consistent FEM mass, i.e. the barycentric areas `sum |t| / 3`
//!   (so `fem` and `voronoi-cot` give the same bi-harmonic map);
//! - `voronoi-cot`: the barycentric areas;
//! - `mixed-voronoi`: Meyer et al.'s mixed Voronoi areas (this is libigl's
//!   `harmonic(V, F, b, bc, 2)`);
//! - `cot` and `uniform`: `B = I`.
//!
//! For the harmonic map (order 1) only the stiffness matters: every cotangent discretization
//! gives the same map, `uniform` gives the graph-harmonic map.
//!
//! ## Vertices no triangle uses
//! They take the value `0` in the output (they are not part of the surface), and they may
//! not be constrained ([`HarmonicError::UnreferencedConstraint`]).
//!
//! ## Choosing constraints
//! [`ConstraintSpec`] gives the executable paper's defaults (2, 4 or 6 constraints at the
//! extreme vertices along x, y, z), explicit `vertex value` pairs (parsed from `V=X`
//! arguments with [`parse_constraint_arg`] or from a file with [`read_constraints_file`]),
//! or values attached to the vertices nearest to given points.

use std::collections::VecDeque;
use std::path::Path;
use std::str::FromStr;

use crate::linalg::{SparseCholesky, SparseMatrix};
use crate::mesh::Mesh;
use crate::mesh::topology::Topology;
use crate::operators::{Laplacian, Operators};

/// Errors raised while choosing constraints or solving for a harmonic map.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum HarmonicError {
    /// No constraint was given.
    #[error("no constraint given: a harmonic map needs at least one fixed vertex per component")]
    NoConstraints,
    /// A constraint names a vertex that does not exist.
    #[error(
        "constraint on vertex {vertex}, but the mesh has {n} vertices (valid: 0 to {})",
        .n.saturating_sub(1)
    )]
    ConstraintOutOfRange {
        /// The vertex named.
        vertex: usize,
        /// Number of vertices of the mesh.
        n: usize,
    },
    /// A constraint names a vertex no triangle uses.
    #[error("constraint on vertex {vertex}, which no triangle uses (it is not on the surface)")]
    UnreferencedConstraint {
        /// The vertex named.
        vertex: usize,
    },
    /// The same vertex is constrained to two different values.
    #[error("vertex {vertex} is constrained twice with different values ({first} and {second})")]
    ConflictingConstraints {
        /// The vertex.
        vertex: usize,
        /// The first value given.
        first: f64,
        /// The later, different value.
        second: f64,
    },
    /// Two of the paper's default rules pick the same vertex with different values.
    #[error(
        "the default constraints conflict: vertex {vertex} is both the {first} (value {first_value}) \
         and the {second} (value {second_value}); use fewer or explicit constraints"
    )]
    ExtremesConflict {
        /// The vertex picked twice.
        vertex: usize,
        /// The first rule (e.g. "min z vertex").
        first: String,
        /// Its value.
        first_value: f64,
        /// The second rule.
        second: String,
        /// Its value.
        second_value: f64,
    },
    /// A constraint value (or a point of [`ConstraintSpec::NearestPoints`]) is NaN or infinite.
    #[error("constraint {what} is not finite")]
    NonFinite {
        /// Description of the offending item.
        what: String,
    },
    /// The number of default constraints is not 2, 4 or 6.
    #[error("the default constraints come in 2, 4 or 6 (min/max along x, y, z), not {0}")]
    BadExtremesCount(usize),
    /// The order is not 1 (harmonic) or 2 (bi-harmonic).
    #[error("order must be 1 (harmonic) or 2 (bi-harmonic), not {0}")]
    BadOrder(u32),
    /// A free vertex has no stiffness at all (all its triangles have zero area).
    #[error(
        "free vertex {vertex} has no non-degenerate triangle (zero stiffness): the map is \
         undetermined there; repair the zero-area triangles or constrain it"
    )]
    DegenerateVertex {
        /// The vertex.
        vertex: usize,
    },
    /// The bi-harmonic operator needs a positive lumped mass where the stiffness is non-zero.
    #[error("vertex {vertex} has lumped mass {mass} (must be > 0) for the bi-harmonic operator")]
    NonPositiveMass {
        /// The vertex.
        vertex: usize,
        /// Its lumped mass.
        mass: f64,
    },
    /// The free block could not be factored.
    #[error(
        "the free block of the {operator} is not positive definite ({detail}); the usual cause \
         is zero-area triangles or a part of the mesh joined to the rest only through them"
    )]
    NotPositiveDefinite {
        /// "Laplacian" or "bi-Laplacian".
        operator: &'static str,
        /// The factorization's message.
        detail: String,
    },
    /// The values given to a [`HarmonicSolver`] do not match its constraint vertices.
    #[error("expected {expected} constraint values, got {got}")]
    ValueCount {
        /// Number of constrained vertices.
        expected: usize,
        /// Number of values given.
        got: usize,
    },
    /// Constraints given to [`HarmonicSolver::solve_constraints`] use other vertices than the
    /// ones it was built for.
    #[error("the solver was factored for other constraint vertices (vertex {vertex} differs)")]
    VertexSetMismatch {
        /// The first vertex that differs.
        vertex: usize,
    },
    /// A `V=X` argument could not be read.
    #[error("bad constraint '{arg}': {message} (expected VERTEX=VALUE, e.g. 12=0.5)")]
    ParseArg {
        /// The argument.
        arg: String,
        /// What is wrong.
        message: String,
    },
    /// A line of a constraints file could not be read.
    #[error("{source_name}:{line}: {message} (expected 'VERTEX VALUE', '#' starts a comment)")]
    ParseFile {
        /// File name (or other source description).
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A constraints file could not be read.
    #[error("cannot read constraints file {file}: {message}")]
    Io {
        /// The file.
        file: String,
        /// The system's message.
        message: String,
    },
}

/// One Dirichlet constraint: `f(vertex) = value`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Constraint {
    /// Vertex index.
    pub vertex: usize,
    /// Prescribed value.
    pub value: f64,
}

impl FromStr for Constraint {
    type Err = HarmonicError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_constraint_arg(s)
    }
}

/// How the constrained vertices are chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum ConstraintSpec {
    /// The executable paper's defaults with 2, 4 or 6 constraints: the vertex of minimum x
    /// gets 0 and that of maximum x gets 1; 4 adds min y -> 0 and max y -> 1; 6 adds min z
    /// -> 0 and max z -> 1. Only vertices used by a triangle are candidates; ties go to the
    /// lowest vertex index. A vertex picked by two rules with the same value is constrained
    /// once; with different values it is an error ([`HarmonicError::ExtremesConflict`]).
    Extremes(usize),
    /// Explicit constraints.
    Explicit(Vec<Constraint>),
    /// Each point's value goes to the used vertex nearest to it (Euclidean; ties to the
    /// lowest index).
    NearestPoints(Vec<([f64; 3], f64)>),
}

impl Default for ConstraintSpec {
    /// The paper's first experiment: 2 constraints (min x -> 0, max x -> 1).
    fn default() -> Self {
        ConstraintSpec::Extremes(2)
    }
}

impl ConstraintSpec {
    /// Resolves the specification to a validated list of constraints on `mesh`: vertices in
    /// range and used by a triangle, finite values, no vertex twice (a repeated vertex with
    /// the same value is kept once, in its first position).
    pub fn resolve(&self, mesh: &Mesh) -> Result<Vec<Constraint>, HarmonicError> {
        let used = referenced(mesh);
        match self {
            ConstraintSpec::Extremes(k) => {
                if !matches!(k, 2 | 4 | 6) {
                    return Err(HarmonicError::BadExtremesCount(*k));
                }
                let axes = ["x", "y", "z"];
                let mut picked: Vec<(Constraint, String)> = Vec::new();
                let p = mesh.positions();
                for (a, axis) in axes.iter().enumerate().take(k / 2) {
                    let mut lo: Option<usize> = None;
                    let mut hi: Option<usize> = None;
                    for v in (0..mesh.n_vertices()).filter(|&v| used[v]) {
                        // Strict comparisons keep the lowest index on ties.
                        if lo.is_none_or(|l| p[v][a] < p[l][a]) {
                            lo = Some(v);
                        }
                        if hi.is_none_or(|h| p[v][a] > p[h][a]) {
                            hi = Some(v);
                        }
                    }
                    let (Some(lo), Some(hi)) = (lo, hi) else {
                        return Err(HarmonicError::NoConstraints);
                    };
                    for (v, val, rule) in [(lo, 0.0, "min"), (hi, 1.0, "max")] {
                        let name = format!("{rule} {axis} vertex");
                        if let Some((c, other)) = picked.iter().find(|(c, _)| c.vertex == v) {
                            if c.value != val {
                                return Err(HarmonicError::ExtremesConflict {
                                    vertex: v,
                                    first: other.clone(),
                                    first_value: c.value,
                                    second: name,
                                    second_value: val,
                                });
                            }
                            continue;
                        }
                        picked.push((
                            Constraint {
                                vertex: v,
                                value: val,
                            },
                            name,
                        ));
                    }
                }
                Ok(picked.into_iter().map(|(c, _)| c).collect())
            }
            ConstraintSpec::Explicit(list) => validate_constraints(mesh.n_vertices(), &used, list),
            ConstraintSpec::NearestPoints(points) => {
                let p = mesh.positions();
                let mut list = Vec::with_capacity(points.len());
                for (k, &(q, value)) in points.iter().enumerate() {
                    if q.iter().any(|c| !c.is_finite()) {
                        return Err(HarmonicError::NonFinite {
                            what: format!("point {k} ({:?})", q),
                        });
                    }
                    let mut best: Option<(f64, usize)> = None;
                    for v in (0..mesh.n_vertices()).filter(|&v| used[v]) {
                        let d = crate::mesh::sub(p[v], q);
                        let d2 = crate::mesh::dot(d, d);
                        if best.is_none_or(|(b, _)| d2 < b) {
                            best = Some((d2, v));
                        }
                    }
                    let Some((_, v)) = best else {
                        return Err(HarmonicError::NoConstraints);
                    };
                    list.push(Constraint { vertex: v, value });
                }
                validate_constraints(mesh.n_vertices(), &used, &list)
            }
        }
    }
}

/// Which vertices some triangle uses.
fn referenced(mesh: &Mesh) -> Vec<bool> {
    let mut used = vec![false; mesh.n_vertices()];
    for tri in mesh.triangles() {
        for &v in tri {
            used[v] = true;
        }
    }
    used
}

/// Checks range, use, finiteness and conflicts; keeps first occurrences in order.
fn validate_constraints(
    n: usize,
    used: &[bool],
    list: &[Constraint],
) -> Result<Vec<Constraint>, HarmonicError> {
    let mut seen: Vec<Option<f64>> = vec![None; n];
    let mut out = Vec::with_capacity(list.len());
    for c in list {
        if c.vertex >= n {
            return Err(HarmonicError::ConstraintOutOfRange {
                vertex: c.vertex,
                n,
            });
        }
        if !c.value.is_finite() {
            return Err(HarmonicError::NonFinite {
                what: format!("value {} on vertex {}", c.value, c.vertex),
            });
        }
        if !used[c.vertex] {
            return Err(HarmonicError::UnreferencedConstraint { vertex: c.vertex });
        }
        match seen[c.vertex] {
            Some(v) if v != c.value => {
                return Err(HarmonicError::ConflictingConstraints {
                    vertex: c.vertex,
                    first: v,
                    second: c.value,
                });
            }
            Some(_) => {}
            None => {
                seen[c.vertex] = Some(c.value);
                out.push(*c);
            }
        }
    }
    Ok(out)
}

/// Parses one `VERTEX=VALUE` argument (spaces around either side are allowed).
pub fn parse_constraint_arg(arg: &str) -> Result<Constraint, HarmonicError> {
    let bad = |message: &str| HarmonicError::ParseArg {
        arg: arg.to_string(),
        message: message.to_string(),
    };
    let (v, x) = arg.split_once('=').ok_or_else(|| bad("no '='"))?;
    let vertex = v
        .trim()
        .parse::<usize>()
        .map_err(|_| bad("the vertex is not a non-negative integer"))?;
    let value = x
        .trim()
        .parse::<f64>()
        .map_err(|_| bad("the value is not a number"))?;
    if !value.is_finite() {
        return Err(bad("the value is not finite"));
    }
    Ok(Constraint { vertex, value })
}

/// Parses the text of a constraints file: one `VERTEX VALUE` pair per line (separated by
/// spaces, tabs or a comma), `#` starts a comment, blank lines are skipped. Errors name
/// `source_name` and the 1-based line. Range and conflicts are checked later, by
/// [`ConstraintSpec::resolve`] or the solvers.
pub fn parse_constraints(text: &str, source_name: &str) -> Result<Vec<Constraint>, HarmonicError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let err = |message: String| HarmonicError::ParseFile {
            source_name: source_name.to_string(),
            line: i + 1,
            message,
        };
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let tokens: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .collect();
        if tokens.len() != 2 {
            return Err(err(format!("found {} fields", tokens.len())));
        }
        let vertex = tokens[0].parse::<usize>().map_err(|_| {
            err(format!(
                "vertex '{}' is not a non-negative integer",
                tokens[0]
            ))
        })?;
        let value = tokens[1]
            .parse::<f64>()
            .map_err(|_| err(format!("value '{}' is not a number", tokens[1])))?;
        if !value.is_finite() {
            return Err(err(format!("value '{}' is not finite", tokens[1])));
        }
        out.push(Constraint { vertex, value });
    }
    Ok(out)
}

/// Reads a constraints file (format of [`parse_constraints`]).
pub fn read_constraints_file(path: &Path) -> Result<Vec<Constraint>, HarmonicError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| HarmonicError::Io {
        file: name.clone(),
        message: e.to_string(),
    })?;
    parse_constraints(&text, &name)
}

/// Parameters of a harmonic map. `Default` is the paper's: order 1 with the linear FEM
/// discretization (whose stiffness is the cotangent one).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HarmonicParams {
    /// 1 = harmonic (`S f = 0`), 2 = bi-harmonic (`S B^-1 S f = 0`, lumped B).
    pub order: u32,
    /// The discretization: its stiffness, and for order 2 its lumped mass (see the module
    /// documentation).
    pub laplacian: Laplacian,
}

impl Default for HarmonicParams {
    fn default() -> Self {
        Self {
            order: 1,
            laplacian: Laplacian::Fem,
        }
    }
}

/// The bi-Laplacian `Q = S D^-1 S` with `D` the lumped (row-summed) mass, `n x n`,
/// positive semi-definite. Vertices whose stiffness column is empty are skipped (their mass
/// may be zero); a non-empty column with a non-positive mass is an error.
pub fn bilaplacian(ops: &Operators) -> Result<SparseMatrix, HarmonicError> {
    let s = &ops.stiffness;
    let n = s.nrows();
    let d = ops.mass.row_sums();
    let mut inv = vec![0.0; n];
    for k in 0..n {
        let (_, vals) = s.col(k);
        if vals.iter().any(|&x| x != 0.0) {
            if !(d[k] > 0.0 && d[k].is_finite()) {
                return Err(HarmonicError::NonPositiveMass {
                    vertex: k,
                    mass: d[k],
                });
            }
            inv[k] = 1.0 / d[k];
        }
    }
    // Column j of Q = sum_k S[:, k] S[k, j] / d_k, accumulated densely (S is symmetric).
    let mut acc = vec![0.0; n];
    let mut mark = vec![usize::MAX; n];
    let mut rows: Vec<usize> = Vec::new();
    let mut triplets: Vec<(usize, usize, f64)> = Vec::with_capacity(20 * n);
    for j in 0..n {
        rows.clear();
        let (kk, skj) = s.col(j);
        for (&k, &w) in kk.iter().zip(skj) {
            if w == 0.0 || inv[k] == 0.0 {
                continue;
            }
            let a = w * inv[k];
            let (ii, sik) = s.col(k);
            for (&i, &x) in ii.iter().zip(sik) {
                if mark[i] != j {
                    mark[i] = j;
                    acc[i] = 0.0;
                    rows.push(i);
                }
                acc[i] += x * a;
            }
        }
        triplets.extend(rows.iter().map(|&i| (i, j, acc[i])));
    }
    Ok(SparseMatrix::from_triplets(n, n, &triplets))
}

/// A factored harmonic (or bi-harmonic) problem for a fixed set of constrained vertices:
/// factor once, then solve for as many value vectors as needed.
#[derive(Debug, Clone)]
pub struct HarmonicSolver {
    n: usize,
    order: u32,
    constrained: Vec<usize>,
    free: Vec<usize>,
    /// Vertices of components that hold no constraint.
    floating: Vec<usize>,
    floating_components: Vec<FloatingComponent>,
    q_fi: SparseMatrix,
    chol: SparseCholesky,
}

/// A connected component that holds no constraint. The map is undetermined there up to a
/// constant; it is given the mean of the constraint values (the middle of the colour
/// range), and its vertices are not classified as critical points.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FloatingComponent {
    /// Component index (as in `Topology::components`).
    pub component: usize,
    /// Its lowest vertex index.
    pub first_vertex: usize,
    /// Number of vertices in it.
    pub vertices: usize,
}

impl HarmonicSolver {
    /// Bytes this solver holds, counted from its arrays: the factor's values (8 bytes
    /// each), the coupling block `Q_FI` (16 bytes per stored entry) and the vertex lists.
    /// The factor's symbolic analysis is not counted.
    pub fn memory_bytes(&self) -> usize {
        self.chol.factor_len() * 8
            + self.q_fi.nnz() * 16
            + (self.constrained.len() + self.free.len() + self.floating.len()) * 8
    }

    /// Builds the operators of `params.laplacian` and factors the free block for the
    /// constrained vertices `constrained` (any order, no repeats).
    pub fn new(
        mesh: &Mesh,
        constrained: &[usize],
        params: &HarmonicParams,
    ) -> Result<Self, HarmonicError> {
        check_order(params.order)?;
        let ops = Operators::new(mesh, params.laplacian);
        Self::with_operators(mesh, &ops, constrained, params.order)
    }

    /// As [`HarmonicSolver::new`], reusing operators already built for `mesh`.
    pub fn with_operators(
        mesh: &Mesh,
        ops: &Operators,
        constrained: &[usize],
        order: u32,
    ) -> Result<Self, HarmonicError> {
        check_order(order)?;
        let n = mesh.n_vertices();
        if constrained.is_empty() {
            return Err(HarmonicError::NoConstraints);
        }
        let used = referenced(mesh);
        let mut is_con = vec![false; n];
        for &v in constrained {
            if v >= n {
                return Err(HarmonicError::ConstraintOutOfRange { vertex: v, n });
            }
            if !used[v] {
                return Err(HarmonicError::UnreferencedConstraint { vertex: v });
            }
            is_con[v] = true;
        }
        let (floating_components, is_floating) = floating_components(mesh, &is_con);
        let mut sorted: Vec<usize> = constrained.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        let free: Vec<usize> = (0..n)
            .filter(|&v| used[v] && !is_con[v] && !is_floating[v])
            .collect();
        let floating: Vec<usize> = (0..n).filter(|&v| is_floating[v]).collect();
        let (q, operator) = if order == 1 {
            (ops.stiffness.clone(), "Laplacian")
        } else {
            (bilaplacian(ops)?, "bi-Laplacian")
        };
        let q_ff = q.submatrix(&free, &free);
        for (k, d) in q_ff.diag().into_iter().enumerate() {
            if d == 0.0 {
                return Err(HarmonicError::DegenerateVertex { vertex: free[k] });
            }
        }
        let q_fi = q.submatrix(&free, &sorted);
        let chol = SparseCholesky::new(&q_ff).map_err(|e| HarmonicError::NotPositiveDefinite {
            operator,
            detail: e.to_string(),
        })?;
        Ok(Self {
            n,
            order,
            constrained: sorted,
            free,
            floating,
            floating_components,
            q_fi,
            chol,
        })
    }

    /// The constrained vertices, ascending: the order of the values [`HarmonicSolver::solve`]
    /// expects.
    pub fn constrained_vertices(&self) -> &[usize] {
        &self.constrained
    }

    /// 1 (harmonic) or 2 (bi-harmonic).
    pub fn order(&self) -> u32 {
        self.order
    }

    /// The components that hold no constraint (see [`FloatingComponent`]).
    pub fn floating_components(&self) -> &[FloatingComponent] {
        &self.floating_components
    }

    /// Solves for the values `values[k]` at `constrained_vertices()[k]`; returns `n` values
    /// (`0` at vertices no triangle uses).
    pub fn solve(&self, values: &[f64]) -> Result<Vec<f64>, HarmonicError> {
        self.solve_many(values, 1)
    }

    /// Solves for `k` value vectors at once: `values` is `|I| x k` column-major; returns
    /// `n x k` column-major.
    pub fn solve_many(&self, values: &[f64], k: usize) -> Result<Vec<f64>, HarmonicError> {
        let ni = self.constrained.len();
        if values.len() != ni * k {
            return Err(HarmonicError::ValueCount {
                expected: ni * k,
                got: values.len(),
            });
        }
        if let Some(p) = values.iter().position(|x| !x.is_finite()) {
            return Err(HarmonicError::NonFinite {
                what: format!(
                    "value {} on vertex {}",
                    values[p],
                    self.constrained[p % ni.max(1)]
                ),
            });
        }
        let nf = self.free.len();
        let mut rhs = Vec::with_capacity(nf * k);
        for c in 0..k {
            let r = self.q_fi.mul_vec(&values[c * ni..(c + 1) * ni]);
            rhs.extend(r.into_iter().map(|x| -x));
        }
        if nf > 0 {
            self.chol.solve_many_in_place(&mut rhs, k);
        }
        let mut out = vec![0.0; self.n * k];
        for c in 0..k {
            let col = &mut out[c * self.n..(c + 1) * self.n];
            for (j, &v) in self.constrained.iter().enumerate() {
                col[v] = values[c * ni + j];
            }
            for (j, &v) in self.free.iter().enumerate() {
                col[v] = rhs[c * nf + j];
            }
            if !self.floating.is_empty() {
                let vals = &values[c * ni..(c + 1) * ni];
                let mean = vals.iter().sum::<f64>() / vals.len().max(1) as f64;
                for &v in &self.floating {
                    col[v] = mean;
                }
            }
        }
        Ok(out)
    }

    /// Solves for constraints on exactly the vertex set this solver was built for (any
    /// order; conflicts and non-finite values are errors).
    pub fn solve_constraints(&self, constraints: &[Constraint]) -> Result<Vec<f64>, HarmonicError> {
        let mut vals: Vec<Option<f64>> = vec![None; self.constrained.len()];
        for c in constraints {
            let j = self
                .constrained
                .binary_search(&c.vertex)
                .map_err(|_| HarmonicError::VertexSetMismatch { vertex: c.vertex })?;
            match vals[j] {
                Some(v) if v != c.value => {
                    return Err(HarmonicError::ConflictingConstraints {
                        vertex: c.vertex,
                        first: v,
                        second: c.value,
                    });
                }
                _ => vals[j] = Some(c.value),
            }
        }
        let mut values = Vec::with_capacity(vals.len());
        for (j, v) in vals.into_iter().enumerate() {
            values.push(v.ok_or(HarmonicError::VertexSetMismatch {
                vertex: self.constrained[j],
            })?);
        }
        self.solve(&values)
    }
}

fn check_order(order: u32) -> Result<(), HarmonicError> {
    if matches!(order, 1 | 2) {
        Ok(())
    } else {
        Err(HarmonicError::BadOrder(order))
    }
}

/// The components that hold no constrained vertex, and a per-vertex flag of their vertices.
fn floating_components(mesh: &Mesh, is_con: &[bool]) -> (Vec<FloatingComponent>, Vec<bool>) {
    let topo = Topology::new(mesh);
    let nc = topo.n_components();
    let mut has = vec![false; nc];
    let mut first = vec![usize::MAX; nc];
    for (v, &c) in topo.vertex_component.iter().enumerate() {
        if c < nc {
            has[c] |= is_con[v];
            first[c] = first[c].min(v);
        }
    }
    let list = (0..nc)
        .filter(|&c| !has[c])
        .map(|c| FloatingComponent {
            component: c,
            first_vertex: first[c],
            vertices: topo.components[c].vertices,
        })
        .collect();
    let flags = topo
        .vertex_component
        .iter()
        .map(|&c| c < nc && !has[c])
        .collect();
    (list, flags)
}

/// The harmonic (`params.order == 1`) or bi-harmonic (`2`) map with the given constraints:
/// `n` values, equal to the constraint values at constrained vertices and `0` at vertices
/// no triangle uses. See the module documentation for the systems solved.
pub fn harmonic_map(
    mesh: &Mesh,
    constraints: &[Constraint],
    params: &HarmonicParams,
) -> Result<Vec<f64>, HarmonicError> {
    check_order(params.order)?;
    let ops = Operators::new(mesh, params.laplacian);
    harmonic_map_with_operators(mesh, &ops, constraints, params.order)
}

/// As [`harmonic_map`], reusing operators already built for `mesh`.
pub fn harmonic_map_with_operators(
    mesh: &Mesh,
    ops: &Operators,
    constraints: &[Constraint],
    order: u32,
) -> Result<Vec<f64>, HarmonicError> {
    let list = validate_constraints(mesh.n_vertices(), &referenced(mesh), constraints)?;
    let vertices: Vec<usize> = list.iter().map(|c| c.vertex).collect();
    let solver = HarmonicSolver::with_operators(mesh, ops, &vertices, order)?;
    solver.solve_constraints(&list)
}

/// The largest `|f_new - f_old|` over the vertices within `rings` edge rings of the `seeds`
/// (ring 0 = the seeds themselves). Seeds out of range are ignored, as are vertices beyond
/// the length of either field; returns 0 when nothing is compared.
///
/// Measures the paper's locality property: adding constraints changes a harmonic map little
/// near the constraints that were already there.
pub fn max_change_near(
    mesh: &Mesh,
    f_old: &[f64],
    f_new: &[f64],
    seeds: &[usize],
    rings: usize,
) -> f64 {
    let n = mesh.n_vertices();
    let adj = vertex_adjacency(mesh);
    let mut depth = vec![usize::MAX; n];
    let mut queue = VecDeque::new();
    for &s in seeds {
        if s < n && depth[s] == usize::MAX {
            depth[s] = 0;
            queue.push_back(s);
        }
    }
    let mut worst: f64 = 0.0;
    while let Some(v) = queue.pop_front() {
        if v < f_old.len() && v < f_new.len() {
            let d = (f_new[v] - f_old[v]).abs();
            if d > worst || d.is_nan() {
                worst = d;
            }
        }
        if depth[v] < rings {
            for &u in &adj[v] {
                if depth[u] == usize::MAX {
                    depth[u] = depth[v] + 1;
                    queue.push_back(u);
                }
            }
        }
    }
    worst
}

/// Neighbours of each vertex through triangle edges, ascending, no repeats.
pub fn vertex_adjacency(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut adj = vec![Vec::new(); mesh.n_vertices()];
    for tri in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            adj[a].push(b);
            adj[b].push(a);
        }
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    adj
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::unit_square;

    #[test]
    fn parses_arguments_and_files() {
        assert_eq!(
            parse_constraint_arg(" 12 = -0.5 ").unwrap(),
            Constraint {
                vertex: 12,
                value: -0.5
            }
        );
        assert!(parse_constraint_arg("12").is_err());
        assert!(parse_constraint_arg("-1=2").is_err());
        assert!(parse_constraint_arg("1=nan").is_err());
        let text = "# header\n3 1.0\n\n  7\t-2 # trailing\n5,0.25\n";
        let c = parse_constraints(text, "c.txt").unwrap();
        assert_eq!(c.len(), 3);
        assert_eq!(c[1].vertex, 7);
        assert_eq!(c[1].value, -2.0);
        assert_eq!(c[2].value, 0.25);
        let e = parse_constraints("1 2\n3 x\n", "c.txt").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("c.txt:2:"), "{msg}");
        assert!(msg.contains("'x'"), "{msg}");
    }

    #[test]
    fn extremes_on_flat_square_conflict_in_z() {
        let m = unit_square();
        let c = ConstraintSpec::Extremes(2).resolve(&m).unwrap();
        // min x: vertices 0 and 3 tie -> 0; max x: 1 and 2 tie -> 1.
        assert_eq!(c[0].vertex, 0);
        assert_eq!(c[1].vertex, 1);
        // min y: 0 (already 0, merged); max y: 2 (ties 2,3 -> 2) but 2 != max x vertex 1.
        let c4 = ConstraintSpec::Extremes(4).resolve(&m).unwrap();
        assert_eq!(c4.len(), 3);
        let e = ConstraintSpec::Extremes(6).resolve(&m).unwrap_err();
        assert!(
            matches!(e, HarmonicError::ExtremesConflict { vertex: 0, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("max z"));
        assert!(ConstraintSpec::Extremes(3).resolve(&m).is_err());
    }

    #[test]
    fn constraint_validation() {
        let m = unit_square();
        let c = |vertex, value| Constraint { vertex, value };
        let p = HarmonicParams::default();
        assert!(matches!(
            harmonic_map(&m, &[c(9, 0.0)], &p),
            Err(HarmonicError::ConstraintOutOfRange { vertex: 9, n: 4 })
        ));
        assert!(matches!(
            harmonic_map(&m, &[c(0, 0.0), c(0, 1.0)], &p),
            Err(HarmonicError::ConflictingConstraints { vertex: 0, .. })
        ));
        assert!(matches!(
            harmonic_map(&m, &[c(0, f64::INFINITY)], &p),
            Err(HarmonicError::NonFinite { .. })
        ));
        assert!(matches!(
            harmonic_map(&m, &[], &p),
            Err(HarmonicError::NoConstraints)
        ));
        let bad = HarmonicParams { order: 3, ..p };
        assert!(matches!(
            harmonic_map(&m, &[c(0, 0.0)], &bad),
            Err(HarmonicError::BadOrder(3))
        ));
        // Same value twice is fine.
        let f = harmonic_map(&m, &[c(0, 0.0), c(0, 0.0), c(2, 1.0)], &p).unwrap();
        assert_eq!(f[0], 0.0);
        assert_eq!(f[2], 1.0);
    }

    #[test]
    fn nearest_points() {
        let m = unit_square();
        let c =
            ConstraintSpec::NearestPoints(vec![([0.9, 1.2, 0.0], 3.0), ([-1.0, 0.1, 0.0], 1.0)])
                .resolve(&m)
                .unwrap();
        assert_eq!(c[0].vertex, 2);
        assert_eq!(c[1].vertex, 0);
    }
}

//! Memory estimates of an analysis and of the work it does: what a mesh, an analysis, an
//! eigenbasis computation and a field request take, in bytes. A server that admits work
//! by memory (the web app's job queue and cache) asks these instead of deriving its own.
//!
//! The eigenbasis estimate follows the solver's own rules: the dense path by
//! [`takes_dense_path`], the sparse solver's search space by
//! [`crate::linalg::eigen::search_columns`]. Measured with the web crate's
//! `examples/job_memory.rs` (VmHWM over the resident memory before the solve) on 2.5k to
//! 100k vertices, k = 50 to 500: the estimate is 0.99x to 1.87x the measured increase,
//! 1.2x at the median (RELIABILITY.md, "Web server").

use super::{Analysis, DistanceSpec, FieldRequest};
use crate::Mesh;
use crate::linalg::eigen::search_columns;
use crate::operators::Laplacian;
use crate::spectral::eigenbasis::takes_dense_path;

/// Predicted values of the factor of `S - sigma B` on `n` vertices before it is made:
/// `n (7.5 log2 n - 35)`, at least `20 n`. Measured (values per vertex): 47 at 2.5k
/// (icosphere), 42-44 at 6-25k (3-torus, torus), 41 at 38k (bunny), 75 at 41k
/// (icosphere), 53 at 100k (torus), 97 at 411k; the formula gives 50, 60-74, 79, 80,
/// 90, 105.
pub fn predicted_factor_len(n: usize) -> usize {
    let per_vertex = (7.5 * (n.max(2) as f64).log2() - 35.0).max(20.0);
    (n as f64 * per_vertex) as usize
}

/// Peak bytes per byte of an input file being read: the bytes, the parsed mesh, its
/// connectivity and validation report (see RELIABILITY.md for the measurement).
pub const READ_FACTOR: usize = 12;

/// Peak bytes per vertex while a built-in shape is built and checked.
pub const SHAPE_BYTES_PER_VERTEX: usize = 1200;

/// Bytes an eigenbasis of `k` pairs on `n` vertices takes.
pub fn basis_bytes(n: usize, k: usize) -> usize {
    n * k * 8 + k * 16
}

/// Bytes a loaded mesh takes: positions and triangles (24 bytes each); 64 per vertex and
/// 96 per triangle leave room for what is kept beside them and allocator overhead.
pub fn mesh_bytes(m: &Mesh) -> usize {
    m.n_vertices() * 64 + m.n_triangles() * 96
}

/// Bytes a loaded point cloud of `n` points takes (positions and normals).
pub fn cloud_bytes(n: usize) -> usize {
    n * 96
}

/// Peak bytes of assembling the operators of a new analysis on `n` vertices (triplets
/// and the two sparse matrices; the robust Laplacian builds an intrinsic mesh first; the
/// point-cloud Laplacian of a cloud of `n` points also its neighbour lists, local
/// triangulations and their union: an estimate of twice the robust figure).
pub fn creation_bytes(n: usize, laplacian: Laplacian, point_cloud: bool) -> usize {
    match (laplacian, point_cloud) {
        (_, true) => 6000 * n,
        (Laplacian::Robust, false) => 3000 * n,
        _ => 1000 * n,
    }
}

/// Peak bytes of a field request on `n` vertices beyond what the analysis holds: the
/// values, the reply, critical points and level sets (400 per vertex), plus a harmonic
/// map's factorization (when not kept from an earlier request), a geodesic distance's
/// heat-method factors, or the wFEM distance's `B X` (`n x k`, computed once).
pub fn field_bytes(n: usize, request: &FieldRequest) -> usize {
    let base = 400 * n;
    match request {
        FieldRequest::Harmonic { .. } => base + predicted_factor_len(n) * 13,
        // The heat method factors up to three matrices (heat, Dirichlet heat, Poisson).
        FieldRequest::Geodesic { .. } => base + 3 * predicted_factor_len(n) * 13,
        FieldRequest::Distance {
            distance: DistanceSpec::WfemDiffusion { .. },
            k,
            ..
        } => base + 8 * n * k,
        _ => base,
    }
}

impl Analysis {
    /// True when a basis of `k` pairs of this analysis takes the dense path (the solver's
    /// rule for the whole input; see [`takes_dense_path`]).
    pub fn basis_is_dense(&self, k: usize) -> bool {
        let n = self.n();
        takes_dense_path(n, k.min(n), self.options().eigen.method)
    }

    /// Estimated peak of the memory a basis of `k` pairs adds to what the analysis
    /// holds, in bytes:
    ///
    /// - dense path: `8 * 12 n^2 + 6 MiB`;
    /// - sparse path, with `c` the search space ([`search_columns`]) and `f` the factor's
    ///   values (the held factorization's, else [`predicted_factor_len`]; a held one
    ///   adds nothing): `8 * (1.6 n c + 1.6 f + 15 c^2) + 6 MiB` (the basis it returns
    ///   included).
    pub fn basis_peak_bytes(&self, k: usize) -> usize {
        let n = self.n();
        let k = k.min(n);
        if self.basis_is_dense(k) {
            return 8 * 12 * n * n + (6 << 20);
        }
        let c = search_columns(n, k);
        let factor = if self.factor_len() > 0 {
            0
        } else {
            predicted_factor_len(n)
        };
        let doubles = 1.6 * (n * c) as f64 + 1.6 * factor as f64 + 15.0 * (c * c) as f64;
        (8.0 * doubles) as usize + (6 << 20)
    }

    /// What the analysis will hold once it has `k` pairs, in bytes: what it holds now
    /// ([`Analysis::memory_bytes`]), the new basis instead of the old one, and the
    /// factorization (held, else predicted).
    pub fn bytes_with_basis(&self, k: usize) -> usize {
        let n = self.n();
        let now = self.memory_bytes();
        let old_basis = self.held_k() * n * 8;
        let factor = if self.basis_is_dense(k) || self.factor_len() > 0 {
            0
        } else {
            predicted_factor_len(n) * 8
        };
        now.saturating_sub(old_basis) + 8 * n * k + factor
    }

    /// Bytes the analysis takes in a cache: [`Analysis::memory_bytes`] plus a tenth for
    /// allocator overhead and the factor's symbolic analysis; the analysis of a point
    /// cloud also holds its points and the triangle union of its Laplacian.
    pub fn cached_bytes(&self) -> usize {
        let mut b = self.memory_bytes();
        if self.is_point_cloud() {
            b += mesh_bytes(self.mesh()) + 48 * self.n();
        }
        b + b / 10
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::AnalysisOptions;
    use crate::spectral::eigenbasis::EigenMethod;
    use std::sync::Arc;

    #[test]
    fn the_solver_rules_the_estimate_reads() {
        assert_eq!(search_columns(100_000, 50), 120);
        assert_eq!(search_columns(100_000, 100), 200);
        assert_eq!(search_columns(100_000, 500), 800);
        assert_eq!(search_columns(6396, 6396), 6396);
        let auto = |n, k| takes_dense_path(n, k, EigenMethod::Auto);
        assert!(auto(300, 1) && auto(1500, 501) && !auto(1500, 500));
        assert!(!auto(1501, 1501));
        assert!(takes_dense_path(100_000, 1, EigenMethod::Dense));
        assert!(!takes_dense_path(10, 1, EigenMethod::ShiftInvertBlock));
    }

    #[test]
    fn the_factor_prediction_is_within_the_measured_range() {
        // (n, measured values per vertex): the prediction is at most 2x above (the
        // bunny: 1.94x) and never more than 15% below.
        for (n, measured) in [
            (2562, 47.0),
            (6396, 42.4),
            (25088, 44.3),
            (37706, 40.7),
            (40962, 74.7),
            (100_352, 52.5),
        ] {
            let p = predicted_factor_len(n) as f64 / n as f64;
            assert!(p > 0.85 * measured && p < 2.0 * measured, "n = {n}: {p}");
        }
    }

    #[test]
    fn estimates_of_an_analysis() {
        let mesh = Arc::new(crate::shapes::build_str("sphere:res=3").unwrap());
        let n = mesh.n_vertices();
        let a = Analysis::new(mesh.clone(), AnalysisOptions::default());
        assert!(n > 300);
        assert!(a.basis_is_dense(n) && !a.basis_is_dense(20));
        assert_eq!(a.basis_peak_bytes(n), 8 * 12 * n * n + (6 << 20));
        let small = a.basis_peak_bytes(20);
        assert!(
            small > 8 * n * 20 && small < a.basis_peak_bytes(n),
            "{small}"
        );
        // Before any solve: the predicted factor counts; after, the held one does.
        let before = a.bytes_with_basis(20);
        assert!(before >= a.memory_bytes() + 8 * n * 20 + predicted_factor_len(n) * 8);
        a.basis(20, &mut |_| {}, &crate::cancel::CancelToken::new())
            .unwrap();
        assert!(a.factor_len() > 0);
        assert!(a.basis_peak_bytes(20) < small);
        assert!(a.cached_bytes() > a.memory_bytes());
        assert!(creation_bytes(n, Laplacian::Fem, false) < creation_bytes(n, Laplacian::Fem, true));
        assert_eq!(basis_bytes(10, 2), 10 * 2 * 8 + 32);
    }
}

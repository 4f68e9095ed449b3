//! Evaluation of a point map against ground truth (pyFM's `accuracy`): for each vertex `v`
//! of shape 2, the geodesic distance on shape 1 between the vertex the map gives,
//! `p2p_21[v]`, and the true one, `gt_21[v]`, divided by `sqrt(area_1)`; the mean, and the
//! cumulative curve (the fraction of vertices whose error is `<= t`, for each threshold).
//!
//! Geodesics come from the heat method ([`GeodesicSolver`]), one solve per distinct true
//! vertex among the vertices mapped wrongly (a vertex mapped to its true vertex has error
//! 0 without a solve). With `max_sources`, only the vertices `v` with `v % s == 0` are
//! evaluated, `s` the smallest stride that needs at most that many solves.

use super::CorrespondenceError;
use super::pointwise::check_p2p;
use crate::geodesic::{GeodesicSolver, Source};

/// Sources solved together.
const SOURCE_BLOCK: usize = 32;

/// The errors of one evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct GeodesicErrors {
    /// The vertices of shape 2 evaluated (all, or every `stride`-th).
    pub vertices: Vec<usize>,
    /// Their errors, in units of `sqrt(area_1)`.
    pub errors: Vec<f64>,
    /// The mean error.
    pub mean: f64,
    /// Geodesic solves made.
    pub sources: usize,
    /// The stride (1: every vertex).
    pub stride: usize,
}

/// Errors of `p2p_21` against `gt_21` (both: for each vertex of shape 2 a vertex of shape
/// 1), geodesics on shape 1 from `solver`, normalized by `sqrt(area_1)`.
pub fn geodesic_errors(
    solver: &GeodesicSolver,
    p2p_21: &[usize],
    gt_21: &[usize],
    area_1: f64,
    max_sources: Option<usize>,
) -> Result<GeodesicErrors, CorrespondenceError> {
    let n1 = solver.n();
    let n2 = gt_21.len();
    check_p2p(p2p_21, n2, n1)?;
    check_p2p(gt_21, n2, n1)?;
    if !(area_1.is_finite() && area_1 > 0.0) {
        return Err(CorrespondenceError::InvalidParameter(format!(
            "the area of shape 1 must be finite and > 0, got {area_1}"
        )));
    }
    let sources_for = |stride: usize| {
        let mut s: Vec<usize> = (0..n2)
            .step_by(stride)
            .filter(|&v| p2p_21[v] != gt_21[v])
            .map(|v| gt_21[v])
            .collect();
        s.sort_unstable();
        s.dedup();
        s
    };
    let mut stride = 1;
    let mut sources = sources_for(stride);
    if let Some(cap) = max_sources {
        let cap = cap.max(1);
        while sources.len() > cap && stride < n2 {
            stride = (stride * sources.len()).div_ceil(cap).max(stride + 1);
            sources = sources_for(stride);
        }
    }
    let vertices: Vec<usize> = (0..n2).step_by(stride).collect();
    let mut errors = vec![0.0; vertices.len()];
    // For each source, the evaluated vertices whose true vertex it is (and are wrong).
    let mut slot = vec![usize::MAX; n1];
    for (q, &s) in sources.iter().enumerate() {
        slot[s] = q;
    }
    let mut by_source: Vec<Vec<usize>> = vec![Vec::new(); sources.len()];
    for (e, &v) in vertices.iter().enumerate() {
        if p2p_21[v] != gt_21[v] {
            by_source[slot[gt_21[v]]].push(e);
        }
    }
    let scale = 1.0 / area_1.sqrt();
    for (chunk_no, chunk) in sources.chunks(SOURCE_BLOCK).enumerate() {
        let sets: Vec<Vec<Source>> = chunk.iter().map(|&s| vec![Source::Vertex(s)]).collect();
        let dists = solver
            .distances(&sets)
            .map_err(|e| CorrespondenceError::Geodesic(e.to_string()))?;
        for (q, d) in dists.iter().enumerate() {
            for &e in &by_source[chunk_no * SOURCE_BLOCK + q] {
                errors[e] = d[p2p_21[vertices[e]]] * scale;
            }
        }
    }
    let mean = if errors.is_empty() {
        0.0
    } else {
        errors.iter().sum::<f64>() / errors.len() as f64
    };
    Ok(GeodesicErrors {
        vertices,
        errors,
        mean,
        sources: sources.len(),
        stride,
    })
}

/// The default thresholds of the cumulative curve: 0 to 0.25 in 101 steps.
pub fn default_thresholds() -> Vec<f64> {
    (0..=100).map(|i| 0.25 * i as f64 / 100.0).collect()
}

/// For each threshold, the fraction of `errors` that are `<= t`.
pub fn cumulative_curve(errors: &[f64], thresholds: &[f64]) -> Vec<f64> {
    if errors.is_empty() {
        return vec![0.0; thresholds.len()];
    }
    let mut sorted = errors.to_vec();
    sorted.sort_by(f64::total_cmp);
    thresholds
        .iter()
        .map(|&t| sorted.partition_point(|&e| e <= t) as f64 / sorted.len() as f64)
        .collect()
}

//! Farthest-point sampling with heat-method distances.

use super::{GeodesicError, GeodesicSolver};

/// `k` vertices spread over the surface: `start` first, then repeatedly the vertex whose
/// distance to the nearest vertex chosen so far is largest (one heat-method solve per
/// sample; the running minimum is kept). Vertices at infinite distance (other components)
/// are never chosen, so fewer than `k` come back when one component has fewer vertices
/// than asked for. Ties go to the smallest index.
pub fn farthest_point_sampling(
    solver: &GeodesicSolver,
    k: usize,
    start: usize,
) -> Result<Vec<usize>, GeodesicError> {
    let mut out = Vec::with_capacity(k);
    if k == 0 {
        return Ok(out);
    }
    let mut nearest = solver.distance_from_vertex(start)?;
    out.push(start);
    while out.len() < k {
        let mut best: Option<(usize, f64)> = None;
        for (v, &d) in nearest.iter().enumerate() {
            if d.is_finite() && best.is_none_or(|(_, b)| d > b) {
                best = Some((v, d));
            }
        }
        let Some((v, d)) = best else { break };
        if d <= 0.0 || out.contains(&v) {
            break;
        }
        out.push(v);
        let dv = solver.distance_from_vertex(v)?;
        for (a, b) in nearest.iter_mut().zip(dv) {
            if b < *a {
                *a = b;
            }
        }
    }
    Ok(out)
}

//! ZoomOut (Melzi, Ren, Rodolà, Sharma, Wonka and Ovsjanikov 2019), as pyFM runs it: from
//! `C` (`k2 x k1`), repeat `p2p_21 = fmap_to_p2p(C)` then `C = p2p_to_fmap(p2p_21)` one
//! `step` larger on both sides, until both sizes reach `k_final` (the last step may be
//! shorter); the point map returned is that of the last `C`.
//!
//! The other direction (a map for each vertex of shape 1) is the same refinement with the
//! shapes swapped, started from `C^T` ([`FunctionalMap::transpose`], the inverse of an
//! orthogonal map).

use super::pointwise::{fmap_to_p2p_hinted, p2p_to_fmap};
use super::{CorrespondenceError, FunctionalMap, truncate};
use crate::spectral::BasisView;

/// Refines `c` to `k_final x k_final` (see the module docs); returns the refined map and
/// its point map `p2p_21`. Both bases must hold `k_final` pairs.
pub fn zoomout(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    k_final: usize,
    step: usize,
) -> Result<(FunctionalMap, Vec<usize>), CorrespondenceError> {
    zoomout_with(c, basis1, basis2, k_final, step, &mut |_, _| {})
}

/// [`zoomout`] calling `progress(k1, k2)` after each iteration.
pub fn zoomout_with(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    k_final: usize,
    step: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(FunctionalMap, Vec<usize>), CorrespondenceError> {
    if step == 0 {
        return Err(CorrespondenceError::InvalidParameter(
            "the ZoomOut step must be >= 1".into(),
        ));
    }
    let k1_final = k_final.max(c.k1);
    let k2_final = k_final.max(c.k2);
    let basis1 = truncate(basis1, k1_final, 1)?;
    let basis2 = truncate(basis2, k2_final, 2)?;
    let mut cur = c.clone();
    // Each iteration's map is the next one's guess: the search is exact either way.
    let mut prev: Option<Vec<usize>> = None;
    while cur.k1 < k1_final || cur.k2 < k2_final {
        let p2p = fmap_to_p2p_hinted(&cur, basis1, basis2, false, prev.as_deref())?;
        let k1 = (cur.k1 + step).min(k1_final);
        let k2 = (cur.k2 + step).min(k2_final);
        cur = p2p_to_fmap(&p2p, basis1, basis2, k1, k2)?;
        prev = Some(p2p);
        progress(k1, k2);
    }
    let p2p = fmap_to_p2p_hinted(&cur, basis1, basis2, false, prev.as_deref())?;
    Ok((cur, p2p))
}

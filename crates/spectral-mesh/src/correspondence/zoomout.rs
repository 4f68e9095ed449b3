//! ZoomOut (Melzi, Ren, Rodolà, Sharma, Wonka and Ovsjanikov 2019), as pyFM runs it: from
//! `C` (`k2 x k1`), repeat `p2p_21 = fmap_to_p2p(C)` then `C = p2p_to_fmap(p2p_21)` one
//! `step` larger on both sides, until both sizes reach `k_final` (the last step may be
//! shorter); the point map returned is that of the last `C`.
//!
//! The reverse direction (a map for each vertex of shape 1) is the same refinement with
//! the shapes swapped, started from `C^T` ([`FunctionalMap::transpose`], the inverse of an
//! orthogonal map): its functional map carries functions on shape 2 to shape 1 and its
//! point map is `p2p_12`. [`ZoomoutDirection`] chooses one direction or both.

use super::pointwise::{fmap_to_p2p_hinted, p2p_to_fmap};
use super::{CorrespondenceError, FunctionalMap, truncate};
use crate::spectral::BasisView;

/// Which point map ZoomOut refines. `Default`: [`ZoomoutDirection::Forward`].
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum ZoomoutDirection {
    /// `p2p_21`, for each vertex of shape 2 a vertex of shape 1, refining `C` (pyFM's).
    #[default]
    Forward,
    /// `p2p_12`, for each vertex of shape 1 a vertex of shape 2, refining `C^T`.
    Reverse,
    /// Both, each refined on its own.
    Both,
}

impl ZoomoutDirection {
    /// True when the forward map `p2p_21` is refined.
    pub fn forward(self) -> bool {
        matches!(self, Self::Forward | Self::Both)
    }

    /// True when the reverse map `p2p_12` is refined.
    pub fn reverse(self) -> bool {
        matches!(self, Self::Reverse | Self::Both)
    }
}

crate::io::names::names_as_text!(
    ZoomoutDirection,
    names: [Forward => "forward", Reverse => "reverse", Both => "both"],
    aliases: [],
    unknown: |s| format!(
        "unknown ZoomOut direction '{}': use forward, reverse or both",
        s.trim().to_ascii_lowercase()
    ),
);

/// One refined direction: the functional map and its point map.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// Forward: `C` (`k2 x k1`, shape 1 to shape 2). Reverse: `C_12` (`k1 x k2` as a
    /// [`FunctionalMap`] whose "shape 1" is shape 2), carrying functions on shape 2 to
    /// shape 1.
    pub fmap: FunctionalMap,
    /// Forward: `p2p_21` (for each vertex of shape 2 a vertex of shape 1). Reverse:
    /// `p2p_12` (for each vertex of shape 1 a vertex of shape 2).
    pub p2p: Vec<usize>,
}

/// What [`zoomout`] returns: the directions asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Zoomed {
    /// The forward refinement (when [`ZoomoutDirection::forward`]).
    pub forward: Option<Refined>,
    /// The reverse refinement (when [`ZoomoutDirection::reverse`]).
    pub reverse: Option<Refined>,
}

/// Refines `c` (`k2 x k1`) to `k_final x k_final` in steps of `step` in the `direction`s
/// asked for (see the module docs). Both bases must hold `max(k_final, k1, k2)` pairs; a
/// `k_final` no larger than the map's sizes refines nothing and returns the point maps of
/// `c` (forward) and `c^T` (reverse).
pub fn zoomout(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    k_final: usize,
    step: usize,
    direction: ZoomoutDirection,
) -> Result<Zoomed, CorrespondenceError> {
    let forward = direction
        .forward()
        .then(|| refine(c, (basis1, 1), (basis2, 2), k_final, step))
        .transpose()?;
    let reverse = direction
        .reverse()
        .then(|| refine(&c.transpose(), (basis2, 2), (basis1, 1), k_final, step))
        .transpose()?;
    Ok(Zoomed { forward, reverse })
}

/// One direction: `from` is the basis of the map's columns with its shape number (for the
/// errors), `to` that of its rows.
fn refine(
    c: &FunctionalMap,
    from: (BasisView<'_>, usize),
    to: (BasisView<'_>, usize),
    k_final: usize,
    step: usize,
) -> Result<Refined, CorrespondenceError> {
    let k1_final = k_final.max(c.k1);
    let k2_final = k_final.max(c.k2);
    if step == 0 && (c.k1 < k1_final || c.k2 < k2_final) {
        return Err(CorrespondenceError::InvalidParameter(
            "the ZoomOut step must be >= 1".into(),
        ));
    }
    let basis1 = truncate(from.0, k1_final, from.1)?;
    let basis2 = truncate(to.0, k2_final, to.1)?;
    let mut cur = c.clone();
    // Each iteration's map is the next one's guess: the search is exact either way.
    let mut prev: Option<Vec<usize>> = None;
    while cur.k1 < k1_final || cur.k2 < k2_final {
        let p2p = fmap_to_p2p_hinted(&cur, basis1, basis2, false, prev.as_deref())?;
        let k1 = (cur.k1 + step).min(k1_final);
        let k2 = (cur.k2 + step).min(k2_final);
        cur = p2p_to_fmap(&p2p, basis1, basis2, k1, k2)?;
        prev = Some(p2p);
    }
    let p2p = fmap_to_p2p_hinted(&cur, basis1, basis2, false, prev.as_deref())?;
    Ok(Refined { fmap: cur, p2p })
}

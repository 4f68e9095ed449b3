//! Phase timings of the Krylov-Schur eigensolver, for tuning: with the environment
//! variable `SPECTRAL_MESH_EIG_TIMINGS=1`, the wall seconds spent in each phase are summed
//! and printed to stderr when a solve succeeds (a failed attempt's time goes into the
//! next report), with the number of block expansions and of operator applications
//! (solves, columns). The totals are process-wide, so solves running at the same time
//! mix. Off by default (one cached flag test per phase). The faces read [`enabled`] to
//! print their own stages (the CLI's `eigs`: read, operators, solve, check, write).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The phases that are timed.
#[derive(Clone, Copy, Debug)]
pub(super) enum Phase {
    /// The fill-reducing ordering and symbolic analysis of `S - sigma B`.
    Ordering,
    /// The numeric factorization of `S - sigma B`.
    Factor,
    /// `Op Q = K^-1 B Q`: the sparse product and the multi-right-hand-side solve.
    Op,
    /// The Lanczos step (known coefficients, `Q^T B W`).
    Local,
    /// Gram products `V^T B W` of the full passes (with the `B W` they need).
    Gram,
    /// Updates `W -= V C` of the full passes.
    Update,
    /// SVQB within the new block.
    Svqb,
    /// Projected eigenproblems at restarts.
    Eig,
    /// Ritz vectors `V Y` at restarts.
    Rotate,
    /// Residual estimates at restarts (`K Q` and its Gram matrix).
    Estimate,
    /// True residuals of the candidate pairs.
    Residual,
    /// The start block (random, `Op` applied, orthonormalized).
    Start,
    /// `B W` and the column norms of a new block before its orthogonalization.
    Norms,
    /// The known null space: finding the components, projecting blocks against it.
    Deflate,
    /// The orthogonality report of the returned vectors (`max |X^T B X - I|`).
    Check,
    /// The start vectors from a coarse space (aggregation, Galerkin pencil, its solve).
    Coarse,
}

const NAMES: [&str; 16] = [
    "ordering", "factor", "op", "local", "gram", "update", "svqb", "eig", "rotate", "estimate",
    "residual", "start", "norms", "deflate", "check", "coarse",
];

static TOTALS: [AtomicU64; 16] = [const { AtomicU64::new(0) }; 16];

/// True when `SPECTRAL_MESH_EIG_TIMINGS` is set (not empty, not `0`): the solver then
/// prints its phase timings, and the faces may print their own stages.
pub fn enabled() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| {
        std::env::var("SPECTRAL_MESH_EIG_TIMINGS").is_ok_and(|v| !v.is_empty() && v != "0")
    })
}

/// Runs `f`, adding its wall time to `phase` when timings are on.
#[inline]
pub(super) fn timed<R>(phase: Phase, f: impl FnOnce() -> R) -> R {
    if !enabled() {
        return f();
    }
    let t = Instant::now();
    let r = f();
    add(phase, t.elapsed());
    r
}

/// Adds a measured duration to `phase` (when timings are on).
pub(super) fn add(phase: Phase, d: std::time::Duration) {
    if enabled() {
        let ns = u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
        TOTALS[phase as usize].fetch_add(ns, Ordering::Relaxed);
    }
}

/// Prints and resets the totals (when timings are on), with the operator applications
/// (`solves`, columns) and block expansions of the solve.
pub(super) fn report(expansions: usize, solves: usize) {
    if !enabled() {
        return;
    }
    let parts: Vec<String> = NAMES
        .iter()
        .zip(&TOTALS)
        .map(|(name, t)| {
            let s = t.swap(0, Ordering::Relaxed) as f64 * 1e-9;
            format!("{name}={s:.3}")
        })
        .collect();
    eprintln!(
        "eig timings (s): {} (expansions {expansions}, solves {solves})",
        parts.join(" ")
    );
}

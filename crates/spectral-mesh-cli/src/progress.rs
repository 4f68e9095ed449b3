//! Progress bars on stderr, only when stderr is a terminal.

use std::cell::Cell;
use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};
use spectral_mesh::linalg::EigenProgress;

/// A progress bar that is hidden when stderr is not a terminal.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(what.to_string());
    pb
}

/// The progress of an eigenbasis of `k` pairs: a bar fed by the solver's progress
/// callback, which also keeps the orthogonality error the solver reports when it finishes.
pub struct EigenBar {
    bar: ProgressBar,
    orthogonality: Cell<Option<f64>>,
}

impl EigenBar {
    /// A bar for `k` pairs (hidden unless stderr is a terminal).
    pub fn new(k: usize) -> Self {
        Self {
            bar: bar(k as u64, "eigenpairs"),
            orthogonality: Cell::new(None),
        }
    }

    /// The solver's progress, shown on the bar.
    pub fn update(&self, p: EigenProgress) {
        match p {
            EigenProgress::Dense { .. } => self.bar.set_message("dense eigen"),
            EigenProgress::Factorization { .. } => self.bar.set_message("factoring"),
            EigenProgress::Iteration { converged, .. } => {
                self.bar.set_message("iterating");
                self.bar.set_position(converged as u64);
            }
            EigenProgress::Finished {
                orthogonality_error,
                ..
            } => self.orthogonality.set(Some(orthogonality_error)),
        }
    }

    /// `max |X^T B X - I|` as the solver reported it for the last basis it computed
    /// (`None` when none was computed: the measure is not taken twice).
    pub fn orthogonality(&self) -> Option<f64> {
        self.orthogonality.get()
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

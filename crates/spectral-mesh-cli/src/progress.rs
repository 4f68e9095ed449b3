//! Progress bars on stderr, only when stderr is a terminal.

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
/// callback.
pub struct EigenBar(ProgressBar);

impl EigenBar {
    /// A bar for `k` pairs (hidden unless stderr is a terminal).
    pub fn new(k: usize) -> Self {
        Self(bar(k as u64, "eigenpairs"))
    }

    /// The solver's progress, shown on the bar.
    pub fn update(&self, p: EigenProgress) {
        match p {
            EigenProgress::Dense { .. } => self.0.set_message("dense eigen"),
            EigenProgress::Factorization { .. } => self.0.set_message("factoring"),
            EigenProgress::Iteration { converged, .. } => {
                self.0.set_message("iterating");
                self.0.set_position(converged as u64);
            }
            _ => {}
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

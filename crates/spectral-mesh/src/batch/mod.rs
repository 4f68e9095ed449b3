//! Shape collections: the eigenbasis and descriptors of every shape of a data set, one
//! job per shape, resumable and idempotent. The faces run the jobs (the command line on
//! worker processes, Python on a process pool or a Dask cluster); the job itself, the
//! file layout, the hashes and the summary are here, so that every face writes the same
//! files. Matching over pairs of a collection is [`pairs`] (its own layout and summary).
//!
//! # Layout of the output folder
//! ```text
//! OUT/NAME.npz          the result of a shape (NAME: see BatchInput::name)
//! OUT/NAME.png          its thumbnail, when asked for
//! OUT/NAME.error.json   the failure marker of a shape that failed (no result then)
//! OUT/summary.csv       one row per shape (see summary::COLUMNS)
//! OUT/summary.parquet   the same rows
//! OUT/.spectral-mesh-batch  marks the folder as a batch output folder
//! ```
//! The result `NAME.npz` is a NumPy archive (`numpy.load`): `eigenvalues` `(k,)`,
//! `residuals` `(k,)`; with [`BatchParams::basis`] `eigenvectors` `(n, k)` and the mass
//! matrix (`mass_data`, `mass_indices`, `mass_indptr`, `mass_shape`: SciPy's CSC), so that
//! [`crate::spectral::store::load_npz`] reads it as a basis; `hks` `(n, T)` with
//! `hks_times` `(T,)`, `wks` `(n, E)` with `wks_energies` `(E,)`, `adf` `(n, T)` with
//! `adf_times` `(T,)` when asked; `meta`, JSON as bytes ([`ResultMeta`]: the basis
//! metadata and, under `batch`, the hashes, the parameters, counts and the list of files).
//! The archive holds nothing that changes between runs (no time, no path, no host): the
//! same input and parameters give the same bytes on any machine and any number of
//! threads (the eigensolver's results do not depend on the thread count).
//!
//! Every file is written to a temporary name beside it and renamed into place
//! ([`crate::io::write_atomic_as`], always synced); the result is written last, so its presence means
//! the shape is complete. A run that is killed leaves complete files and possibly
//! temporary ones (`.NAME.npz.tmp-PID-N`), which [`remove_stale_temporaries`] clears at
//! the start of the next run.
//!
//! # Hashes and the rules of a rerun
//! - input hash: BLAKE3 of the input file's bytes (its content, not its name or time:
//!   a copy of the data set elsewhere is recognised; `touch` alone recomputes nothing);
//! - parameter hash: [`BatchParams::hash`] (every parameter, the full eigensolver
//!   parameters and [`RESULT_VERSION`]; not the number of workers or threads).
//!
//! A shape is skipped when its result holds both hashes (and the same result version) and
//! every file it lists exists; recomputed (its files replaced) when either hash differs.
//! A shape that failed leaves `NAME.error.json` with both hashes: the next run reports the
//! same failure without trying again (unless told to retry), and tries again as soon as
//! the input or the parameters change. Failures of the run rather than of the shape
//! (cancelled, a disk error, a worker process that died) leave no marker.

mod inputs;
mod job;
pub mod memory;
pub mod pairs;
mod params;
mod record;
pub mod summary;

use std::path::Path;

pub use inputs::{BatchInput, SCANNED_EXTENSIONS, resolve_inputs};
pub use job::{
    BatchMeta, DescriptorAxes, JobOptions, ResultKey, ResultMeta, Thumbnailer, process_one,
};
pub use pairs::{
    PairJob, PairParams, PairRecord, PairSizes, PairSpec, PairTimings, Pairing, pairs_csv,
    plan_pairs, process_pair, write_pairs_summary,
};
pub use params::{BatchParams, DescriptorParams, RESULT_VERSION, Schedule, SolveParams};
pub use record::{BasisSummary, BatchRecord, InputKind, ShapeCounts, Status};
pub use summary::write_summary;

/// Suffix of a thumbnail after the shape's name.
pub const THUMBNAIL_SUFFIX: &str = ".png";
/// Suffix of a failure marker after the shape's name.
pub const FAILURE_SUFFIX: &str = ".error.json";

/// Errors that stop a batch before or after its jobs (a job's own errors go into its row).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum BatchError {
    /// A parameter is out of range.
    #[error("{key}: {message}")]
    Parameter {
        /// The parameter.
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// An input (file, folder, pattern or manifest line) cannot be resolved.
    #[error("{spec}: {message}")]
    Input {
        /// The input as given.
        spec: String,
        /// What is wrong.
        message: String,
    },
    /// The summary or the output folder could not be written.
    #[error("{0}")]
    Write(String),
}

/// The file that marks a folder as a batch output folder (written by [`prepare_output`]).
pub const MARKER_FILE: &str = ".spectral-mesh-batch";

/// Makes `out` ready for a batch: creates it (and its parents) and writes
/// [`MARKER_FILE`]. Refuses a folder that already holds files but is not a batch output
/// folder (no marker) unless `force`: a batch replaces files by the names of its shapes
/// and must not replace files of the user's that happen to share them.
pub fn prepare_output(out: &Path, force: bool) -> Result<(), BatchError> {
    let shown = out.display();
    std::fs::create_dir_all(out)
        .map_err(|e| BatchError::Write(format!("{shown}: cannot create folder: {e}")))?;
    let marker = out.join(MARKER_FILE);
    if marker.is_file() {
        return Ok(());
    }
    let used = std::fs::read_dir(out)
        .map_err(|e| BatchError::Write(format!("{shown}: cannot list folder: {e}")))?
        .next()
        .is_some();
    if used && !force {
        return Err(BatchError::Write(format!(
            "{shown}: the folder holds files but is not a batch output folder (no {MARKER_FILE}); \
             choose an empty or new folder, or pass --force to write into it"
        )));
    }
    crate::io::write_atomic_durable(&marker, b"spectral-mesh batch output folder\n")
        .map_err(|e| BatchError::Write(e.to_string()))
}

/// Removes the temporary files an interrupted run left in `out` (recursively): hidden
/// files named `.FILE.tmp-PID-N`, as [`crate::io::write_atomic_with`] makes them. Call it
/// before starting the jobs of a run, never while another run writes to `out`. Returns
/// how many were removed.
pub fn remove_stale_temporaries(out: &Path) -> usize {
    fn walk(dir: &Path, removed: &mut usize) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                walk(&p, removed);
            } else if name.starts_with('.')
                && name.contains(".tmp-")
                && std::fs::remove_file(&p).is_ok()
            {
                *removed += 1;
            }
        }
    }
    let mut removed = 0;
    walk(out, &mut removed);
    removed
}

/// The error of a job (a shape's or a pair's) that panicked: the panic's message, asking
/// for a report.
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    let what = panic
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| panic.downcast_ref::<&str>().copied())
        .unwrap_or("unknown panic");
    format!("internal error (please report it): {what}")
}

#[cfg(test)]
mod tests;

//! The row a batch keeps for each shape.

use std::fmt;

/// What happened to a shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Computed and saved by this run.
    Ok,
    /// A result with the same input and parameter hashes was already there: nothing done.
    Skipped,
    /// The shape could not be processed; `error` says why.
    Failed,
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Status::Ok => "ok",
            Status::Skipped => "skipped",
            Status::Failed => "failed",
        })
    }
}

/// What the input was.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InputKind {
    /// A triangle mesh.
    Mesh,
    /// A point cloud (solved with the point-cloud Laplacian).
    Points,
}

impl fmt::Display for InputKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InputKind::Mesh => "mesh",
            InputKind::Points => "points",
        })
    }
}

/// What was read from a shape's file: every count `None` until known (the file could not
/// be read, or the job failed first).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShapeCounts {
    /// Mesh or point cloud.
    pub kind: Option<InputKind>,
    /// Vertices (points).
    pub n: Option<usize>,
    /// Triangles (0 for point clouds).
    pub faces: Option<usize>,
    /// Connected components (of the mesh, or of the point-cloud operator's graph).
    pub components: Option<usize>,
}

/// The eigenbasis a shape was solved for: how many pairs, with which discretization, how
/// accurate.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BasisSummary {
    /// Eigenpairs computed.
    pub k: Option<usize>,
    /// The discretization used (`fem`, ..., `robust` for point clouds).
    pub discretization: String,
    /// Largest relative residual of the eigenpairs.
    pub max_residual: Option<f64>,
}

/// One row of the summary: a small record (a few hundred bytes), what a worker returns
/// for a shape; the heavy results are in the files it names. In JSON the keys of
/// [`ShapeCounts`] and [`BasisSummary`] stand beside the others (the summary's columns).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BatchRecord {
    /// The shape's name in the output folder (see [`super::BatchInput::name`]).
    pub name: String,
    /// The input file as given.
    pub input: String,
    /// Ok, skipped or failed.
    pub status: Status,
    /// True when the row comes from a previous run's files (a result, or the failure
    /// marker of a shape that failed with the same hashes).
    pub reused: bool,
    /// Why it failed (`None` unless failed).
    pub error: Option<String>,
    /// What the file held.
    #[serde(flatten)]
    pub shape: ShapeCounts,
    /// The eigenbasis computed.
    #[serde(flatten)]
    pub basis: BasisSummary,
    /// Wall seconds spent on this shape by this run (reading, solving, writing; for a
    /// skipped shape, the check).
    pub seconds: f64,
    /// Peak resident memory of the process while it worked on this shape, in bytes (Linux
    /// only; exact when the process works on one shape at a time, as the command line's
    /// and Dask's single-task workers do). `None` when unknown or skipped.
    pub peak_memory_bytes: Option<u64>,
    /// Files written for the shape, relative to the output folder, the result last.
    pub outputs: Vec<String>,
    /// BLAKE3 (hex) of the input file's bytes (`None` when it could not be read).
    pub input_hash: Option<String>,
    /// [`super::BatchParams::hash`] of the parameters.
    pub params_hash: String,
    /// What the reader skipped or guessed, one sentence each.
    pub warnings: Vec<String>,
}

impl BatchRecord {
    /// An empty row for `name` (failed until filled in).
    pub fn new(name: &str, input: &str, params_hash: &str) -> Self {
        Self {
            name: name.to_string(),
            input: input.to_string(),
            status: Status::Failed,
            reused: false,
            error: None,
            shape: ShapeCounts::default(),
            basis: BasisSummary::default(),
            seconds: 0.0,
            peak_memory_bytes: None,
            outputs: Vec::new(),
            input_hash: None,
            params_hash: params_hash.to_string(),
            warnings: Vec::new(),
        }
    }

    /// A failed row with `message` (e.g. a worker that died: made by the face that saw it).
    pub fn failed(name: &str, input: &str, params_hash: &str, message: impl Into<String>) -> Self {
        Self {
            error: Some(message.into()),
            ..Self::new(name, input, params_hash)
        }
    }
}

//! What can go wrong, as a plain Rust value (built on any thread, without the GIL), and
//! its conversion to the Python exception the package documents:
//!
//! | failure | Python exception |
//! | --- | --- |
//! | bad arrays, parameters, requests | `ValueError` |
//! | a file that cannot be opened or written | `OSError` (`FileNotFoundError`, `PermissionError`, ... picked from the errno) |
//! | a mesh or basis file whose content is invalid | `spectral_mesh.MeshFileError` (an `OSError`) |
//! | the eigensolver did not converge | `spectral_mesh.NoConvergenceError` (a `RuntimeError`) |
//! | another numerical failure (a factorization) | `spectral_mesh.SolverError` (a `RuntimeError`) |
//! | a cancelled computation | `KeyboardInterrupt` |
//! | a bug (a Rust panic) | `spectral_mesh.InternalError` (a `RuntimeError`) |
//!
//! The package's own exception classes live in the pure-Python module
//! `spectral_mesh._errors` (so they can inherit from two built-in classes) and are looked up
//! when an error is raised.

use pyo3::call::PyCallArgs;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use spectral_mesh::analysis::AnalysisError;
use spectral_mesh::io::IoError;
use spectral_mesh::mesh::MeshError;
use spectral_mesh::spectral::eigenbasis::EigenError;
use spectral_mesh::spectral::store::StoreError;

/// A failure, converted to a Python exception by [`Failure::into_pyerr`].
#[derive(Debug)]
pub enum Failure {
    /// Bad input: `ValueError`.
    Value(String),
    /// A file could not be opened, read or written: `OSError(errno, strerror, path)`, whose
    /// text is `[Errno N] cannot ACTION: REASON: 'PATH'`.
    Io {
        /// The OS error number, when there is one.
        errno: Option<i32>,
        /// `cannot ACTION: REASON` (the library's message without the path).
        message: String,
        /// The file.
        path: String,
    },
    /// A file's content is invalid: `MeshFileError`.
    Format {
        /// The library's message (`path:line: problem`).
        message: String,
        /// The file.
        path: String,
        /// 1-based line, when known.
        line: Option<usize>,
    },
    /// The eigensolver stopped before convergence: `NoConvergenceError`.
    NoConvergence(String),
    /// Another numerical failure: `SolverError`.
    Solver(String),
    /// The computation was cancelled: `KeyboardInterrupt`.
    Cancelled,
    /// A bug: `InternalError`.
    Internal(String),
    /// An exception raised by Python code the computation called (a progress callback).
    Python(PyErr),
}

impl Failure {
    /// A `ValueError` with `message`.
    pub fn value(message: impl Into<String>) -> Self {
        Failure::Value(message.into())
    }

    /// The Python exception (needs the GIL to look up the package's classes).
    pub fn into_pyerr(self, py: Python<'_>) -> PyErr {
        match self {
            Failure::Value(m) => PyValueError::new_err(m),
            Failure::Io {
                errno: Some(errno),
                message,
                path,
            } => PyOSError::new_err((errno, message, path)),
            Failure::Io {
                errno: None,
                message,
                path,
            } => PyOSError::new_err(format!("{path}: {message}")),
            Failure::Format {
                message,
                path,
                line,
            } => own(py, "MeshFileError", (message, path, line)),
            Failure::NoConvergence(m) => own(py, "NoConvergenceError", (m,)),
            Failure::Solver(m) => own(py, "SolverError", (m,)),
            Failure::Cancelled => PyKeyboardInterrupt::new_err("the computation was cancelled"),
            Failure::Python(e) => e,
            Failure::Internal(m) => own(
                py,
                "InternalError",
                (format!(
                    "internal error in spectral-mesh (please report it): {m}"
                ),),
            ),
        }
    }
}

/// An instance of the package's exception class `name` (from `spectral_mesh._errors`).
fn own<'py, A: PyCallArgs<'py>>(py: Python<'py>, name: &str, args: A) -> PyErr {
    match py
        .import("spectral_mesh._errors")
        .and_then(|m| m.getattr(name))
        .and_then(|cls| cls.call1(args))
    {
        Ok(exc) => PyErr::from_value(exc),
        Err(e) => e,
    }
}

impl From<MeshError> for Failure {
    fn from(e: MeshError) -> Self {
        Failure::Value(e.to_string())
    }
}

impl From<IoError> for Failure {
    fn from(e: IoError) -> Self {
        match e {
            IoError::Io {
                path,
                action,
                source,
            } => Failure::Io {
                errno: source.raw_os_error(),
                message: format!("cannot {action}: {}", os_text(&source)),
                path,
            },
            IoError::Invalid { ref path, line, .. } => Failure::Format {
                message: e.to_string(),
                path: path.clone(),
                line,
            },
            IoError::UnknownFormat { ref path, .. } => Failure::Format {
                message: e.to_string(),
                path: path.clone(),
                line: None,
            },
        }
    }
}

impl From<EigenError> for Failure {
    fn from(e: EigenError) -> Self {
        match e {
            EigenError::TooMany { .. }
            | EigenError::Zero
            | EigenError::DirichletOutOfRange { .. } => Failure::Value(e.to_string()),
            EigenError::NoConvergence { .. } => Failure::NoConvergence(e.to_string()),
            EigenError::Numerical(_) => Failure::Solver(e.to_string()),
            EigenError::Cancelled => Failure::Cancelled,
        }
    }
}

impl From<AnalysisError> for Failure {
    fn from(e: AnalysisError) -> Self {
        match e {
            AnalysisError::Eigen(e) => e.into(),
            AnalysisError::NoBasis => Failure::Internal(e.to_string()),
            other => Failure::Value(other.to_string()),
        }
    }
}

impl From<StoreError> for Failure {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Io { path, source } => Failure::Io {
                errno: source.raw_os_error(),
                message: os_text(&source),
                path,
            },
            StoreError::Format { ref path, .. } => Failure::Format {
                message: e.to_string(),
                path: path.clone(),
                line: None,
            },
            StoreError::Eigen(e) => e.into(),
        }
    }
}

impl From<spectral_mesh_render::FigureError> for Failure {
    fn from(e: spectral_mesh_render::FigureError) -> Self {
        use spectral_mesh_render::FigureError as F;
        match e {
            F::Write(w) => Failure::Io {
                errno: w.source.raw_os_error(),
                message: format!("cannot {}: {}", w.action, os_text(&w.source)),
                path: w.path,
            },
            F::Io(io) => io.into(),
            other => Failure::Value(other.to_string()),
        }
    }
}

/// An OS error's text without Rust's " (os error N)" suffix (the errno is shown by
/// Python).
fn os_text(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.rfind(" (os error ") {
        Some(i) if s.ends_with(')') => s[..i].to_string(),
        _ => s,
    }
}

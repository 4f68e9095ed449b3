//! Every computation runs here: on a worker thread, with the GIL released, watched by the
//! calling thread for signals.
//!
//! - **GIL**: the calling thread waits with the GIL released, so other Python threads run
//!   (and call the library) meanwhile; the work itself never touches Python objects.
//! - **Threads**: the work uses the library's rayon pool (all cores unless
//!   `RAYON_NUM_THREADS` says otherwise). The heavy computations ([`run_heavy`]: the
//!   module-level solves, building an `Analysis` or a geodesic solver, an `Analysis`'
//!   eigensolve for more pairs than it holds, the learning operators) on
//!   [`POOL_MIN_ROWS`] rows or more run as a job of a pool of that size made for the
//!   call: their parallel steps are joined on a pool thread instead of being handed from
//!   the worker to the global pool one by one and waited for. 26k vertices, k = 50,
//!   medians of alternating runs of the two builds: `eigenbasis` 0.654 -> 0.573 s quiet (8
//!   runs), 1.72 -> 1.28 s with two busy processes on the 2 cores (6 runs);
//!   `Analysis(V, F).basis(50)` 0.589 -> 0.522 s. The pool's threads end with the call
//!   (it waits for them, and for its worker thread), so the memory their heaps hold goes
//!   back to the system (running on the global pool instead was as fast, but its threads
//!   stay, and with them 46 MiB after a 10k-vertex k = 100 solve). Only the call's own
//!   jobs run in its pool: a thread waiting in a join never takes up another call's work.
//! - **Ctrl-C**: every [`POLL`] the calling thread takes the GIL back for a moment and
//!   runs Python's signal handlers (`PyErr_CheckSignals`, only effective on the main
//!   thread). When one raises (`KeyboardInterrupt` for Ctrl-C) the work's
//!   [`CancelToken`] is cancelled, the worker is given [`GRACE`] to stop, and the
//!   exception is raised — whether or not the worker has stopped by then: a worker that
//!   has not finishes in the background and its result is dropped (a computation that
//!   checks the token stops at its next check).
//! - **Panics** are caught on the worker and become `spectral_mesh.InternalError`; they
//!   never unwind into Python.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use pyo3::prelude::*;
use spectral_mesh::CancelToken;
use spectral_mesh::linalg::EigenProgress;

use crate::errors::Failure;
use crate::pyjson;

/// How often the waiting thread checks for signals.
pub const POLL: Duration = Duration::from_millis(50);
/// How long a cancelled worker is waited for before the exception is raised anyway.
pub const GRACE: Duration = Duration::from_millis(500);

/// Runs `work` as described in the module documentation and returns its result, on a
/// thread of its own whose parallel steps go to the global pool: for light work (queries
/// on a held basis), where a pool's threads would cost more than they save.
pub fn run<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&CancelToken) -> Result<T, Failure> + Send + 'static,
{
    run_on(py, false, work)
}

/// Below this many rows (vertices, points) a heavy call runs as [`run`] does: starting a
/// pool's threads costs more than its parallel steps gain. Measured per call (2 cores):
/// `eigenbasis(k = 20)` 2.9 -> 3.9 ms at 162 vertices, 10.7 -> 10.1 ms at 642, 32.7 ->
/// 30.6 ms at 2,562; `laplacian` 0.26 -> 0.38 ms at 162 and 1.37 -> 1.64 ms at 2,562.
pub const POOL_MIN_ROWS: usize = 4096;

/// [`run`] for heavy work (a factorization, an eigensolve, an assembly) on `rows` rows
/// (vertices or points; `None` when not known before the work starts, as for a file):
/// from [`POOL_MIN_ROWS`] rows, on a rayon pool made for the call (see the module
/// documentation).
pub fn run_heavy<T, F>(py: Python<'_>, rows: Option<usize>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&CancelToken) -> Result<T, Failure> + Send + 'static,
{
    run_on(py, rows.is_none_or(|n| n >= POOL_MIN_ROWS), work)
}

fn run_on<T, F>(py: Python<'_>, in_pool: bool, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&CancelToken) -> Result<T, Failure> + Send + 'static,
{
    let token = CancelToken::new();
    let worker_token = token.clone();
    let (tx, rx) = channel();
    let worker = std::thread::Builder::new()
        .name("spectral-mesh".into())
        .spawn(move || {
            let guarded = move || {
                catch_unwind(AssertUnwindSafe(|| work(&worker_token)))
                    .unwrap_or_else(|payload| Err(Failure::Internal(panic_message(&payload))))
            };
            let out = if in_pool {
                // The pool's usual size (all cores, or `RAYON_NUM_THREADS`), its threads
                // started for the call (not `use_current_thread`: rayon then leaks the
                // pool's registry, about 11 KiB a call, measured); they end with it.
                let (ended_tx, ended) = channel::<()>();
                let pool = rayon::ThreadPoolBuilder::new()
                    .exit_handler(move |_| {
                        let _ = ended_tx.send(());
                    })
                    .build();
                match pool {
                    Ok(pool) => {
                        let threads = pool.current_num_threads();
                        let out = pool.install(guarded);
                        drop(pool);
                        wait_for_ends(&ended, threads);
                        out
                    }
                    Err(_) => guarded(),
                }
            } else {
                guarded()
            };
            // The receiver is gone only when the caller gave up after a signal.
            let _ = tx.send(out);
        })
        .map_err(|e| {
            Failure::Internal(format!("cannot start a worker thread: {e}")).into_pyerr(py)
        })?;
    let mut rx = rx;
    loop {
        // The receiver is moved in and out: it is `Send` but not `Sync`.
        let (got, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match got {
            Ok(out) => {
                // The worker ends right after sending: joined, so that its heap has gone
                // back to the allocator when the call returns (it cannot have panicked:
                // the work's panics are caught).
                py.detach(move || {
                    let _ = worker.join();
                });
                return out.map_err(|f| f.into_pyerr(py));
            }
            Err(RecvTimeoutError::Timeout) => {
                if let Err(signal) = py.check_signals() {
                    token.cancel();
                    let _ = py.detach(move || rx.recv_timeout(GRACE).map(|_| ()));
                    return Err(signal);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Failure::Internal("the worker thread vanished".into()).into_pyerr(py));
            }
        }
    }
}

/// The longest a call waits for its pool's threads to end after its work is done.
const THREADS_END: Duration = Duration::from_millis(200);

/// Waits (at most [`THREADS_END`]) until `threads` pool threads have said they ended on
/// `ended`: a dropped rayon pool ends its threads without waiting for them, and a thread's
/// heap goes back to the allocator (and the memory it freed to the system, mimalloc v2's
/// 10 ms later) only when the thread has ended. Waited for, the memory a solve freed is
/// returned soon after the call rather than whenever the threads happen to end (Python:
/// `test_freed_memory_goes_back_to_the_system_soon_after_a_solve`).
fn wait_for_ends(ended: &std::sync::mpsc::Receiver<()>, threads: usize) {
    let deadline = std::time::Instant::now() + THREADS_END;
    for _ in 0..threads {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        if ended.recv_timeout(left).is_err() {
            return;
        }
    }
}

/// The text of a panic payload.
pub fn panic_message(payload: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// A Python progress callback of an eigensolve, called on the worker thread (which takes
/// the GIL for the call). An exception it raises cancels the computation and is raised
/// in its place.
#[derive(Clone, Default)]
pub struct Progress {
    callback: Option<Arc<Py<PyAny>>>,
    error: Arc<Mutex<Option<PyErr>>>,
}

impl Progress {
    /// Calls `callback` (when given) with a dict per progress event.
    pub fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback: callback.map(Arc::new),
            error: Arc::default(),
        }
    }

    /// Reports one event; cancels `token` when the callback raises.
    pub fn report(&self, event: &EigenProgress, token: &CancelToken) {
        let Some(cb) = &self.callback else { return };
        let mut error = self.error.lock().unwrap_or_else(|p| p.into_inner());
        if error.is_some() {
            return;
        }
        let outcome = Python::attach(|py| -> PyResult<()> {
            // A dict tagged by `stage`, with the event's fields (the library's serde form).
            let event = serde_json::to_value(event)
                .map_err(|e| Failure::Internal(format!("progress event: {e}")).into_pyerr(py))?;
            let d = pyjson::to_py(py, &event)?;
            cb.call1(py, (d,))?;
            Ok(())
        });
        if let Err(e) = outcome {
            *error = Some(e);
            token.cancel();
        }
    }

    /// `result`, or the exception the callback raised.
    pub fn finish<T>(&self, result: Result<T, Failure>) -> Result<T, Failure> {
        let raised = self.error.lock().unwrap_or_else(|p| p.into_inner()).take();
        match raised {
            Some(e) => Err(Failure::Python(e)),
            None => result,
        }
    }
}

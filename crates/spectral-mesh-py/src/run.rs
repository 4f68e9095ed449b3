//! Every computation runs here: as a job of a thread pool of its own, with the GIL
//! released, watched by the calling thread for signals.
//!
//! - **GIL**: the calling thread waits with the GIL released, so other Python threads run
//!   (and call the library) meanwhile; the work itself never touches Python objects.
//! - **Threads**: the work runs on a thread of a rayon pool (all cores unless
//!   `RAYON_NUM_THREADS` says otherwise when the first pool is made), so that the
//!   library's parallel steps (`rayon::join`) start on a thread of the pool and the pool's
//!   other threads take their halves at once (a step started from outside a pool must
//!   wake a pool thread and sleep until it ends). A pool runs **one computation at a
//!   time**: an idle pool is taken for each computation (a new one made when all are
//!   busy) and given back when its work ends. So a thread of the pool that waits in a
//!   join and takes other work meanwhile (as rayon's threads do) only ever takes a part
//!   of the same computation, never another Python thread's call, which could wait for a
//!   lock (an `Analysis`'s basis, say) that the waiting computation holds lower on the
//!   same thread's stack. A pool whose computation was abandoned (Ctrl-C) is given back
//!   only when its work has really ended. In a forked child the parent's pools (whose
//!   threads are not copied by `fork`) are forgotten and new ones made.
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
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use pyo3::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};
use spectral_mesh::CancelToken;
use spectral_mesh::linalg::EigenProgress;

use crate::errors::Failure;
use crate::pyjson;

/// How often the waiting thread checks for signals.
pub const POLL: Duration = Duration::from_millis(50);
/// How long a cancelled worker is waited for before the exception is raised anyway.
pub const GRACE: Duration = Duration::from_millis(500);

/// The idle pools, and the process that made them (a forked child has their handles but
/// not their threads).
struct Idle {
    pid: u32,
    pools: Vec<Arc<ThreadPool>>,
}

static IDLE: Mutex<Idle> = Mutex::new(Idle {
    pid: 0,
    pools: Vec::new(),
});

/// The threads of every pool: fixed when the first pool is made (rayon's default then:
/// `RAYON_NUM_THREADS`, else the cores).
static THREADS: OnceLock<usize> = OnceLock::new();

/// The idle pools, locked (only to take or give back one: never across a computation).
fn idle() -> std::sync::MutexGuard<'static, Idle> {
    IDLE.lock().unwrap_or_else(|p| p.into_inner())
}

/// An idle pool, or a new one when every pool is busy.
fn take_pool() -> Result<Arc<ThreadPool>, Failure> {
    {
        let mut idle = idle();
        let pid = std::process::id();
        if idle.pid != pid {
            // A fork's child: the parent's pools have no threads here. Their handles are
            // leaked, not dropped: dropping one would signal threads that do not exist.
            std::mem::forget(std::mem::take(&mut idle.pools));
            idle.pid = pid;
        }
        if let Some(pool) = idle.pools.pop() {
            return Ok(pool);
        }
    }
    let mut builder = ThreadPoolBuilder::new()
        .thread_name(|i| format!("spectral-mesh-{i}"))
        // A panic escaping a job (none should: the work's is caught) must not abort.
        .panic_handler(|_| {});
    if let Some(&n) = THREADS.get() {
        builder = builder.num_threads(n);
    }
    let pool = builder
        .build()
        .map_err(|e| Failure::Internal(format!("cannot start the worker threads: {e}")))?;
    let _ = THREADS.set(pool.current_num_threads());
    Ok(Arc::new(pool))
}

/// Makes `pool` idle again (when this process made it).
fn give_back(pool: Arc<ThreadPool>) {
    let mut idle = idle();
    if idle.pid == std::process::id() {
        idle.pools.push(pool);
    } else {
        std::mem::forget(pool);
    }
}

/// The number of threads a computation uses (a pool is made if none was yet).
pub fn threads() -> Result<usize, Failure> {
    if let Some(&n) = THREADS.get() {
        return Ok(n);
    }
    let pool = take_pool()?;
    let n = pool.current_num_threads();
    give_back(pool);
    Ok(n)
}

/// Runs `work` as described in the module documentation and returns its result.
pub fn run<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&CancelToken) -> Result<T, Failure> + Send + 'static,
{
    let token = CancelToken::new();
    let worker_token = token.clone();
    let (tx, rx) = channel();
    let pool = take_pool().map_err(|f| f.into_pyerr(py))?;
    let own = pool.clone();
    pool.spawn(move || {
        let out = catch_unwind(AssertUnwindSafe(|| work(&worker_token)))
            .unwrap_or_else(|payload| Err(Failure::Internal(panic_message(&payload))));
        // Idle again before the result is sent: the caller's next computation finds it.
        give_back(own);
        // The receiver is gone only when the caller gave up after a signal.
        let _ = tx.send(out);
    });
    drop(pool);
    let mut rx = rx;
    loop {
        // The receiver is moved in and out: it is `Send` but not `Sync`.
        let (got, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match got {
            Ok(out) => return out.map_err(|f| f.into_pyerr(py)),
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

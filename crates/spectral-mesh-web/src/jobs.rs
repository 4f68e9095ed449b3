//! Eigenbasis jobs: a queue with a bounded number running, memory admission, cancel,
//! and the rules that stop a job nobody wants any more.
//!
//! One job per mesh (the page shows one basis per mesh; the status endpoint is per
//! mesh). A request for a basis:
//! - is answered at once (200, `done`) when the analysis already holds `k` pairs;
//! - joins the job of the same analysis when it asks for at most the same `k`;
//! - otherwise supersedes the mesh's job (queued: removed; running: its token is
//!   cancelled, the eigensolver stops within a fraction of a second; the factorization
//!   itself is not interrupted) and is queued.
//!
//! The queue is first come, first served. Its head starts when fewer than `max_jobs`
//! run and its estimated peak memory (the library's
//! [`spectral_mesh::analysis::Analysis::basis_peak_bytes`]) can be reserved from the server's
//! budget (least recently used cache entries not in use are evicted for it); otherwise
//! it waits. A request whose estimate alone exceeds the budget, or whose result could
//! not stay in the cache, is refused (422) with the figures.
//!
//! A job stops computing when:
//! - it is superseded (above), or cancelled (`DELETE /api/mesh/{id}/basis`);
//! - its client went away: nobody asked for its status (or for it) for
//!   `job_idle_seconds` (the page polls every 150 ms while it waits; a closed tab stops
//!   polling): state `cancelled`;
//! - it ran longer than `job_seconds`: state `error`;
//! - its client moved on: a basis request carrying the same `X-Client-Id` header for
//!   another mesh cancels the client's earlier job (if no other client joined it).

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde::Serialize;
use spectral_mesh::analysis::{Analysis, AnalysisError};
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::spectral::eigenbasis::EigenError;

use crate::cache::Shortfall;
use crate::entries::{AnalysisKey, Reservation};
use crate::limits::mib;

// ---------- jobs ----------

/// State of the eigenbasis computation of one mesh, as the status endpoint reports it.
#[derive(Debug, Clone, Serialize)]
pub struct Job {
    /// `idle`, `queued`, `running`, `done`, `error` or `cancelled`.
    pub state: String,
    /// Discretization.
    pub laplacian: String,
    /// Unit-area normalisation.
    pub normalize: bool,
    /// Pairs asked for.
    pub k: usize,
    /// Pairs the analysis holds now (at least `k` once done).
    pub held_k: usize,
    /// 0..=1.
    pub progress: f64,
    /// Last progress or error message.
    pub message: String,
    /// Seconds since the request (or until it finished).
    pub seconds: f64,
    /// Place in the queue while queued (1 = next).
    pub queue_position: Option<usize>,
    /// Estimated peak memory of the computation, in bytes (reserved while it runs).
    pub estimate_bytes: usize,
}

impl Job {
    /// The job of a mesh nobody asked a basis for.
    pub fn idle() -> Self {
        Self {
            state: "idle".into(),
            laplacian: String::new(),
            normalize: true,
            k: 0,
            held_k: 0,
            progress: 0.0,
            message: "no eigenbasis requested yet".into(),
            seconds: 0.0,
            queue_position: None,
            estimate_bytes: 0,
        }
    }

    fn new(key: &AnalysisKey, k: usize, held_k: usize, state: &str, message: String) -> Self {
        Self {
            state: state.into(),
            laplacian: key.laplacian.name().into(),
            normalize: key.normalize,
            k,
            held_k,
            progress: if state == "done" { 1.0 } else { 0.0 },
            message,
            seconds: 0.0,
            queue_position: None,
            estimate_bytes: 0,
        }
    }

    /// True while queued or running.
    pub fn active(&self) -> bool {
        self.state == "queued" || self.state == "running"
    }
}

/// A job and what the server needs to control it.
struct Slot {
    job: Job,
    /// Which request this is (a finished or cancelled computation only updates its own).
    serial: u64,
    cancel: CancelToken,
    /// The analysis being computed, held while queued or running (so that field
    /// requests find it even if the cache evicted it), dropped when done.
    analysis: Option<Arc<Analysis>>,
    key: AnalysisKey,
    created: Instant,
    /// Last status request or basis request for it.
    seen: Instant,
    started: Option<Instant>,
    /// Clients (`X-Client-Id`) that asked for it; `anonymous` when one did without.
    clients: Vec<String>,
    anonymous: bool,
    /// Why it was stopped: (state, message) to report once the computation returns.
    stop: Option<(&'static str, String)>,
}

#[derive(Default)]
struct Inner {
    slots: HashMap<String, Slot>,
    /// (mesh id, serial) in arrival order; entries whose slot moved on are skipped.
    queue: VecDeque<(String, u64)>,
    /// Computations running (superseded ones included until they return).
    running: usize,
    serial: u64,
    /// Jobs stopped because a newer request replaced them (same mesh, or same client on
    /// another mesh), since the server started.
    superseded: u64,
    /// Jobs cancelled for any reason (superseded, DELETE, abandoned, mesh unloaded).
    cancelled: u64,
}

/// The jobs of the server.
#[derive(Default)]
pub struct Jobs {
    inner: Mutex<Inner>,
}

/// A basis request, checked by the handler.
pub struct Submit {
    /// Mesh id.
    pub id: String,
    /// The analysis.
    pub key: AnalysisKey,
    /// Pairs.
    pub k: usize,
    /// The analysis (created if need be).
    pub analysis: Arc<Analysis>,
    /// [`Analysis::basis_peak_bytes`].
    pub estimate: usize,
    /// `X-Client-Id`, if sent.
    pub client: Option<String>,
}

/// What became of a basis request.
pub enum Submitted {
    /// The analysis holds enough pairs (200).
    Done(Job),
    /// Queued, running or joined (202).
    Accepted(Job),
    /// The queue is full (503).
    QueueFull(String),
}

impl Inner {
    fn queued(&self) -> usize {
        self.slots
            .values()
            .filter(|s| s.job.state == "queued")
            .count()
    }

    fn position(&self, id: &str, serial: u64) -> Option<usize> {
        self.queue
            .iter()
            .filter(|(i, s)| {
                self.slots
                    .get(i)
                    .is_some_and(|slot| slot.serial == *s && slot.job.state == "queued")
            })
            .position(|(i, s)| i == id && *s == serial)
            .map(|p| p + 1)
    }

    fn report(&self, id: &str) -> Option<Job> {
        let slot = self.slots.get(id)?;
        let mut job = slot.job.clone();
        job.seconds = match (slot.started, job.active()) {
            (_, true) => slot.created.elapsed().as_secs_f64(),
            _ => job.seconds,
        };
        job.queue_position = if job.state == "queued" {
            self.position(id, slot.serial)
        } else {
            None
        };
        Some(job)
    }

    /// Stops the slot's job: a queued one at once, a running one when its computation
    /// returns (its token is cancelled now). True when it was active and not already
    /// being stopped.
    fn stop(slot: &mut Slot, state: &'static str, message: String) -> bool {
        let active = slot.job.active() && slot.stop.is_none();
        match slot.job.state.as_str() {
            "queued" => {
                slot.job.state = state.into();
                slot.job.message = message;
                slot.job.seconds = slot.created.elapsed().as_secs_f64();
                slot.analysis = None;
            }
            "running" => {
                slot.cancel.cancel();
                slot.job.message = format!("stopping: {message}");
                slot.stop = Some((state, message));
            }
            _ => {}
        }
        active
    }
}

impl Jobs {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The job of mesh `id` (marks it as still wanted).
    pub fn status(&self, id: &str) -> Job {
        let mut g = self.lock();
        if let Some(slot) = g.slots.get_mut(id) {
            slot.seen = Instant::now();
        }
        g.report(id).unwrap_or_else(Job::idle)
    }

    /// The job of mesh `id` without marking it.
    pub fn peek(&self, id: &str) -> Option<Job> {
        self.lock().report(id)
    }

    /// The analysis a queued or running job of `key` holds.
    pub fn analysis_of(&self, key: &AnalysisKey) -> Option<Arc<Analysis>> {
        self.lock()
            .slots
            .get(&key.id)
            .filter(|slot| &slot.key == key)
            .and_then(|slot| slot.analysis.clone())
    }

    /// Counts for `/api/health`: (running, queued).
    pub fn counts(&self) -> (usize, usize) {
        let g = self.lock();
        (g.running, g.queued())
    }

    /// Totals since the server started, for `/api/health`: (superseded, cancelled). A
    /// superseded job is one a newer basis request replaced (the same mesh with other
    /// parameters, or the same `X-Client-Id` on another mesh); cancelled counts those and
    /// every other cancel (DELETE, abandoned, mesh unloaded).
    pub fn totals(&self) -> (u64, u64) {
        let g = self.lock();
        (g.superseded, g.cancelled)
    }

    /// Forgets the jobs of meshes no longer loaded (stopping the active ones).
    pub fn forget(&self, keep: impl Fn(&str) -> bool) {
        let mut g = self.lock();
        let gone: Vec<String> = g.slots.keys().filter(|id| !keep(id)).cloned().collect();
        let mut stopped = 0;
        for id in gone {
            if let Some(slot) = g.slots.get_mut(&id) {
                if slot.job.active() {
                    stopped += u64::from(Inner::stop(
                        slot,
                        "cancelled",
                        "the mesh was unloaded".into(),
                    ));
                } else {
                    g.slots.remove(&id);
                }
            }
        }
        g.cancelled += stopped;
    }

    /// Cancels the job of mesh `id` (DELETE): the job as it is then.
    pub fn cancel(&self, id: &str) -> Option<Job> {
        let mut g = self.lock();
        let slot = g.slots.get_mut(id)?;
        slot.seen = Instant::now();
        let stopped = Inner::stop(slot, "cancelled", "cancelled by request".into());
        g.cancelled += u64::from(stopped);
        g.report(id)
    }

    /// Handles a basis request (see the module documentation) with at most `max_queued`
    /// requests waiting; call [`pump`] after.
    pub fn submit(&self, max_queued: usize, req: Submit) -> Submitted {
        let mut g = self.lock();
        let held = req.analysis.held_k();
        let now = Instant::now();
        if held >= req.k {
            let job = Job::new(
                &req.key,
                req.k,
                held,
                "done",
                format!("held ({held} pairs)"),
            );
            // A finished status is replaced; an active job for other parameters goes on.
            if g.slots.get(&req.id).is_none_or(|j| !j.job.active()) {
                g.serial += 1;
                let serial = g.serial;
                g.slots.insert(
                    req.id.clone(),
                    Slot {
                        job: job.clone(),
                        serial,
                        cancel: CancelToken::new(),
                        analysis: None,
                        key: req.key,
                        created: now,
                        seen: now,
                        started: None,
                        clients: Vec::new(),
                        anonymous: true,
                        stop: None,
                    },
                );
            }
            return Submitted::Done(job);
        }
        if let Some(slot) = g.slots.get_mut(&req.id)
            && slot.job.active()
        {
            if slot.key == req.key && slot.job.k >= req.k && slot.stop.is_none() {
                slot.seen = now;
                match &req.client {
                    Some(c) if !slot.clients.contains(c) => slot.clients.push(c.clone()),
                    Some(_) => {}
                    None => slot.anonymous = true,
                }
                let id = req.id.clone();
                return Submitted::Accepted(g.report(&id).unwrap_or_else(Job::idle));
            }
            let stopped = Inner::stop(
                slot,
                "cancelled",
                format!(
                    "superseded by a request for {} k = {} (normalize = {})",
                    req.key.laplacian.name(),
                    req.k,
                    req.key.normalize
                ),
            );
            g.superseded += u64::from(stopped);
            g.cancelled += u64::from(stopped);
        }
        if g.queued() >= max_queued {
            return Submitted::QueueFull(format!(
                "{} eigenbasis requests are waiting, the limit is {max_queued} (--max-queued); try again later",
                g.queued(),
            ));
        }
        // The same client moved on to another mesh: its earlier job goes.
        if let Some(client) = &req.client {
            let mut stopped = 0;
            for (id, slot) in g.slots.iter_mut() {
                if *id != req.id
                    && slot.job.active()
                    && slot.clients.iter().all(|c| c == client)
                    && slot.clients.contains(client)
                    && !slot.anonymous
                {
                    stopped += u64::from(Inner::stop(
                        slot,
                        "cancelled",
                        format!("superseded: the same client asked for mesh {}", req.id),
                    ));
                }
            }
            g.superseded += stopped;
            g.cancelled += stopped;
        }
        g.serial += 1;
        let serial = g.serial;
        let mut job = Job::new(&req.key, req.k, held, "queued", "waiting to start".into());
        job.estimate_bytes = req.estimate;
        g.slots.insert(
            req.id.clone(),
            Slot {
                job,
                serial,
                cancel: CancelToken::new(),
                analysis: Some(req.analysis),
                key: req.key,
                created: now,
                seen: now,
                started: None,
                anonymous: req.client.is_none(),
                clients: req.client.into_iter().collect(),
                stop: None,
            },
        );
        g.queue.push_back((req.id.clone(), serial));
        Submitted::Accepted(g.report(&req.id).unwrap_or_else(Job::idle))
    }

    /// Stops the jobs whose client went away or that ran too long (see the module
    /// documentation). Returns how many were stopped.
    pub fn enforce(&self, job_seconds: u64, idle_seconds: u64) -> usize {
        let mut g = self.lock();
        let (mut stopped, mut abandoned) = (0, 0);
        for slot in g.slots.values_mut() {
            if !slot.job.active() || slot.stop.is_some() {
                continue;
            }
            if slot.seen.elapsed() >= Duration::from_secs(idle_seconds) {
                Inner::stop(
                    slot,
                    "cancelled",
                    format!(
                        "abandoned: nobody asked for its status for {idle_seconds} s (--job-idle-seconds)"
                    ),
                );
                stopped += 1;
                abandoned += 1;
            } else if slot
                .started
                .is_some_and(|t| t.elapsed() >= Duration::from_secs(job_seconds))
            {
                Inner::stop(
                    slot,
                    "error",
                    format!(
                        "stopped after the time limit of {job_seconds} s (--job-seconds): ask for fewer pairs"
                    ),
                );
                stopped += 1;
            }
        }
        g.cancelled += abandoned;
        stopped
    }
}

/// What the queue needs of the server that runs it: the jobs, how many may run at once,
/// the memory budget and the cache an analysis re-enters when its job ends.
pub trait Host: Send + Sync + 'static {
    /// The jobs.
    fn jobs(&self) -> &Jobs;
    /// Eigenbasis computations running at once.
    fn max_jobs(&self) -> usize;
    /// Reserves `bytes` of the memory budget (evicting what may go), or says what is short.
    fn try_reserve(&self, bytes: usize) -> Result<Reservation, Shortfall>;
    /// (Re-)enters an analysis into the cache with its current size.
    fn remember(&self, key: &AnalysisKey, a: &Arc<Analysis>);
}

/// Starts queued jobs while fewer than `max_jobs` run and the head of the queue fits the
/// memory budget.
pub fn pump<H: Host>(s: &Arc<H>) {
    let mut g = s.jobs().lock();
    while g.running < s.max_jobs() {
        let Some((id, serial)) = g.queue.front().cloned() else {
            break;
        };
        let Some(slot) = g
            .slots
            .get(&id)
            .filter(|slot| slot.serial == serial && slot.job.state == "queued")
        else {
            g.queue.pop_front();
            continue;
        };
        let Some(analysis) = slot.analysis.clone() else {
            g.queue.pop_front();
            continue;
        };
        let estimate = slot.job.estimate_bytes;
        let reservation = match s.try_reserve(estimate) {
            Ok(r) => r,
            Err(short) => {
                let message = format!(
                    "waiting for memory: needs about {}, {} of the budget of {} is in use ({} held by the cache, {} reserved by other work)",
                    mib(estimate),
                    mib(short.cached + short.reserved),
                    mib(short.limit),
                    mib(short.cached),
                    mib(short.reserved),
                );
                if let Some(slot) = g.slots.get_mut(&id) {
                    slot.job.message = message;
                }
                break;
            }
        };
        g.queue.pop_front();
        g.running += 1;
        let (key, k, cancel) = {
            let Some(slot) = g.slots.get_mut(&id) else {
                g.running -= 1;
                continue;
            };
            slot.job.state = "running".into();
            slot.job.message = "starting".into();
            slot.started = Some(Instant::now());
            (slot.key.clone(), slot.job.k, slot.cancel.clone())
        };
        let s2 = s.clone();
        let spawned = std::thread::Builder::new()
            .name(format!("spectral-mesh-job-{serial}"))
            .spawn(move || run(&s2, &key, &analysis, k, serial, &cancel, reservation));
        if let Err(e) = spawned {
            g.running -= 1;
            if let Some(slot) = g.slots.get_mut(&id) {
                slot.job.state = "error".into();
                slot.job.message = format!("could not start a thread: {e}");
                slot.analysis = None;
            }
        }
    }
}

/// The progress of an eigenbasis computation as (fraction done, message).
fn progress_of(p: &EigenProgress) -> (f64, String) {
    match p {
        EigenProgress::Dense { n } => (0.1, format!("dense solver, n = {n}")),
        EigenProgress::Factorization { n, .. } => (0.02, format!("factoring, n = {n}")),
        EigenProgress::Iteration {
            iteration,
            converged,
            wanted,
            ..
        } => (
            0.05 + 0.9 * *converged as f64 / (*wanted).max(1) as f64,
            format!("iteration {iteration}: {converged} of {wanted} pairs converged"),
        ),
        EigenProgress::Finished { .. } => (0.99, "finishing".into()),
    }
}

/// The body of a job's thread: computes, reports progress into the job (while it is
/// still the mesh's current one), re-enters the analysis into the cache with its new
/// size, releases the reservation and starts what waits.
fn run<H: Host>(
    s: &Arc<H>,
    key: &AnalysisKey,
    analysis: &Arc<Analysis>,
    k: usize,
    serial: u64,
    cancel: &CancelToken,
    reservation: Reservation,
) {
    let start = Instant::now();
    let mut progress = |p: EigenProgress| {
        let (frac, msg) = progress_of(&p);
        let mut g = s.jobs().lock();
        if let Some(slot) = g.slots.get_mut(&key.id)
            && slot.serial == serial
            && slot.stop.is_none()
        {
            slot.job.progress = frac;
            slot.job.message = msg;
        }
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        analysis.basis(k, &mut progress, cancel)
    }));
    let held = analysis.held_k();
    let (state, message) = match result {
        Ok(Ok(b)) => (
            "done",
            format!("{} pairs in {:.2} s", b.k(), start.elapsed().as_secs_f64()),
        ),
        Ok(Err(AnalysisError::Eigen(EigenError::Cancelled))) => {
            ("cancelled", "cancelled".to_string())
        }
        Ok(Err(e)) => ("error", e.to_string()),
        Err(_) => ("error", "the eigensolver failed unexpectedly".to_string()),
    };
    // The analysis grew (or kept a factorization): account for it before the
    // reservation that covered the growth goes.
    s.remember(key, analysis);
    {
        let mut g = s.jobs().lock();
        g.running -= 1;
        if let Some(slot) = g.slots.get_mut(&key.id)
            && slot.serial == serial
        {
            let (state, message) = match slot.stop.take() {
                Some((st, msg)) if state != "done" => (st, msg),
                _ => (state, message),
            };
            slot.job.state = state.into();
            slot.job.message = message;
            slot.job.held_k = held;
            slot.job.seconds = slot.created.elapsed().as_secs_f64();
            if state == "done" {
                slot.job.progress = 1.0;
            }
            slot.analysis = None;
        }
    }
    drop(reservation);
    pump(s);
}

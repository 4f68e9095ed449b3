//! `spectral-mesh batch INPUTS... --out DIR`: the eigenbasis and descriptors of every shape
//! of a collection, on worker processes, resumable (see the library's `batch` module for
//! the layout, the hashes and the rules of a rerun).
//!
//! Crash isolation: every job runs in a worker process (this binary, `batch --worker`,
//! fed one shape at a time through its stdin and answering one JSON record per line on
//! its stdout). A panic is caught inside the job and becomes a row; a worker that dies
//! (abort, segfault, killed by the out-of-memory killer) is replaced, and the shape it
//! was working on is tried once more on the new worker; a second death makes the shape's
//! row "failed" with the cause, and the batch goes on. The process boundary also makes the
//! peak memory of each row exact (one shape at a time per process). A worker whose parent
//! dies (Ctrl-C, kill) sees its stdin close and exits at once: results are written to a
//! temporary name and renamed, so the next run finds complete files only and resumes.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex, mpsc};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use spectral_mesh::analysis::request::DEFAULT_K;
use spectral_mesh::batch::{
    BatchError, BatchInput, BatchParams, BatchRecord, DescriptorParams, JobOptions, Schedule,
    SolveParams, Status, prepare_output, process_one, remove_stale_temporaries, resolve_inputs,
    write_summary,
};
use spectral_mesh::operators::Laplacian;
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh_render::Thumbnails;

use crate::engine::CloudArgs;

/// How many times a shape is given to a worker that then dies before it is reported
/// failed.
const ATTEMPTS: u32 = 2;

/// Test hook: a worker aborts (as a crash would) when it is given the shape of this name.
const TEST_ABORT_ENV: &str = "SPECTRAL_MESH_BATCH_TEST_ABORT";

/// Arguments of `batch`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Inputs: mesh or point-cloud files, folders (scanned recursively for .off, .obj,
    /// .ply, .stl, .xyz, .pts), glob patterns (quote them: 'data/**/*.ply'), or @FILE, a
    /// manifest listing one input per line.
    #[arg(required_unless_present = "worker")]
    pub inputs: Vec<String>,
    /// Output folder: one result per shape (NAME.npz), summary.csv and summary.parquet.
    #[arg(long, short = 'o', required_unless_present = "worker")]
    pub out: Option<PathBuf>,
    /// Number of eigenpairs per shape (the smallest eigenvalues).
    #[arg(long, short = 'k', default_value_t = DEFAULT_K)]
    pub k: usize,
    /// Discretization of meshes: cot, voronoi-cot, fem, mixed-voronoi, uniform (point
    /// clouds always use the robust point-cloud Laplacian).
    #[arg(long, default_value_t = spectral_mesh::batch::BatchParams::default().solve.laplacian)]
    pub laplacian: Laplacian,
    /// Target relative residual of every eigenpair.
    #[arg(long, default_value_t = EigenParams::default().tolerance)]
    pub tolerance: f64,
    /// Analyse each shape as given instead of scaled to unit area (the default scaling
    /// makes eigenvalues and times comparable across shapes of different sizes).
    #[arg(long)]
    pub no_normalize: bool,
    /// Save the eigenvalues (and descriptors) only, not the eigenvectors and mass.
    #[arg(long)]
    pub eigenvalues_only: bool,
    #[command(flatten)]
    pub descriptors: DescriptorArgs,
    /// A PNG thumbnail of this many pixels a side per mesh (the first non-constant
    /// eigenvector).
    #[arg(long, value_name = "PIXELS")]
    pub thumbnail: Option<u32>,
    /// Geodesic distances (heat method, mesh units) from N farthest-point samples per mesh
    /// (the first at the vertex of largest x): arrays `geodesic` (n x N, inf where a
    /// sample cannot reach) and `geodesic_sources`.
    #[arg(long, value_name = "N")]
    pub geodesic: Option<usize>,
    /// Worker processes, each working on one shape at a time (default: the number of
    /// cores, at most the number of shapes). Lower it when large meshes do not fit in
    /// memory side by side.
    #[arg(long, short = 'j')]
    pub jobs: Option<usize>,
    /// Threads of each worker (default: the cores divided among the workers, at least 1).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Try again the shapes that failed in an earlier run with the same input and
    /// parameters (by default their failure is reported again without new work).
    #[arg(long)]
    pub retry_failed: bool,
    /// Write into a folder that holds other files (not made by a batch).
    #[arg(long, short = 'f')]
    pub force: bool,
    // The point-cloud Laplacian's parameters, for the point clouds of the collection
    // (its meshes have no use for them, and a collection may hold both: no error).
    #[command(flatten)]
    pub cloud: CloudArgs,
    /// Internal: run as a worker process of a batch (jobs on stdin, records on stdout).
    #[arg(long, hide = true)]
    pub worker: bool,
}

/// The point descriptors each shape's result holds (none unless asked for).
#[derive(Debug, clap::Args)]
pub struct DescriptorArgs {
    /// Heat kernel signature: auto:N (N times from each spectrum) or a list t1,t2,...
    #[arg(long, value_name = "TIMES")]
    pub hks: Option<Schedule>,
    /// Wave kernel signature: auto:N or a list of log-energies e1,e2,...
    #[arg(long, value_name = "ENERGIES")]
    pub wks: Option<Schedule>,
    /// WKS bandwidth (default: from auto:N, or 0.5 with a list).
    #[arg(long)]
    pub wks_sigma: Option<f64>,
    /// Auto-diffusion function: auto:N or a list of times.
    #[arg(long, value_name = "TIMES")]
    pub adf: Option<Schedule>,
    /// Divide HKS by the heat trace and WKS by its normalisation sum.
    #[arg(long)]
    pub scaled: bool,
}

/// What a worker is told once, on its first stdin line.
#[derive(serde::Serialize, serde::Deserialize)]
struct WorkerConfig {
    params: BatchParams,
    out: PathBuf,
    threads: usize,
    retry_failed: bool,
}

/// One shape for a worker (one stdin line).
#[derive(serde::Serialize, serde::Deserialize)]
struct WorkerJob {
    path: PathBuf,
    name: String,
}

impl Args {
    fn params(&self) -> Result<BatchParams> {
        Ok(BatchParams {
            k: self.k,
            solve: SolveParams {
                laplacian: self.laplacian,
                tolerance: self.tolerance,
                normalize: !self.no_normalize,
            },
            basis: !self.eigenvalues_only,
            descriptors: DescriptorParams {
                hks: self.descriptors.hks.clone(),
                wks: self.descriptors.wks.clone(),
                wks_sigma: self.descriptors.wks_sigma,
                adf: self.descriptors.adf.clone(),
                scaled: self.descriptors.scaled,
            },
            thumbnail: self.thumbnail,
            point_cloud: self.cloud.params()?,
            geodesic: self.geodesic,
        })
    }
}

/// Runs the batch (or, with `--worker`, a worker).
pub fn run(args: Args) -> Result<()> {
    if args.worker {
        return worker();
    }
    let Some(out) = args.out.clone() else {
        bail!("--out: the output folder is required");
    };
    let params = args.params()?;
    params.validate().map_err(|e| match e {
        BatchError::Parameter { key, message } => {
            anyhow::anyhow!("--{}: {message}", key.replace('_', "-"))
        }
        other => other.into(),
    })?;
    let inputs = resolve_inputs(&args.inputs)?;
    if inputs.is_empty() {
        bail!("no input shapes");
    }
    prepare_output(&out, args.force)?;
    let stale = remove_stale_temporaries(&out);
    if stale > 0 {
        eprintln!("removed {stale} temporary files of an interrupted run");
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = match args.jobs {
        Some(0) => bail!("--jobs 0: at least one worker is needed"),
        Some(j) => j,
        None => cores,
    }
    .min(inputs.len());
    let threads = match args.threads {
        Some(0) => bail!("--threads 0: at least one thread is needed"),
        Some(t) => t,
        None => (cores / jobs).max(1),
    };
    let config = WorkerConfig {
        params: params.clone(),
        out: out.clone(),
        threads,
        retry_failed: args.retry_failed,
    };
    let config_line = serde_json::to_string(&config)?;
    let exe = std::env::current_exe().context("cannot find this program to start workers")?;
    let t0 = std::time::Instant::now();
    let records = run_workers(&exe, &config_line, &inputs, &params.hash(), jobs)?;
    let seconds = t0.elapsed().as_secs_f64();
    let [csv, pq] = write_summary(&out, &records)?;
    let count = |s: Status| records.iter().filter(|r| r.status == s).count();
    let (ok, skipped, failed) = (
        count(Status::Ok),
        count(Status::Skipped),
        count(Status::Failed),
    );
    println!(
        "{} shapes in {seconds:.1} s on {jobs} workers x {threads} threads: {ok} computed, {skipped} up to date (skipped), {failed} failed",
        records.len()
    );
    println!("summary -> {}, {}", csv.display(), pq.display());
    if failed > 0 {
        for r in records.iter().filter(|r| r.status == Status::Failed) {
            eprintln!(
                "failed: {}: {}",
                r.name,
                r.error.as_deref().unwrap_or("unknown error")
            );
        }
        bail!(
            "{failed} of {} shapes failed (listed above and in {})",
            records.len(),
            csv.display()
        );
    }
    Ok(())
}

/// The bar of the batch: shapes done out of all, and the counts so far.
fn shapes_bar(len: usize) -> ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("[{bar:40}] {pos}/{len} shapes ({elapsed}, eta {eta}) {msg}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// What a worker thread reports to the main thread.
enum Event {
    /// The row of shape `i`.
    Done(usize, Box<BatchRecord>),
    /// The worker died on shape `i`, which goes back to the queue.
    Retry(usize, String),
}

/// Runs every input on `jobs` worker processes; returns the rows in input order.
fn run_workers(
    exe: &Path,
    config_line: &str,
    inputs: &[BatchInput],
    params_hash: &str,
    jobs: usize,
) -> Result<Vec<BatchRecord>> {
    let queue: Mutex<VecDeque<(usize, u32)>> =
        Mutex::new((0..inputs.len()).map(|i| (i, 0)).collect());
    let (tx, rx) = mpsc::channel::<Event>();
    let bar = shapes_bar(inputs.len());
    let mut records: Vec<Option<BatchRecord>> = vec![None; inputs.len()];
    let spawn_error: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            let tx = tx.clone();
            let (queue, spawn_error) = (&queue, &spawn_error);
            scope.spawn(move || {
                let mut worker: Option<Worker> = None;
                loop {
                    let next = queue.lock().unwrap_or_else(|p| p.into_inner()).pop_front();
                    let Some((i, attempt)) = next else { break };
                    let input = &inputs[i];
                    if worker.is_none() {
                        match Worker::spawn(exe, config_line) {
                            Ok(w) => worker = Some(w),
                            Err(e) => {
                                let message = format!("cannot start a worker process: {e:#}");
                                let rec = BatchRecord::failed(
                                    &input.name,
                                    &input.path.display().to_string(),
                                    params_hash,
                                    message,
                                );
                                spawn_error
                                    .lock()
                                    .unwrap_or_else(|p| p.into_inner())
                                    .get_or_insert(e);
                                let _ = tx.send(Event::Done(i, Box::new(rec)));
                                continue;
                            }
                        }
                    }
                    let Some(w) = worker.as_mut() else { continue };
                    match w.process(input) {
                        Ok(rec) => {
                            let _ = tx.send(Event::Done(i, Box::new(rec)));
                        }
                        Err(death) => {
                            let died = worker.take().map(Worker::finish).unwrap_or_default();
                            let message = format!(
                                "the worker process died while processing this shape ({death}{died})"
                            );
                            if attempt + 1 < ATTEMPTS {
                                queue
                                    .lock()
                                    .unwrap_or_else(|p| p.into_inner())
                                    .push_back((i, attempt + 1));
                                let _ = tx.send(Event::Retry(i, message));
                            } else {
                                let rec = BatchRecord::failed(
                                    &input.name,
                                    &input.path.display().to_string(),
                                    params_hash,
                                    format!("{message}, {ATTEMPTS} times: out of memory or a crash"),
                                );
                                let _ = tx.send(Event::Done(i, Box::new(rec)));
                            }
                        }
                    }
                }
                if let Some(w) = worker {
                    w.finish();
                }
            });
        }
        drop(tx);
        let (mut ok, mut skipped, mut failed) = (0, 0, 0);
        for event in rx {
            match event {
                Event::Done(i, rec) => {
                    match rec.status {
                        Status::Ok => ok += 1,
                        Status::Skipped => skipped += 1,
                        Status::Failed => failed += 1,
                    }
                    records[i] = Some(*rec);
                    bar.inc(1);
                    bar.set_message(format!("{ok} computed, {skipped} skipped, {failed} failed"));
                }
                Event::Retry(i, message) => {
                    let line = format!("{}: {message}; trying once more", inputs[i].name);
                    if bar.is_hidden() {
                        eprintln!("{line}");
                    } else {
                        bar.println(line);
                    }
                }
            }
        }
    });
    bar.finish_and_clear();
    if let Some(e) = spawn_error.into_inner().unwrap_or_else(|p| p.into_inner())
        && records.iter().flatten().all(|r| {
            r.error
                .as_deref()
                .is_some_and(|m| m.starts_with("cannot start"))
        })
    {
        return Err(e.context("no worker process could be started"));
    }
    Ok(records
        .into_iter()
        .zip(inputs)
        .map(|(r, input)| {
            r.unwrap_or_else(|| {
                BatchRecord::failed(
                    &input.name,
                    &input.path.display().to_string(),
                    params_hash,
                    "not processed (internal error)",
                )
            })
        })
        .collect())
}

/// A worker process seen from the batch.
struct Worker {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    /// The last lines the worker wrote to stderr (the cause of a death, if it said one).
    stderr_tail: Arc<Mutex<VecDeque<String>>>,
    stderr_thread: Option<std::thread::JoinHandle<()>>,
}

impl Worker {
    fn spawn(exe: &Path, config_line: &str) -> Result<Self> {
        let mut child = Command::new(exe)
            .args(["batch", "--worker"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .with_context(|| format!("{}: cannot start", exe.display()))?;
        let (Some(mut stdin), Some(stdout), Some(stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            let _ = child.kill();
            let _ = child.wait();
            bail!("the worker's pipes could not be opened");
        };
        let tail: Arc<Mutex<VecDeque<String>>> = Arc::default();
        let t = tail.clone();
        let stderr_thread = std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let mut t = t.lock().unwrap_or_else(|p| p.into_inner());
                if t.len() == 8 {
                    t.pop_front();
                }
                t.push_back(line);
            }
        });
        writeln!(stdin, "{config_line}").context("cannot configure the worker")?;
        stdin.flush()?;
        Ok(Self {
            child,
            stdin: Some(stdin),
            stdout: BufReader::new(stdout),
            stderr_tail: tail,
            stderr_thread: Some(stderr_thread),
        })
    }

    /// The row of one shape, or why the worker could not give it (it died).
    fn process(&mut self, input: &BatchInput) -> Result<BatchRecord, String> {
        let job = WorkerJob {
            path: input.path.clone(),
            name: input.name.clone(),
        };
        let line = serde_json::to_string(&job).map_err(|e| e.to_string())?;
        let stdin = self.stdin.as_mut().ok_or("no stdin")?;
        writeln!(stdin, "{line}")
            .and_then(|()| stdin.flush())
            .map_err(|e| format!("cannot send it the job: {e}"))?;
        let mut answer = String::new();
        match self.stdout.read_line(&mut answer) {
            Ok(0) => Err("it ended without an answer".into()),
            Ok(_) => serde_json::from_str(&answer)
                .map_err(|e| format!("its answer is not a record: {e}")),
            Err(e) => Err(format!("cannot read its answer: {e}")),
        }
    }

    /// Ends the worker (closing its stdin ends it) and waits for it; returns how it ended
    /// and its last words on stderr, as a clause for a message (empty when it exited
    /// normally with nothing to say).
    fn finish(mut self) -> String {
        drop(self.stdin.take());
        let status = self.child.wait();
        if let Some(t) = self.stderr_thread.take() {
            let _ = t.join();
        }
        let mut said = String::new();
        match status {
            Ok(s) if s.success() => {}
            Ok(s) => said.push_str(&format!("; {}", describe_exit(s))),
            Err(e) => said.push_str(&format!("; cannot wait for it: {e}")),
        }
        let tail = self.stderr_tail.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(last) = tail.iter().rev().find(|l| !l.trim().is_empty()) {
            said.push_str(&format!("; it said: {}", last.trim()));
        }
        said
    }
}

#[cfg(unix)]
fn describe_exit(s: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match s.signal() {
        Some(9) => "killed by signal 9 (SIGKILL, e.g. the out-of-memory killer)".into(),
        Some(6) => "aborted (signal 6, SIGABRT)".into(),
        Some(11) => "crashed (signal 11, SIGSEGV)".into(),
        Some(sig) => format!("killed by signal {sig}"),
        None => format!("exit status {}", s.code().unwrap_or(-1)),
    }
}

#[cfg(not(unix))]
fn describe_exit(s: std::process::ExitStatus) -> String {
    format!("exit status {}", s.code().unwrap_or(-1))
}

/// The worker side: reads its configuration and then one shape per stdin line, answers
/// one record per stdout line. Exits as soon as its stdin closes (the batch ended, or its
/// parent died), even in the middle of a shape: nothing is left but a temporary file.
fn worker() -> Result<()> {
    let (tx, rx) = mpsc::channel::<String>();
    std::thread::spawn(move || {
        let stdin = std::io::stdin();
        let mut line = String::new();
        loop {
            line.clear();
            match stdin.lock().read_line(&mut line) {
                Ok(0) | Err(_) => std::process::exit(0),
                Ok(_) => {
                    if tx.send(line.clone()).is_err() {
                        std::process::exit(0);
                    }
                }
            }
        }
    });
    let first = rx.recv().context("no configuration")?;
    let config: WorkerConfig =
        serde_json::from_str(&first).context("the worker's configuration")?;
    let thumbnails = Thumbnails;
    let options = JobOptions {
        threads: config.threads,
        thumbnailer: Some(&thumbnails),
        retry_failed: config.retry_failed,
        ..JobOptions::default()
    };
    let abort_on = std::env::var(TEST_ABORT_ENV).ok();
    let stdout = std::io::stdout();
    for line in rx {
        let job: WorkerJob = serde_json::from_str(&line).context("a job line")?;
        if abort_on.as_deref() == Some(job.name.as_str()) {
            std::process::abort();
        }
        let input = BatchInput {
            path: job.path,
            name: job.name,
        };
        let rec = process_one(&input, &config.params, &config.out, &options);
        let mut out = stdout.lock();
        writeln!(out, "{}", serde_json::to_string(&rec)?)?;
        out.flush()?;
    }
    Ok(())
}

//! `spectral-mesh serve`: the interactive local web app.

use std::net::IpAddr;
use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::defaults::server;
use spectral_mesh_web::{Limits, ServeConfig, serve_blocking};

/// The end of `serve --help`: how the limits above are answered.
const AFTER_HELP: &str = "\
Limits: every request over a limit above gets a 4xx or a 503 with a JSON message naming the \
figure and the option (uploads over --max-upload-mib, meshes over --max-vertices or \
--max-faces: 413; k over --max-k: 422; a full queue (--max-queued) or too many requests \
(--max-requests): 503 with Retry-After; a body late past --request-seconds: 408). JSON \
bodies are at most 1 MiB. Memory: --memory-mib covers the cache (--cache-mib) and the work \
in progress; an eigenbasis job reserves its estimated peak before it starts (it waits in \
the queue until that fits, at most --max-jobs run at once; one that could never fit is \
refused with the figure). A job stops when cancelled (DELETE /api/mesh/ID/basis), \
superseded (another basis request for the mesh), abandoned (no status poll for \
--job-idle-seconds) or overlong (--job-seconds). The server listens on 127.0.0.1 only \
unless --host names another address.";

/// Arguments of `serve`.
///
/// Limits: every request over one is answered with a 4xx or a 503 and a message naming
/// the limit and the option below that sets it. Memory: the budget (--memory-mib) covers
/// the cache (--cache-mib: meshes and analyses, least recently used out) and the work in
/// progress: each eigenbasis computation reserves its estimated peak before it starts
/// (it waits in the queue until that fits; one that could never fit is refused with the
/// figure), uploads and field requests reserve theirs (they wait until their deadline,
/// then 503).
#[derive(Debug, clap::Args)]
#[command(after_help = AFTER_HELP)]
pub struct Args {
    /// Address to listen on. Only 127.0.0.1 (this machine) unless you ask for another:
    /// with another address, other machines on the network can use the server.
    #[arg(long, default_value_t = server::HOST)]
    pub host: IpAddr,
    /// Port (0 picks a free one).
    #[arg(long, default_value_t = server::PORT)]
    pub port: u16,
    /// Memory budget of the server in MiB: the cache plus the work in progress.
    #[arg(long, default_value_t = server::MEMORY_MIB, value_name = "MIB")]
    pub memory_mib: usize,
    /// Most the cache of meshes and analyses (operators, factorization, eigenbasis) may
    /// hold, in MiB (at most --memory-mib).
    #[arg(long, default_value_t = server::CACHE_MIB, value_name = "MIB")]
    pub cache_mib: usize,
    /// Largest mesh upload, in MiB (413 beyond).
    #[arg(long, default_value_t = server::MAX_UPLOAD_MIB, value_name = "MIB")]
    pub max_upload_mib: usize,
    /// Most vertices of a mesh, uploaded or built (413 beyond).
    #[arg(long, default_value_t = server::MAX_VERTICES, value_name = "N")]
    pub max_vertices: usize,
    /// Most triangles of a mesh, after polygons are split (413 beyond).
    #[arg(long, default_value_t = server::MAX_FACES, value_name = "N")]
    pub max_faces: usize,
    /// Most eigenpairs of a basis (422 beyond; also at most the number of vertices).
    #[arg(long, default_value_t = server::MAX_K, value_name = "K")]
    pub max_k: usize,
    /// Eigenbasis computations running at once; more wait in a queue.
    #[arg(long, default_value_t = server::MAX_JOBS, value_name = "N")]
    pub max_jobs: usize,
    /// Eigenbasis requests waiting in the queue (503 beyond).
    #[arg(long, default_value_t = server::MAX_QUEUED, value_name = "N")]
    pub max_queued: usize,
    /// Longest an eigenbasis computation may run, in seconds (then it is stopped).
    #[arg(long, default_value_t = server::JOB_SECONDS, value_name = "S")]
    pub job_seconds: u64,
    /// An eigenbasis job whose status nobody asked for during this many seconds is
    /// cancelled (its client went away).
    #[arg(long, default_value_t = server::JOB_IDLE_SECONDS, value_name = "S")]
    pub job_idle_seconds: u64,
    /// Longest time for any other request, reading its body and waiting for memory
    /// included (408 when the body is late, 503 otherwise).
    #[arg(long, default_value_t = server::REQUEST_SECONDS, value_name = "S")]
    pub request_seconds: u64,
    /// Requests in progress at once (503 beyond).
    #[arg(long, default_value_t = server::MAX_REQUESTS, value_name = "N")]
    pub max_requests: usize,
    /// Meshes and analyses nobody used for this many seconds are dropped (0: never).
    #[arg(long, default_value_t = server::IDLE_SECONDS, value_name = "S")]
    pub idle_seconds: u64,
    /// Folder holding npm's `node_modules` with three.js, served instead of the copy
    /// embedded in this binary at build time.
    #[arg(long)]
    pub node_modules: Option<PathBuf>,
}

impl Args {
    /// The server's configuration (checked: counts and times at least 1, the cache within
    /// the budget).
    pub fn config(&self) -> Result<ServeConfig> {
        for (name, v) in [
            ("--memory-mib", self.memory_mib as u64),
            ("--cache-mib", self.cache_mib as u64),
            ("--max-upload-mib", self.max_upload_mib as u64),
            ("--max-vertices", self.max_vertices as u64),
            ("--max-faces", self.max_faces as u64),
            ("--max-k", self.max_k as u64),
            ("--max-jobs", self.max_jobs as u64),
            ("--job-seconds", self.job_seconds),
            ("--job-idle-seconds", self.job_idle_seconds),
            ("--request-seconds", self.request_seconds),
            ("--max-requests", self.max_requests as u64),
        ] {
            if v == 0 {
                bail!("{name} must be at least 1");
            }
        }
        if self.cache_mib > self.memory_mib {
            bail!(
                "--cache-mib ({}) must be at most --memory-mib ({})",
                self.cache_mib,
                self.memory_mib
            );
        }
        let mib = |m: usize| m.saturating_mul(1 << 20);
        Ok(ServeConfig {
            host: self.host,
            port: self.port,
            limits: Limits {
                memory_bytes: mib(self.memory_mib),
                cache_bytes: mib(self.cache_mib),
                max_upload_bytes: mib(self.max_upload_mib),
                max_vertices: self.max_vertices,
                max_faces: self.max_faces,
                max_k: self.max_k,
                max_jobs: self.max_jobs,
                max_queued: self.max_queued,
                job_seconds: self.job_seconds,
                job_idle_seconds: self.job_idle_seconds,
                request_seconds: self.request_seconds,
                max_requests: self.max_requests,
                idle_seconds: self.idle_seconds,
                ..Limits::default()
            },
            node_modules: self.node_modules.clone(),
            ..ServeConfig::default()
        })
    }
}

/// Runs the server until interrupted.
pub fn run(args: Args) -> Result<()> {
    serve_blocking(args.config()?)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(argv: &[&str]) -> Args {
        Cli::try_parse_from(std::iter::once("serve").chain(argv.iter().copied()))
            .unwrap_or_else(|e| panic!("{e}"))
            .args
    }

    /// The defaults are the library's, and the server listens on this machine only
    /// unless `--host` names another address.
    #[test]
    fn defaults_are_the_librarys_and_loopback_only() {
        let cfg = parse(&[]).config().unwrap_or_else(|e| panic!("{e}"));
        assert!(cfg.host.is_loopback());
        assert_eq!(cfg.limits, Limits::default());
        assert_eq!(cfg.port, server::PORT);
        let cfg = parse(&["--host", "0.0.0.0"])
            .config()
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(!cfg.host.is_loopback());
    }

    #[test]
    fn options_set_the_limits_and_bad_ones_are_refused() {
        let cfg = parse(&[
            "--memory-mib",
            "512",
            "--cache-mib",
            "256",
            "--max-k",
            "300",
            "--max-jobs",
            "1",
            "--job-idle-seconds",
            "5",
        ])
        .config()
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(cfg.limits.memory_bytes, 512 << 20);
        assert_eq!(cfg.limits.cache_bytes, 256 << 20);
        assert_eq!(
            (
                cfg.limits.max_k,
                cfg.limits.max_jobs,
                cfg.limits.job_idle_seconds
            ),
            (300, 1, 5)
        );
        let e = parse(&["--cache-mib", "4096"]).config().unwrap_err();
        assert!(e.to_string().contains("--memory-mib"), "{e}");
        let e = parse(&["--max-jobs", "0"]).config().unwrap_err();
        assert!(e.to_string().contains("--max-jobs"), "{e}");
    }
}

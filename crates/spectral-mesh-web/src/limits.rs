//! The server's limits, the count of requests in progress, the request deadline and
//! the host and origin checks (the layer that applies them is `api::guard`).
//!
//! Every limit is answered with a 4xx or a 503 and `{"error": message}` naming the
//! limit, the figure and the option that sets it (see [`Limits`] for the list).

use std::net::IpAddr;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use serde::Serialize;

/// Every limit of the server. The defaults are the library's
/// ([`spectral_mesh::defaults::server`]); the `serve` option that sets each is named in
/// brackets.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Limits {
    /// Total memory budget in bytes (`--memory-mib`, default 2 GiB): what the cache holds
    /// plus what work in progress has reserved (eigenbasis jobs at their estimated peak,
    /// uploads being read and parsed, fields being computed). Work that does not fit
    /// waits (jobs in the queue, requests until their deadline: then 503); work that
    /// could never fit is refused (413 for an upload, 422 for a basis, with the figure).
    pub memory_bytes: usize,
    /// Most the cache of meshes and analyses may hold, in bytes (`--cache-mib`, default
    /// 1 GiB, at most the budget); least recently used entries not in use go first.
    pub cache_bytes: usize,
    /// Largest mesh upload in bytes (`--max-upload-mib`, default 64 MiB): 413.
    pub max_upload_bytes: usize,
    /// Largest JSON body in bytes (field, basis, shape and download requests; 1 MiB):
    /// 413.
    pub max_json_bytes: usize,
    /// Most vertices of a mesh (`--max-vertices`, default 1,000,000): 413.
    pub max_vertices: usize,
    /// Most triangles of a mesh, after polygons are split (`--max-faces`, default
    /// 2,000,000): 413.
    pub max_faces: usize,
    /// Most eigenpairs of a basis (`--max-k`, default 1000; also at most the number of
    /// vertices): 422.
    pub max_k: usize,
    /// Eigenbasis computations running at once (`--max-jobs`, default 2); more wait in a
    /// queue, first come first served.
    pub max_jobs: usize,
    /// Eigenbasis requests waiting in the queue (`--max-queued`, default 16): 503 beyond.
    pub max_queued: usize,
    /// Longest an eigenbasis computation may run, in seconds (`--job-seconds`, default
    /// 600): then it is stopped (state `error`, the message says why).
    pub job_seconds: u64,
    /// A queued or running eigenbasis job nobody asked about (status polls, a request
    /// for it) for this many seconds is cancelled (`--job-idle-seconds`, default 60):
    /// the client went away.
    pub job_idle_seconds: u64,
    /// Longest time for any other request, reading its body and waiting for memory
    /// included, in seconds (`--request-seconds`, default 120): 408 when the body did not
    /// arrive in time, 503 otherwise.
    pub request_seconds: u64,
    /// Requests in progress at once (`--max-requests`, default 64): 503 beyond.
    pub max_requests: usize,
    /// Meshes and analyses nobody used for this many seconds are dropped
    /// (`--idle-seconds`, default 3600; 0 = never).
    pub idle_seconds: u64,
}

impl Default for Limits {
    /// The library's server limits ([`spectral_mesh::defaults::server`]).
    fn default() -> Self {
        use spectral_mesh::defaults::server as d;
        Self {
            memory_bytes: d::MEMORY_MIB << 20,
            cache_bytes: d::CACHE_MIB << 20,
            max_upload_bytes: d::MAX_UPLOAD_MIB << 20,
            max_json_bytes: d::MAX_JSON_BYTES,
            max_vertices: d::MAX_VERTICES,
            max_faces: d::MAX_FACES,
            max_k: d::MAX_K,
            max_jobs: d::MAX_JOBS,
            max_queued: d::MAX_QUEUED,
            job_seconds: d::JOB_SECONDS,
            job_idle_seconds: d::JOB_IDLE_SECONDS,
            request_seconds: d::REQUEST_SECONDS,
            max_requests: d::MAX_REQUESTS,
            idle_seconds: d::IDLE_SECONDS,
        }
    }
}

/// Mebibytes, for messages.
pub fn mib(bytes: usize) -> String {
    let m = bytes as f64 / (1u64 << 20) as f64;
    if m >= 10.0 {
        format!("{m:.0} MiB")
    } else {
        format!("{m:.1} MiB")
    }
}

/// The moment a request must be answered by (its start plus `request_seconds`), put
/// into the request's extensions by the API's `guard` middleware.
#[derive(Debug, Clone, Copy)]
pub struct Deadline(pub tokio::time::Instant);

impl Deadline {
    /// A deadline `seconds` from now.
    pub fn after(seconds: u64) -> Self {
        Self(tokio::time::Instant::now() + Duration::from_secs(seconds))
    }
}

/// Requests in progress (see the API's `guard` middleware).
#[derive(Debug, Default)]
pub struct InFlight(AtomicUsize);

impl InFlight {
    /// Requests in progress now.
    pub fn get(&self) -> usize {
        self.0.load(Ordering::Relaxed)
    }

    /// Counts one more request in progress until the ticket is dropped; returns the
    /// count with it.
    pub fn enter(&self) -> (usize, Ticket<'_>) {
        let now = self.0.fetch_add(1, Ordering::Relaxed) + 1;
        (now, Ticket(self))
    }
}

/// One request in progress: counted by [`InFlight::enter`] until dropped.
pub struct Ticket<'a>(&'a InFlight);

impl Drop for Ticket<'_> {
    fn drop(&mut self) {
        self.0.0.fetch_sub(1, Ordering::Relaxed);
    }
}

/// The host part of a `Host` header or of an origin's authority (`[::1]:8000` ->
/// `::1`, `localhost:8000` -> `localhost`).
pub fn host_name(authority: &str) -> &str {
    let a = authority.trim();
    if let Some(rest) = a.strip_prefix('[') {
        return rest.split(']').next().unwrap_or(rest);
    }
    a.rsplit_once(':').map_or(a, |(h, port)| {
        if port.bytes().all(|b| b.is_ascii_digit()) {
            h
        } else {
            a
        }
    })
}

/// True for the names of this machine: `localhost`, `*.localhost` and loopback
/// addresses.
pub fn is_loopback_name(host: &str) -> bool {
    let h = host.trim_end_matches('.').to_ascii_lowercase();
    h == "localhost"
        || h.ends_with(".localhost")
        || h.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// Checks the `Host` and `Origin` headers of a request to a server bound to `bound`:
/// - bound to a loopback address, the `Host` must name this machine (a page of another
///   site whose name was made to resolve to 127.0.0.1, "DNS rebinding", is refused);
/// - an `Origin` (sent by browsers with every cross-site request and every POST) must be
///   the server's own: a page of another site cannot use the API from the user's
///   browser.
pub fn check_host_and_origin(
    bound: IpAddr,
    host: Option<&str>,
    origin: Option<&str>,
) -> Result<(), String> {
    let Some(host) = host else {
        return Err("a request needs a Host header".into());
    };
    if bound.is_loopback() && !is_loopback_name(host_name(host)) {
        return Err(format!(
            "this server listens on {bound} and answers requests for this machine only \
             (Host: localhost or 127.0.0.1), not for '{host}'; start it with --host to serve \
             other hosts"
        ));
    }
    if let Some(origin) = origin
        && origin != "null"
    {
        let authority = origin
            .split_once("://")
            .map_or(origin, |(_, rest)| rest)
            .trim_end_matches('/');
        let same = authority.eq_ignore_ascii_case(host)
            || (is_loopback_name(host_name(authority))
                && is_loopback_name(host_name(host))
                && port_of(authority) == port_of(host));
        if !same {
            return Err(format!(
                "cross-site request refused: the page at {origin} may not use this server \
                 ({host})"
            ));
        }
    }
    Ok(())
}

fn port_of(authority: &str) -> Option<&str> {
    let a = authority.trim();
    let after = a.rsplit_once(']').map_or(a, |(_, rest)| rest);
    after
        .rsplit_once(':')
        .map(|(_, p)| p)
        .filter(|p| p.bytes().all(|b| b.is_ascii_digit()))
}

/// Reads the file `rel` (one of the server's fixed names, never a client's) inside the
/// folder `dir`, refusing it when its real path (symbolic links resolved) is not inside
/// the folder's real path: a link planted in a served folder cannot expose another file.
pub async fn read_inside(dir: &Path, rel: &str) -> Result<Vec<u8>, String> {
    let real_dir = tokio::fs::canonicalize(dir)
        .await
        .map_err(|e| format!("{}: {e}", dir.display()))?;
    let real = tokio::fs::canonicalize(dir.join(rel))
        .await
        .map_err(|e| format!("{rel}: {e}"))?;
    if !real.starts_with(&real_dir) {
        return Err(format!(
            "{rel} leads outside the served folder {} (a symbolic link?): refused",
            dir.display()
        ));
    }
    tokio::fs::read(&real)
        .await
        .map_err(|e| format!("{rel}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::Ipv4Addr;

    #[test]
    fn host_names() {
        assert_eq!(host_name("127.0.0.1:8000"), "127.0.0.1");
        assert_eq!(host_name("[::1]:8000"), "::1");
        assert_eq!(host_name("localhost"), "localhost");
        assert!(is_loopback_name("localhost"));
        assert!(is_loopback_name("app.localhost."));
        assert!(is_loopback_name("127.0.0.2"));
        assert!(is_loopback_name("::1"));
        assert!(!is_loopback_name("evil.example"));
        assert!(!is_loopback_name("127.0.0.1.evil.example"));
        assert!(!is_loopback_name("192.168.1.2"));
    }

    #[test]
    fn host_and_origin_rules() {
        let lo = IpAddr::V4(Ipv4Addr::LOCALHOST);
        let any = IpAddr::V4(Ipv4Addr::UNSPECIFIED);
        let ok = |b, h, o| check_host_and_origin(b, h, o).is_ok();
        assert!(ok(lo, Some("127.0.0.1:8000"), None));
        assert!(ok(
            lo,
            Some("localhost:8000"),
            Some("http://localhost:8000")
        ));
        assert!(ok(
            lo,
            Some("127.0.0.1:8000"),
            Some("http://localhost:8000")
        ));
        assert!(ok(lo, Some("127.0.0.1:8000"), Some("null")));
        assert!(!ok(lo, None, None));
        // DNS rebinding: another name resolving to 127.0.0.1.
        let e = check_host_and_origin(lo, Some("evil.example:8000"), None).unwrap_err();
        assert!(e.contains("--host"), "{e}");
        // Another site's page.
        assert!(!ok(lo, Some("127.0.0.1:8000"), Some("http://evil.example")));
        assert!(!ok(
            lo,
            Some("127.0.0.1:8000"),
            Some("http://127.0.0.1:9000")
        ));
        // Bound to every interface: any Host, but still no other site's page.
        assert!(ok(
            any,
            Some("myhost.lan:8000"),
            Some("http://myhost.lan:8000")
        ));
        assert!(!ok(
            any,
            Some("myhost.lan:8000"),
            Some("http://evil.example")
        ));
    }

    #[test]
    fn default_limits_fit_together() {
        let l = Limits::default();
        assert!(l.cache_bytes <= l.memory_bytes);
        assert!(l.max_upload_bytes < l.memory_bytes / 4);
        assert!(l.max_k >= spectral_mesh::analysis::request::DEFAULT_K);
        assert!(l.job_idle_seconds >= 10 && l.request_seconds >= 10);
        assert_eq!(mib(3 << 20), "3.0 MiB");
        assert_eq!(mib(2 << 30), "2048 MiB");
    }
}

//! The server's limits over real TCP: every limit answered with a 4xx or a 503 whose
//! message names the figure and the option; the eigenbasis queue, cancel and the rules
//! that stop abandoned, superseded and overlong jobs; late and truncated bodies; no file
//! outside the served folders; loopback only unless a host is given. Every wait is
//! bounded.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::{Duration, Instant};

use serde_json::json;
use spectral_mesh_web::{Limits, ServeConfig};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;

mod common;
use common::*;

/// A flat `side x side` grid as OFF text: `side^2` vertices, `2 (side - 1)^2` triangles.
fn grid_off(side: usize) -> Vec<u8> {
    let mut s = format!("OFF\n{} {} 0\n", side * side, 2 * (side - 1) * (side - 1));
    for i in 0..side {
        for j in 0..side {
            s += &format!("{i} {j} 0\n");
        }
    }
    for i in 0..side - 1 {
        for j in 0..side - 1 {
            let a = i * side + j;
            s += &format!(
                "3 {} {} {}\n3 {} {} {}\n",
                a,
                a + side,
                a + 1,
                a + 1,
                a + side,
                a + side + 1
            );
        }
    }
    s.into_bytes()
}

/// Sizes, counts and k: 413 or 422 with the figure and the option, the server still up.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn size_and_count_limits_name_their_option() {
    let addr = start(Limits {
        max_upload_bytes: 64 << 10,
        max_json_bytes: 4096,
        max_vertices: 500,
        max_faces: 700,
        max_k: 30,
        ..Limits::default()
    })
    .await;
    let r = upload(addr, "big.off", &vec![b'0'; 100_000]).await;
    assert_refused(&r, 413, &["--max-upload-mib"]);
    // Without a Content-Length (chunked), the cap holds as the bytes arrive.
    let mut s = TcpStream::connect(addr).await.unwrap();
    let chunked = format!(
        "POST /api/mesh HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: application/octet-stream\r\nTransfer-Encoding: chunked\r\n\r\n"
    );
    s.write_all(chunked.as_bytes()).await.unwrap();
    for _ in 0..10 {
        let _ = s.write_all(format!("{:x}\r\n", 10_000).as_bytes()).await;
        let _ = s.write_all(&[b'1'; 10_000]).await;
        let _ = s.write_all(b"\r\n").await;
    }
    let _ = s.write_all(b"0\r\n\r\n").await;
    let r = read_reply(&mut s).await;
    assert_eq!(r.status, 413, "{}", r.text());

    let r = upload(addr, "grid23.off", &grid_off(23)).await;
    assert_refused(&r, 413, &["529 vertices", "--max-vertices"]);
    let r = upload(addr, "grid20.off", &grid_off(20)).await;
    assert_refused(&r, 413, &["722 triangles", "--max-faces"]);
    let r = upload(addr, "grid15.off", &grid_off(15)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["n"], 225);
    let r = post_json(addr, "/api/mesh", json!({"shape": "sphere:res=3"})).await;
    assert_refused(&r, 413, &["--max-vertices"]);

    let (id, n) = load(addr, "sphere:res=2").await;
    assert_eq!(n, 162);
    let r = post_json(addr, &format!("/api/mesh/{id}/basis"), json!({"k": 31})).await;
    assert_refused(&r, 422, &["--max-k"]);
    let r = post_json(addr, &format!("/api/mesh/{id}/basis"), json!({"k": 163})).await;
    assert_eq!(r.status, 422, "{}", r.text());
    let big = json!({"kind": "heat", "k": 10, "pad": "x".repeat(5000)});
    let r = post_json(addr, &format!("/api/mesh/{id}/field"), big).await;
    assert_refused(&r, 413, &["4096 bytes"]);
    assert_eq!(get(addr, "/api/health").await.json()["ok"], true);
}

/// A basis whose estimated peak exceeds the memory budget (or whose result would not fit
/// the cache) is refused with the figures; one that fits runs.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_basis_that_cannot_fit_is_refused_with_the_figures() {
    let addr = start(Limits {
        memory_bytes: 48 << 20,
        cache_bytes: 24 << 20,
        ..Limits::default()
    })
    .await;
    let (id, n) = load(addr, "sphere:res=5").await;
    assert_eq!(n, 10242);
    let path = format!("/api/mesh/{id}/basis");
    let r = post_json(addr, &path, json!({"k": 300})).await;
    assert_eq!(r.status, 422, "{}", r.text());
    let e = r.error();
    assert!(e.contains("MiB") && e.contains("k = 300"), "{e}");
    assert!(
        e.contains("--cache-mib") || e.contains("--memory-mib"),
        "{e}"
    );
    let r = post_json(addr, &path, json!({"k": 12})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    assert!(r.json()["estimate_bytes"].as_u64().unwrap() > 0);
    let st = wait_job(addr, &id).await;
    assert_eq!(st["state"], "done", "{st}");
    let h = get(addr, "/api/health").await.json();
    assert!(h["cache_used"].as_u64().unwrap() <= 24 << 20, "{h}");
    assert_eq!(h["memory_reserved"], 0, "{h}");
}

/// At most `max_jobs` computations run; the next waits in the queue with its place; the
/// queue is bounded (503 with Retry-After); a cancelled job lets the next one start.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_queue_bounds_running_jobs() {
    let addr = start(Limits {
        max_jobs: 1,
        max_queued: 1,
        ..Limits::default()
    })
    .await;
    let (big, _) = load(addr, "sphere:res=6").await;
    let (small, _) = load(addr, "sphere:res=3").await;
    let (third, _) = load(addr, "sphere:res=2").await;
    let r = post_json(addr, &format!("/api/mesh/{big}/basis"), json!({"k": 300})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let r = post_json(addr, &format!("/api/mesh/{small}/basis"), json!({"k": 10})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    assert_eq!(r.json()["state"], "queued", "{}", r.text());
    assert_eq!(r.json()["queue_position"], 1, "{}", r.text());
    let r = post_json(addr, &format!("/api/mesh/{third}/basis"), json!({"k": 10})).await;
    assert_refused(&r, 503, &["--max-queued"]);
    assert!(r.headers.to_ascii_lowercase().contains("retry-after"));
    let h = get(addr, "/api/health").await.json();
    assert_eq!(
        (h["jobs_running"].clone(), h["jobs_queued"].clone()),
        (json!(1), json!(1))
    );
    let r = request(addr, "DELETE", &format!("/api/mesh/{big}/basis"), "", b"").await;
    assert_eq!(r.status, 200, "{}", r.text());
    let st = wait_job(addr, &big).await;
    assert_eq!(st["state"], "cancelled", "{st}");
    assert_eq!(st["message"], "cancelled by request", "{st}");
    let st = wait_job(addr, &small).await;
    assert_eq!(st["state"], "done", "{st}");
    let r = post_json(addr, &format!("/api/mesh/{third}/basis"), json!({"k": 10})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    assert_eq!(wait_job(addr, &third).await["state"], "done");
    let h = get(addr, "/api/health").await.json();
    assert_eq!(
        (h["jobs_running"].clone(), h["memory_reserved"].clone()),
        (json!(0), json!(0)),
        "{h}"
    );
}

/// A job nobody polls is cancelled after `job_idle_seconds`; one that runs past
/// `job_seconds` is stopped with an error; a client that asks for another mesh stops
/// its earlier job.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abandoned_overlong_and_superseded_jobs_stop() {
    let addr = start(Limits {
        job_idle_seconds: 1,
        ..Limits::default()
    })
    .await;
    let (big, _) = load(addr, "sphere:res=6").await;
    let path = format!("/api/mesh/{big}/basis");
    let t = Instant::now();
    let r = post_json(addr, &path, json!({"k": 300})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    tokio::time::sleep(Duration::from_millis(2500)).await;
    let st = wait_job(addr, &big).await;
    assert_eq!(st["state"], "cancelled", "{st}");
    let msg = st["message"].as_str().unwrap();
    assert!(
        msg.contains("abandoned") && msg.contains("--job-idle-seconds"),
        "{msg}"
    );
    assert!(t.elapsed() < Duration::from_secs(60));

    let addr = start(Limits {
        job_seconds: 1,
        ..Limits::default()
    })
    .await;
    let (big, _) = load(addr, "sphere:res=6").await;
    let r = post_json(addr, &format!("/api/mesh/{big}/basis"), json!({"k": 300})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let st = wait_job(addr, &big).await;
    assert_eq!(st["state"], "error", "{st}");
    assert!(
        st["message"].as_str().unwrap().contains("--job-seconds"),
        "{st}"
    );

    let addr = start(Limits::default()).await;
    let (big, _) = load(addr, "sphere:res=6").await;
    let (small, _) = load(addr, "sphere:res=3").await;
    let me = "X-Client-Id: tab-1\r\n";
    let r = post_json_as(
        addr,
        &format!("/api/mesh/{big}/basis"),
        json!({"k": 300}),
        me,
    )
    .await;
    assert_eq!(r.status, 202, "{}", r.text());
    let r = post_json_as(
        addr,
        &format!("/api/mesh/{small}/basis"),
        json!({"k": 10}),
        me,
    )
    .await;
    assert_eq!(r.status, 202, "{}", r.text());
    let st = wait_job(addr, &big).await;
    assert_eq!(st["state"], "cancelled", "{st}");
    assert!(
        st["message"].as_str().unwrap().contains("superseded"),
        "{st}"
    );
    assert_eq!(wait_job(addr, &small).await["state"], "done");
    // The health counters say so.
    let h = get(addr, "/api/health").await.json();
    assert_eq!(h["jobs_superseded"], 1, "{h}");
    assert_eq!(h["jobs_cancelled"], 1, "{h}");
}

/// A body that stops arriving is answered 408 at the request deadline, one cut short is a
/// 400, and requests beyond `max_requests` in progress are a 503.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn late_truncated_and_too_many_requests() {
    let addr = start(Limits {
        request_seconds: 2,
        max_requests: 2,
        ..Limits::default()
    })
    .await;
    let upload_head = |len: usize| {
        head(
            addr,
            "POST",
            "/api/mesh",
            len,
            "Content-Type: application/octet-stream\r\nX-Filename: slow.off\r\n",
        )
    };
    // Late: 10 of 1000 bytes, then nothing.
    let t = Instant::now();
    let mut slow = TcpStream::connect(addr).await.unwrap();
    slow.write_all(upload_head(1000).as_bytes()).await.unwrap();
    slow.write_all(b"OFF\n3 1 0\n").await.unwrap();
    // Cut short: 10 of 1000 bytes, then the client stops sending.
    let mut cut = TcpStream::connect(addr).await.unwrap();
    cut.write_all(upload_head(1000).as_bytes()).await.unwrap();
    cut.write_all(b"OFF\n3 1 0\n").await.unwrap();
    tokio::time::sleep(Duration::from_millis(300)).await;
    // Two requests are in progress: a third is refused.
    let r = get(addr, "/api/health").await;
    assert_refused(&r, 503, &["--max-requests"]);
    cut.shutdown().await.unwrap();
    let r = read_reply(&mut cut).await;
    assert_refused(&r, 400, &["ended early"]);
    let r = read_reply(&mut slow).await;
    assert_refused(&r, 408, &["--request-seconds"]);
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    let h = get(addr, "/api/health").await;
    assert_eq!(h.status, 200, "{}", h.text());
    assert_eq!(h.json()["memory_reserved"], 0);
}

/// No request reads a file outside the served folders: traversal in paths and ids is a
/// 4xx, a symbolic link in the static folder pointing outside it is refused, and an
/// upload's name keeps its last component only.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn no_file_outside_the_served_folders() {
    let root =
        std::env::temp_dir().join(format!("spectral-mesh-web-limits-{}", std::process::id()));
    let served = root.join("static");
    let outside = root.join("secret.txt");
    std::fs::create_dir_all(&served).unwrap();
    std::fs::write(&outside, "root:x:0:0:secret").unwrap();
    std::fs::write(served.join("app.js"), "console.log('served');").unwrap();
    std::os::unix::fs::symlink(&outside, served.join("index.html")).unwrap();
    let addr = start_with(ServeConfig {
        port: 0,
        static_dir: Some(served.clone()),
        node_modules: Some(served.clone()),
        ..Default::default()
    })
    .await;
    let r = get(addr, "/app.js").await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(r.text().contains("served"));
    let r = get(addr, "/").await;
    assert_refused(&r, 404, &["outside"]);
    for path in [
        "/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "/vendor/..%2F..%2F..%2F..%2Fetc%2Fpasswd",
        "/vendor/../../secret.txt",
        "/static/../secret.txt",
        "/api/mesh/..%2F..%2Fsecret.txt",
        "/api/mesh/..%2F..%2Fsecret.txt/geometry",
        "//etc/passwd",
    ] {
        let r = get(addr, path).await;
        assert!((400..500).contains(&r.status), "{path}: {}", r.status);
        assert!(!r.text().contains("root:"), "{path}: {}", r.text());
    }
    let r = upload(addr, "../../../tmp/evil.off", &grid_off(4)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["source"], "evil.off");
    std::fs::remove_dir_all(&root).unwrap();
}

/// An address of this machine other than loopback, if it has one (no packet is sent:
/// connecting a UDP socket only picks the route).
fn outward_ipv4() -> Option<IpAddr> {
    let s = std::net::UdpSocket::bind("0.0.0.0:0").ok()?;
    s.connect("192.0.2.1:9").ok()?;
    let ip = s.local_addr().ok()?.ip();
    (!ip.is_loopback() && !ip.is_unspecified()).then_some(ip)
}

/// By default the server listens on 127.0.0.1 only: another address of the machine is
/// refused, and so is a request naming another host (DNS rebinding). With an explicit
/// host (`--host 0.0.0.0`) the other address is served.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn loopback_only_unless_a_host_is_given() {
    let addr = start(Limits::default()).await;
    assert_eq!(addr.ip(), IpAddr::V4(Ipv4Addr::LOCALHOST));
    let r = request(addr, "GET", "/api/health", "", b"").await;
    assert_eq!(r.status, 200);
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(
        b"GET /api/health HTTP/1.1\r\nHost: evil.example:8000\r\nConnection: close\r\n\r\n",
    )
    .await
    .unwrap();
    let r = read_reply(&mut s).await;
    assert_refused(&r, 403, &["--host"]);
    let Some(ip) = outward_ipv4() else {
        eprintln!("skipped: this machine has no address besides loopback");
        return;
    };
    let other = SocketAddr::new(ip, addr.port());
    assert!(
        TcpStream::connect(other).await.is_err(),
        "the default server answered on {other}"
    );
    let open = start_with(ServeConfig {
        host: IpAddr::V4(Ipv4Addr::UNSPECIFIED),
        port: 0,
        ..Default::default()
    })
    .await;
    let other = SocketAddr::new(ip, open.port());
    let r = request(other, "GET", "/api/health", "", b"").await;
    assert_eq!(r.status, 200, "{}", r.text());
}

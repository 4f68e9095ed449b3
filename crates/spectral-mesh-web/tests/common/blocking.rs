//! One blocking HTTP/1.1 exchange with a local server over std's `TcpStream`
//! (`Connection: close`, a JSON body, chunked replies decoded), and the steps most tests
//! start with (a shape loaded, a basis computed), for the tests and examples that do not
//! run inside tokio. Included by path where it is needed.
#![allow(dead_code, clippy::unwrap_used)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// How long one read of the helpers below may wait.
const TIMEOUT: Duration = Duration::from_secs(120);

/// (status, headers in lower case, body) of one request, waiting at most `timeout` for
/// each read.
pub fn exchange(
    addr: SocketAddr,
    method: &str,
    path: &str,
    body: Option<&Value>,
    timeout: Duration,
) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_nodelay(true).unwrap();
    s.set_read_timeout(Some(timeout)).unwrap();
    let payload = body.map(|b| b.to_string()).unwrap_or_default();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{payload}",
        payload.len()
    )
    .unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let split = buf.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&buf[..split]).to_ascii_lowercase();
    let status = head[9..12].parse().unwrap();
    let mut body = buf[split + 4..].to_vec();
    if head.contains("transfer-encoding: chunked") {
        body = dechunk(&body);
    }
    (status, head, body)
}

/// The payload of a chunked body.
pub fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let nl = b.windows(2).position(|w| w == b"\r\n").unwrap();
        let len = usize::from_str_radix(std::str::from_utf8(&b[..nl]).unwrap().trim(), 16).unwrap();
        if len == 0 {
            break;
        }
        out.extend_from_slice(&b[nl + 2..nl + 2 + len]);
        b = &b[nl + 4 + len..];
    }
    out
}

/// The JSON reply of a request that must succeed (status below 300).
pub fn json_ok(addr: SocketAddr, method: &str, path: &str, body: Option<&Value>) -> Value {
    let (status, _, b) = exchange(addr, method, path, body, TIMEOUT);
    assert!(
        status < 300,
        "{method} {path}: {status} {}",
        String::from_utf8_lossy(&b)
    );
    serde_json::from_slice(&b).unwrap()
}

/// Loads the built-in shape `spec` (`POST /api/mesh`): its mesh id.
pub fn load_shape(addr: SocketAddr, spec: &str) -> String {
    let mesh = json_ok(addr, "POST", "/api/mesh", Some(&json!({ "shape": spec })));
    mesh["mesh_id"].as_str().unwrap().to_string()
}

/// Starts the basis job of `k` pairs of mesh `id` with the default options and waits
/// (at most `within`) until it is done.
pub fn wait_for_basis(addr: SocketAddr, id: &str, k: usize, within: Duration) {
    json_ok(
        addr,
        "POST",
        &format!("/api/mesh/{id}/basis"),
        Some(&json!({ "k": k })),
    );
    let start = Instant::now();
    loop {
        let st = json_ok(addr, "GET", &format!("/api/mesh/{id}/basis/status"), None);
        if st["state"] == "done" {
            assert!(st["held_k"].as_u64().unwrap() >= k as u64, "{st}");
            return;
        }
        assert_eq!(st["state"], "running", "{st}");
        assert!(
            start.elapsed() < within,
            "the basis took more than {within:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

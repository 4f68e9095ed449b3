//! What the web server's integration tests share: one request per connection over real
//! TCP on 127.0.0.1 (`Connection: close`, chunked replies decoded), a server started on a
//! free loopback port, and polling of a basis job.
//!
//! Each test file includes it with `mod common;` and uses a part of it.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use spectral_mesh_web::{Limits, ServeConfig, bind};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// A reply: status, header block, body (de-chunked).
pub struct Reply {
    pub status: u16,
    pub headers: String,
    pub body: Vec<u8>,
}

impl Reply {
    pub fn json(&self) -> Value {
        serde_json::from_slice(&self.body).unwrap_or(Value::Null)
    }
    pub fn error(&self) -> String {
        self.json()["error"].as_str().unwrap_or("").to_string()
    }
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

/// Reads a whole reply (the server closes: `Connection: close`), at most 60 s.
pub async fn read_reply(s: &mut TcpStream) -> Reply {
    let mut buf = Vec::new();
    let _ = tokio::time::timeout(Duration::from_secs(60), s.read_to_end(&mut buf)).await;
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or_else(|| panic!("no reply header in {:?}", String::from_utf8_lossy(&buf)));
    let headers = String::from_utf8_lossy(&buf[..split]).to_string();
    let status: u16 = headers[9..12].parse().unwrap();
    let mut body = buf[split + 4..].to_vec();
    if headers
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        body = dechunk(&body);
    }
    Reply {
        status,
        headers,
        body,
    }
}

pub fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    while let Some(eol) = b.windows(2).position(|w| w == b"\r\n") {
        let size =
            usize::from_str_radix(std::str::from_utf8(&b[..eol]).unwrap().trim(), 16).unwrap_or(0);
        if size == 0 || b.len() < eol + 4 + size {
            break;
        }
        out.extend(&b[eol + 2..eol + 2 + size]);
        b = &b[eol + 2 + size + 2..];
    }
    out
}

/// The head of a request (`extra`: more header lines, each ending in CRLF).
pub fn head(addr: SocketAddr, method: &str, path: &str, len: usize, extra: &str) -> String {
    format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Length: {len}\r\n{extra}\r\n"
    )
}

pub async fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    extra: &str,
    body: &[u8],
) -> Reply {
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(head(addr, method, path, body.len(), extra).as_bytes())
        .await
        .unwrap();
    // The server may answer (413) before the whole body is sent.
    let _ = s.write_all(body).await;
    read_reply(&mut s).await
}

pub async fn get(addr: SocketAddr, path: &str) -> Reply {
    request(addr, "GET", path, "", b"").await
}

pub async fn post_json(addr: SocketAddr, path: &str, v: Value) -> Reply {
    post_json_as(addr, path, v, "").await
}

pub async fn post_json_as(addr: SocketAddr, path: &str, v: Value, extra: &str) -> Reply {
    let extra = format!("Content-Type: application/json\r\n{extra}");
    request(addr, "POST", path, &extra, v.to_string().as_bytes()).await
}

pub async fn upload(addr: SocketAddr, name: &str, bytes: &[u8]) -> Reply {
    let extra = format!("Content-Type: application/octet-stream\r\nX-Filename: {name}\r\n");
    request(addr, "POST", "/api/mesh", &extra, bytes).await
}

pub async fn start(limits: Limits) -> SocketAddr {
    start_with(ServeConfig {
        port: 0,
        limits,
        ..Default::default()
    })
    .await
}

pub async fn start_with(cfg: ServeConfig) -> SocketAddr {
    let server = bind(cfg).await.unwrap();
    let addr = server.addr;
    tokio::spawn(server.run());
    addr
}

pub async fn load(addr: SocketAddr, shape: &str) -> (String, usize) {
    let r = post_json(addr, "/api/mesh", json!({ "shape": shape })).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let j = r.json();
    (
        j["mesh_id"].as_str().unwrap().to_string(),
        j["n"].as_u64().unwrap() as usize,
    )
}

/// Polls the job of mesh `id` until it is neither queued nor running (at most 300 s).
pub async fn wait_job(addr: SocketAddr, id: &str) -> Value {
    wait_job_within(addr, id, Duration::from_secs(300)).await
}

/// As [`wait_job`], at most `limit`.
pub async fn wait_job_within(addr: SocketAddr, id: &str, limit: Duration) -> Value {
    let t = Instant::now();
    while t.elapsed() < limit {
        let j = get(addr, &format!("/api/mesh/{id}/basis/status"))
            .await
            .json();
        if j["state"] != "running" && j["state"] != "queued" {
            return j;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("the job of {id} did not end within {limit:?}");
}

/// Asserts the reply has `status` and an error message containing each of `needles`.
pub fn assert_refused(r: &Reply, status: u16, needles: &[&str]) {
    assert_eq!(r.status, status, "{}", r.text());
    let e = r.error();
    assert!(needles.iter().all(|n| e.contains(n)), "{e}");
}

/// Posts a field request for mesh `id`.
pub async fn post_field(addr: SocketAddr, id: &str, body: Value) -> Reply {
    post_json(addr, &format!("/api/mesh/{id}/field"), body).await
}

/// Posts a download request (a field request with its `format`) for mesh `id`.
pub async fn post_download(addr: SocketAddr, id: &str, body: Value) -> Reply {
    post_json(addr, &format!("/api/mesh/{id}/download"), body).await
}

/// Asserts `|got[i] - want[i]| <= rel * max |want|` for every `i` of `want` (the message
/// names `what` and `i`).
pub fn assert_close(got: &[f64], want: &[f64], rel: f64, what: &str) {
    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, w) in want.iter().enumerate() {
        assert!(
            (got[i] - w).abs() <= rel * scale,
            "{what} {i}: {} vs {w}",
            got[i]
        );
    }
}

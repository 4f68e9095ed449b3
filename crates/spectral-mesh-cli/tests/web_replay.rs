//! A field downloaded from the web app replays bit for bit: the server runs in this
//! process (127.0.0.1, a free port), computes a basis of K pairs, and answers a field
//! that uses k < K of them as text and as an experiment file; `spectral-mesh run` of the
//! experiment file writes `{out}/{kind}.txt`, which must equal the downloaded text byte
//! for byte (same unit-area operators, the same K-pair basis, the same first k pairs).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use spectral_mesh_web::{ServeConfig, spawn};

#[path = "../../spectral-mesh-web/tests/common/blocking.rs"]
mod blocking;

/// One HTTP/1.1 exchange: (status, body).
fn http(addr: SocketAddr, method: &str, path: &str, body: &Value) -> (u16, Vec<u8>) {
    let (status, _, body) =
        blocking::exchange(addr, method, path, Some(body), Duration::from_secs(120));
    (status, body)
}

fn json_of(addr: SocketAddr, method: &str, path: &str, body: &Value) -> Value {
    let (status, b) = http(addr, method, path, body);
    assert!(
        status < 300,
        "{method} {path}: {status} {}",
        String::from_utf8_lossy(&b)
    );
    serde_json::from_slice(&b).unwrap()
}

#[test]
fn a_web_download_replays_to_the_same_bytes() {
    let server = spawn(ServeConfig {
        port: 0,
        limits: spectral_mesh_web::Limits {
            cache_bytes: 256 << 20,
            ..Default::default()
        },
        ..Default::default()
    })
    .unwrap();
    let addr = server.addr;
    assert!(addr.ip().is_loopback());
    let mesh = json_of(addr, "POST", "/api/mesh", &json!({"shape": "sphere:res=3"}));
    let id = mesh["mesh_id"].as_str().unwrap().to_string();
    let big_k = 60;
    json_of(
        addr,
        "POST",
        &format!("/api/mesh/{id}/basis"),
        &json!({ "k": big_k }),
    );
    let start = Instant::now();
    loop {
        let st = json_of(
            addr,
            "GET",
            &format!("/api/mesh/{id}/basis/status"),
            &json!({}),
        );
        if st["state"] == "done" {
            assert_eq!(st["held_k"], big_k);
            break;
        }
        assert_eq!(st["state"], "running", "{st}");
        assert!(start.elapsed() < Duration::from_secs(300), "basis too slow");
        std::thread::sleep(Duration::from_millis(50));
    }
    let dir = tempfile::tempdir().unwrap();
    for (n, request) in [
        json!({"kind": "heat", "t": 0.01, "k": 40}),
        json!({"kind": "distance", "distance": "diffusion:t=0.02", "source": 100, "k": 25}),
        json!({"kind": "harmonic", "constraints": [{"vertex": 5, "value": 0.0}, {"vertex": 300, "value": 1.0}]}),
    ]
    .into_iter()
    .enumerate()
    {
        let kind = request["kind"].as_str().unwrap().to_string();
        let download = |format: &str| {
            let mut body = request.clone();
            body["format"] = json!(format);
            let (status, bytes) = http(addr, "POST", &format!("/api/mesh/{id}/download"), &body);
            assert_eq!(status, 200, "{format}: {}", String::from_utf8_lossy(&bytes));
            bytes
        };
        let txt = download("txt");
        let toml = download("toml");
        let toml_text = String::from_utf8(toml.clone()).unwrap();
        assert!(toml_text.contains("experiment = \"field\""), "{toml_text}");
        if kind != "harmonic" {
            assert!(
                toml_text.contains(&format!("basis_k = {big_k}")),
                "{toml_text}"
            );
        }
        let file = dir.path().join(format!("web-{n}.toml"));
        std::fs::write(&file, &toml).unwrap();
        let out = dir.path().join(format!("out-{n}"));
        let run = Command::new(env!("CARGO_BIN_EXE_spectral-mesh"))
            .arg("run")
            .arg(&file)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "spectral-mesh run {}: {}\n{}\nthe file:\n{toml_text}",
            file.display(),
            String::from_utf8_lossy(&run.stdout),
            String::from_utf8_lossy(&run.stderr)
        );
        let written = out.join(format!("{kind}.txt"));
        let replayed = std::fs::read(&written).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; run wrote {:?}",
                written.display(),
                std::fs::read_dir(&out)
                    .map(|d| d.flatten().map(|e| e.file_name()).collect::<Vec<_>>())
                    .unwrap_or_default()
            )
        });
        assert_eq!(
            replayed.len(),
            txt.len(),
            "{kind}: the replay's text differs in length"
        );
        assert!(
            replayed == txt,
            "{kind}: the replay differs from the download at line {}",
            String::from_utf8_lossy(&txt)
                .lines()
                .zip(String::from_utf8_lossy(&replayed).lines())
                .position(|(a, b)| a != b)
                .unwrap_or(0)
                + 1
        );
    }
}

//! A field downloaded from the web app replays bit for bit: the server runs in this
//! process (127.0.0.1, a free port), computes a basis of K pairs, and answers a field
//! that uses k < K of them as text and as an experiment file; `spectral-mesh run` of the
//! experiment file writes `{out}/{kind}.txt`, which must equal the downloaded text byte
//! for byte (same unit-area operators, the same K-pair basis, the same first k pairs).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

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

/// A server on 127.0.0.1 (a free port) with a cache of 256 MiB.
fn server() -> spectral_mesh_web::RunningServer {
    spawn(ServeConfig {
        port: 0,
        limits: spectral_mesh_web::Limits {
            cache_bytes: 256 << 20,
            ..Default::default()
        },
        ..Default::default()
    })
    .unwrap()
}

/// The download of a field request `body` in `format` (asserting a 200 reply).
fn download(addr: SocketAddr, id: &str, body: &Value, format: &str, label: &str) -> Vec<u8> {
    let mut b = body.clone();
    b["format"] = json!(format);
    let (status, bytes) = http(addr, "POST", &format!("/api/mesh/{id}/download"), &b);
    assert_eq!(
        status,
        200,
        "{label} {format}: {}",
        String::from_utf8_lossy(&bytes)
    );
    bytes
}

/// Writes a downloaded experiment file as `dir/{name}.toml` and runs it with
/// `spectral-mesh run FILE -o dir/{name}` (asserting success); returns that folder.
fn replay(dir: &Path, name: &str, toml: &[u8], label: &str) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, toml).unwrap();
    let out = dir.join(name);
    let run = Command::new(env!("CARGO_BIN_EXE_spectral-mesh"))
        .arg("run")
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "spectral-mesh run {} ({label}): {}\n{}\nthe file:\n{}",
        file.display(),
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr),
        String::from_utf8_lossy(toml)
    );
    out
}

#[test]
fn a_web_download_replays_to_the_same_bytes() {
    let server = server();
    let addr = server.addr;
    assert!(addr.ip().is_loopback());
    let id = blocking::load_shape(addr, "sphere:res=3");
    let big_k = 60;
    blocking::wait_for_basis(addr, &id, big_k, Duration::from_secs(300));
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
        let download = |format: &str| download(addr, &id, &request, format, &kind);
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
        let out = replay(dir.path(), &format!("web-{n}"), &toml, &kind);
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

/// The values of a text download or a `.txt` output, one per line.
fn values(bytes: &[u8]) -> Vec<f64> {
    String::from_utf8_lossy(bytes)
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect()
}

/// A geodesic distance from the web app equals the command line's `geodesic` for the
/// same source (to 1e-12: the same library call), on a closed shape and on one with
/// boundary (Crane's averaged heat), for both conventions and the robust Laplacian; the
/// web's experiment file replays it byte for byte.
#[test]
fn a_web_geodesic_equals_the_command_line() {
    let server = server();
    let addr = server.addr;
    let dir = tempfile::tempdir().unwrap();
    for (shape, source, extra) in [
        ("3torus", 17usize, json!({})),
        ("disk", 3, json!({})),
        (
            "disk",
            10,
            json!({"convention": "potpourri3d", "time_factor": 2.0}),
        ),
        ("3torus", 5, json!({"laplacian": "robust"})),
    ] {
        let id = blocking::load_shape(addr, shape);
        let mut body = json!({"kind": "geodesic", "source": source});
        for (k, v) in extra.as_object().unwrap() {
            body[k] = v.clone();
        }
        let label = format!("{shape} {body}");
        let download = |format: &str| download(addr, &id, &body, format, &label);
        let web = download("txt");
        let web_values = values(&web);
        assert_eq!(web_values[source], 0.0, "{label}");
        let out = dir.path().join(format!("cli-{shape}-{source}.txt"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_spectral-mesh"));
        cmd.args(["geodesic", shape, "--source", &source.to_string(), "-o"])
            .arg(&out);
        if let Some(l) = extra.get("laplacian") {
            cmd.args(["--laplacian", l.as_str().unwrap()]);
        }
        if let Some(c) = extra.get("convention") {
            cmd.args(["--convention", c.as_str().unwrap()]);
        }
        if let Some(m) = extra.get("time_factor") {
            cmd.args(["--time-factor", &m.to_string()]);
        }
        let run = cmd.output().unwrap();
        assert!(
            run.status.success(),
            "{label}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let cli_values = values(&std::fs::read(&out).unwrap());
        assert_eq!(cli_values.len(), web_values.len(), "{label}");
        let err = cli_values
            .iter()
            .zip(&web_values)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(err <= 1e-12, "{label}: web and CLI differ by {err}");
        // The experiment file replays to the same bytes.
        let toml = download("toml");
        let toml_text = String::from_utf8(toml.clone()).unwrap();
        assert!(toml_text.contains("kind = \"geodesic\""), "{toml_text}");
        let replay = replay(dir.path(), &format!("geo-{shape}-{source}"), &toml, &label);
        assert!(
            std::fs::read(replay.join("geodesic.txt")).unwrap() == web,
            "{label}: the replay differs from the download"
        );
    }
}

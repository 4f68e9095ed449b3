//! API tests over real TCP on 127.0.0.1 (no browser): every endpoint's happy path, and
//! every kind of bad input answered with a 4xx JSON error while the server stays up.

#![allow(clippy::unwrap_used, clippy::needless_range_loop)]

use std::time::Duration;

use serde_json::Value;
use spectral_mesh_web::{ServeConfig, bind};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

struct Reply {
    status: u16,
    headers: String,
    body: Vec<u8>,
}

impl Reply {
    fn json(&self) -> Value {
        serde_json::from_slice(&self.body).unwrap_or(Value::Null)
    }
    fn error(&self) -> String {
        self.json()["error"].as_str().unwrap_or("").to_string()
    }
}

async fn request(
    addr: std::net::SocketAddr,
    method: &str,
    path: &str,
    content_type: &str,
    extra: &str,
    body: &[u8],
) -> Reply {
    let mut s = TcpStream::connect(addr).await.unwrap();
    let head = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n{extra}\r\n",
        body.len()
    );
    s.write_all(head.as_bytes()).await.unwrap();
    // The server may answer (413) before the whole body is sent; ignore write errors.
    let _ = s.write_all(body).await;
    let mut buf = Vec::new();
    let _ = tokio::time::timeout(Duration::from_secs(30), s.read_to_end(&mut buf)).await;
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("no header end");
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

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    while let Some(eol) = b.windows(2).position(|w| w == b"\r\n") {
        let size =
            usize::from_str_radix(std::str::from_utf8(&b[..eol]).unwrap().trim(), 16).unwrap_or(0);
        if size == 0 {
            break;
        }
        out.extend(&b[eol + 2..eol + 2 + size]);
        b = &b[eol + 2 + size + 2..];
    }
    out
}

async fn get(addr: std::net::SocketAddr, path: &str) -> Reply {
    request(addr, "GET", path, "text/plain", "", b"").await
}

async fn post_json(addr: std::net::SocketAddr, path: &str, v: Value) -> Reply {
    request(
        addr,
        "POST",
        path,
        "application/json",
        "",
        v.to_string().as_bytes(),
    )
    .await
}

async fn start(max_upload: usize) -> std::net::SocketAddr {
    let cfg = ServeConfig {
        port: 0,
        max_upload_bytes: max_upload,
        cache_bytes: 64 << 20,
        ..Default::default()
    };
    let server = bind(cfg).await.unwrap();
    let addr = server.addr;
    assert!(addr.ip().is_loopback());
    tokio::spawn(server.run());
    addr
}

fn parse_field(body: &[u8]) -> (Value, Vec<f32>, Vec<f32>) {
    let hl = u32::from_le_bytes(body[0..4].try_into().unwrap()) as usize;
    let header: Value = serde_json::from_slice(&body[4..4 + hl]).unwrap();
    let n = header["n"].as_u64().unwrap() as usize;
    let floats: Vec<f32> = body[4 + hl..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (header, floats[..n].to_vec(), floats[n..].to_vec())
}

async fn wait_basis(addr: std::net::SocketAddr, id: &str) -> Value {
    for _ in 0..200 {
        let r = get(addr, &format!("/api/mesh/{id}/basis/status")).await;
        let j = r.json();
        if j["state"] != "running" {
            return j;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("basis did not finish");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn happy_paths() {
    let addr = start(1 << 20).await;
    // Static page and shapes.
    let r = get(addr, "/").await;
    assert_eq!(r.status, 200);
    assert!(r.headers.to_ascii_lowercase().contains("text/html"));
    let r = get(addr, "/api/shapes").await;
    assert_eq!(r.status, 200);
    assert!(
        r.json()["shapes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["name"] == "sphere")
    );

    // Load a shape.
    let r = post_json(
        addr,
        "/api/mesh",
        serde_json::json!({"shape": "sphere:res=2"}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.error());
    let j = r.json();
    let id = j["mesh_id"].as_str().unwrap().to_string();
    let n = j["n"].as_u64().unwrap() as usize;
    assert_eq!(n, 162);
    assert_eq!(j["info"]["euler_characteristic"], 2);
    assert_eq!(j["info"]["genus"], 0);

    // Geometry.
    let r = get(addr, &format!("/api/mesh/{id}/geometry")).await;
    assert_eq!(r.status, 200);
    let gn = u32::from_le_bytes(r.body[0..4].try_into().unwrap()) as usize;
    let gm = u32::from_le_bytes(r.body[4..8].try_into().unwrap()) as usize;
    assert_eq!((gn, gm), (162, 320));
    assert_eq!(r.body.len(), 8 + 12 * gn + 12 * gm);

    // Harmonic field needs no basis; its critical points satisfy the Euler check.
    let r = post_json(
        addr,
        &format!("/api/mesh/{id}/field"),
        serde_json::json!({"experiment": "harmonic", "constraints": "2", "levels": 8}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let (h, vals, segs) = parse_field(&r.body);
    assert_eq!(vals.len(), n);
    assert!((h["min"].as_f64().unwrap() - 0.0).abs() < 1e-12);
    assert!((h["max"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(h["critical"]["euler_ok"], true);
    assert_eq!(h["level_counts"].as_array().unwrap().len(), 8);
    assert!(!segs.is_empty() && segs.len() % 6 == 0);

    // A field that needs a basis before it exists: 409.
    let body = serde_json::json!({"experiment": "heat", "k": 30, "t": 0.05, "source": 7});
    let r = post_json(addr, &format!("/api/mesh/{id}/field"), body.clone()).await;
    assert_eq!(r.status, 409);

    // Basis, polled to completion.
    let r = post_json(
        addr,
        &format!("/api/mesh/{id}/basis"),
        serde_json::json!({"laplacian": "fem", "k": 40}),
    )
    .await;
    assert!(r.status == 202 || r.status == 200, "{}", r.error());
    let st = wait_basis(addr, &id).await;
    assert_eq!(st["state"], "done", "{st}");

    // Heat from the basis (k = 30 <= 40 reuses it): peak at the anchor.
    let r = post_json(addr, &format!("/api/mesh/{id}/field"), body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let (h, vals, _) = parse_field(&r.body);
    let argmax = (0..n).max_by(|&a, &b| vals[a].total_cmp(&vals[b])).unwrap();
    assert_eq!(argmax, 7);
    assert_eq!(h["basis"]["k"], 30);

    // Every spectral experiment answers with finite values.
    for exp in [
        "diffusion",
        "distance",
        "signature",
        "segmentation",
        "embedding",
        "eigenfunction",
    ] {
        for filter in ["diffusion", "commute", "biharmonic", "mix"] {
            let r = post_json(
                addr,
                &format!("/api/mesh/{id}/field"),
                serde_json::json!({"experiment": exp, "k": 40, "t": 0.1, "a": 0.3,
                    "filter": filter, "source": 3, "levels": 5, "segments": 4}),
            )
            .await;
            assert_eq!(
                r.status,
                200,
                "{exp} {filter}: {}",
                String::from_utf8_lossy(&r.body)
            );
            let (_, vals, _) = parse_field(&r.body);
            assert!(vals.iter().all(|v| v.is_finite()));
        }
    }
    // Distance is zero at the source; custom w = 1/s^2 equals biharmonic.
    let mut got = Vec::new();
    for (filter, custom) in [("biharmonic", ""), ("custom", "1/s^2"), ("custom", "s^2")] {
        let r = post_json(
            addr,
            &format!("/api/mesh/{id}/field"),
            serde_json::json!({"experiment": "distance", "k": 40, "filter": filter,
                "custom": custom, "custom_kind": if custom == "s^2" {"phi"} else {"w"}, "source": 11}),
        )
        .await;
        assert_eq!(r.status, 200);
        let (_, vals, _) = parse_field(&r.body);
        assert_eq!(vals[11], 0.0);
        got.push(vals);
    }
    for i in 0..n {
        assert!((got[0][i] - got[1][i]).abs() <= 1e-6 * got[0][i].abs().max(1e-6));
        assert!((got[0][i] - got[2][i]).abs() <= 1e-6 * got[0][i].abs().max(1e-6));
    }

    // Downloads: txt matches the field values; ply, wrl, toml are well formed.
    let q = "experiment=distance&k=40&filter=biharmonic&source=11";
    let r = get(addr, &format!("/api/mesh/{id}/download?format=txt&{q}")).await;
    assert_eq!(r.status, 200);
    let txt: Vec<f64> = String::from_utf8(r.body)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(txt.len(), n);
    for i in 0..n {
        assert!((txt[i] as f32 - got[0][i]).abs() <= 1e-6 * got[0][i].abs().max(1e-6));
    }
    let r = get(addr, &format!("/api/mesh/{id}/download?format=ply&{q}")).await;
    assert_eq!(r.status, 200);
    assert!(r.body.starts_with(b"ply\n"));
    let r = get(addr, &format!("/api/mesh/{id}/download?format=wrl&{q}")).await;
    assert!(r.body.starts_with(b"#VRML V2.0 utf8"));
    let r = get(
        addr,
        &format!("/api/mesh/{id}/download?format=png&colormap=viridis&{q}"),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.error());
    assert!(r.body.starts_with(b"\x89PNG"));
    let r = get(
        addr,
        &format!("/api/mesh/{id}/download?format=png&colormap=nope&{q}"),
    )
    .await;
    assert_eq!(r.status, 400);
    let r = get(addr, &format!("/api/mesh/{id}/download?format=toml&{q}")).await;
    assert_eq!(r.status, 200);
    let t: toml::Table = toml::from_str(&String::from_utf8(r.body).unwrap()).unwrap();
    assert_eq!(t["experiment"].as_str(), Some("distance"));
    assert_eq!(t["mesh"].as_str(), Some("sphere:res=2"));
    assert_eq!(t["k"].as_integer(), Some(40));
    assert_eq!(t["source"].as_integer(), Some(11));

    // Upload an OFF file.
    let off = b"OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let r = request(
        addr,
        "POST",
        "/api/mesh",
        "application/octet-stream",
        "X-Filename: tet.off\r\n",
        off,
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.error());
    assert_eq!(r.json()["n"], 4);
    assert_eq!(r.json()["info"]["euler_characteristic"], 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_is_a_4xx_with_a_message_and_the_server_stays_up() {
    let addr = start(4096).await;
    let r = post_json(
        addr,
        "/api/mesh",
        serde_json::json!({"shape": "sphere:res=1"}),
    )
    .await;
    let id = r.json()["mesh_id"].as_str().unwrap().to_string();
    let n = r.json()["n"].as_u64().unwrap();
    let field = format!("/api/mesh/{id}/field");
    let basis = format!("/api/mesh/{id}/basis");
    let r = post_json(addr, &basis, serde_json::json!({"k": 20})).await;
    assert!(r.status < 300);
    wait_basis(addr, &id).await;

    let mut cases: Vec<(&str, Reply)> = Vec::new();
    cases.push((
        "malformed upload",
        request(
            addr,
            "POST",
            "/api/mesh",
            "application/octet-stream",
            "X-Filename: broken.off\r\n",
            b"OFF\n3 1 0\n0 0 0\n1 zero 0\n",
        )
        .await,
    ));
    cases.push((
        "out-of-range face",
        request(
            addr,
            "POST",
            "/api/mesh",
            "application/octet-stream",
            "",
            b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
        )
        .await,
    ));
    cases.push((
        "oversized upload",
        request(
            addr,
            "POST",
            "/api/mesh",
            "application/octet-stream",
            "",
            &vec![b'0'; 100_000],
        )
        .await,
    ));
    cases.push((
        "unknown shape",
        post_json(
            addr,
            "/api/mesh",
            serde_json::json!({"shape": "klein-bottle-9"}),
        )
        .await,
    ));
    cases.push((
        "bad JSON",
        request(
            addr,
            "POST",
            "/api/mesh",
            "application/json",
            "",
            b"{shape:",
        )
        .await,
    ));
    cases.push((
        "vertex out of range",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "heat", "k": 20, "source": n}),
        )
        .await,
    ));
    cases.push((
        "constraint vertex out of range",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "harmonic", "constraints": "0=0,99999=1"}),
        )
        .await,
    ));
    cases.push((
        "t = NaN",
        request(
            addr,
            "POST",
            &field,
            "application/json",
            "",
            br#"{"experiment":"heat","k":20,"t":NaN}"#,
        )
        .await,
    ));
    cases.push((
        "t <= 0",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "heat", "k": 20, "t": -1.0}),
        )
        .await,
    ));
    cases.push((
        "k > n",
        post_json(addr, &basis, serde_json::json!({"k": n + 1})).await,
    ));
    cases.push((
        "k > n in a field",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "heat", "k": n + 5}),
        )
        .await,
    ));
    cases.push((
        "unknown laplacian",
        post_json(
            addr,
            &basis,
            serde_json::json!({"laplacian": "nope", "k": 5}),
        )
        .await,
    ));
    cases.push((
        "bad custom expression",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "distance", "k": 20, "filter": "custom", "custom": "exp(-t*"}),
        )
        .await,
    ));
    cases.push((
        "non-positive custom expression",
        post_json(
            addr,
            &field,
            serde_json::json!({"experiment": "distance", "k": 20, "filter": "custom", "custom": "s-1000"}),
        )
        .await,
    ));
    cases.push((
        "unknown experiment",
        post_json(addr, &field, serde_json::json!({"experiment": "astrology"})).await,
    ));
    cases.push((
        "bad mesh id",
        get(addr, "/api/mesh/..%2F..%2Fetc/geometry").await,
    ));
    cases.push((
        "unknown mesh",
        get(addr, "/api/mesh/0123456789abcdef/geometry").await,
    ));
    cases.push((
        "bad download format",
        get(addr, &format!("/api/mesh/{id}/download?format=exe")).await,
    ));
    for (what, r) in &cases {
        assert!(
            (400..500).contains(&r.status),
            "{what}: status {} body {}",
            r.status,
            String::from_utf8_lossy(&r.body)
        );
        assert!(!r.error().is_empty(), "{what}: no JSON error message");
    }
    let oversized = &cases[2].1;
    assert_eq!(oversized.status, 413);
    assert!(cases[3].1.error().contains("unknown shape"));
    assert!(cases[5].1.error().contains("out of range"));
    // The server is still up and still answers correctly.
    let r = post_json(
        addr,
        &field,
        serde_json::json!({"experiment": "heat", "k": 20, "source": 1}),
    )
    .await;
    assert_eq!(r.status, 200);
    assert_eq!(get(addr, "/api/health").await.json()["ok"], true);
}

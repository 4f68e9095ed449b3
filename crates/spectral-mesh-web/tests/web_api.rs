//! API tests over real TCP on 127.0.0.1 (no browser): every endpoint's happy path, the
//! fields against the library's own, and every kind of bad input answered with a 4xx JSON
//! error while the server stays up.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Duration;

use serde_json::{Value, json};
use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
use spectral_mesh::experiments::file::ExperimentFile;
use spectral_mesh_web::ServeConfig;
use spectral_mesh_web::field::{ParsedReply, parse_reply};

mod common;
use common::{Reply, get, post_download, post_field, post_json, start_with};

/// The reply of a field request, parsed (asserting status 200).
trait FieldReply {
    fn field(&self) -> ParsedReply;
}

impl FieldReply for Reply {
    fn field(&self) -> ParsedReply {
        assert_eq!(self.status, 200, "{}", self.text());
        parse_reply(&self.body).unwrap()
    }
}

/// A request with this content type (`extra`: more header lines, each ending in CRLF).
async fn request(
    addr: std::net::SocketAddr,
    method: &str,
    path: &str,
    content_type: &str,
    extra: &str,
    body: &[u8],
) -> Reply {
    let extra = format!("Content-Type: {content_type}\r\n{extra}");
    common::request(addr, method, path, &extra, body).await
}

/// A request of a table of bad requests.
enum Req {
    /// A JSON body posted to the path.
    Json(String, Value),
    /// A GET of the path.
    Get(String),
    /// Method, path, content type, extra header lines, body.
    Raw(&'static str, String, &'static str, &'static str, Vec<u8>),
}

async fn send(addr: std::net::SocketAddr, req: Req) -> Reply {
    match req {
        Req::Json(path, v) => post_json(addr, &path, v).await,
        Req::Get(path) => get(addr, &path).await,
        Req::Raw(method, path, ct, extra, body) => {
            request(addr, method, &path, ct, extra, &body).await
        }
    }
}

/// The text of the `.txt` download of the field request `field` for mesh `id`, which must
/// succeed.
async fn download_txt(addr: std::net::SocketAddr, id: &str, mut field: Value) -> String {
    field["format"] = json!("txt");
    let r = post_download(addr, id, field).await;
    assert_eq!(r.status, 200, "{}", r.error());
    r.text()
}

async fn start(max_upload: usize) -> std::net::SocketAddr {
    let addr = start_with(ServeConfig {
        port: 0,
        limits: spectral_mesh_web::Limits {
            max_upload_bytes: max_upload,
            cache_bytes: 256 << 20,
            ..Default::default()
        },
        ..Default::default()
    })
    .await;
    assert!(addr.ip().is_loopback());
    addr
}

async fn load(addr: std::net::SocketAddr, shape: &str) -> (String, usize) {
    let r = post_json(addr, "/api/mesh", json!({ "shape": shape })).await;
    assert_eq!(r.status, 200, "{}", r.error());
    let j = r.json();
    (
        j["mesh_id"].as_str().unwrap().to_string(),
        j["n"].as_u64().unwrap() as usize,
    )
}

async fn wait_basis(addr: std::net::SocketAddr, id: &str) -> Value {
    common::wait_job_within(addr, id, Duration::from_secs(120)).await
}

async fn basis(addr: std::net::SocketAddr, id: &str, body: Value) -> Value {
    let r = post_json(addr, &format!("/api/mesh/{id}/basis"), body).await;
    assert!(r.status == 202 || r.status == 200, "{}", r.error());
    let st = wait_basis(addr, id).await;
    assert_eq!(st["state"], "done", "{st}");
    st
}

/// A download's text, one value per line, as numbers.
fn numbers(text: &str) -> Vec<f64> {
    text.lines().map(|l| l.parse().unwrap()).collect()
}

fn url_encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
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

    // Load a shape: the id is the start of the library's content hash.
    let (id, n) = load(addr, "sphere:res=2").await;
    assert_eq!(n, 162);
    let mesh = spectral_mesh::shapes::build_str("sphere:res=2").unwrap();
    assert_eq!(id, mesh.content_hash()[..16]);
    let r = get(addr, &format!("/api/mesh/{id}")).await;
    assert_eq!(r.json()["info"]["euler_characteristic"], 2);
    assert_eq!(r.json()["info"]["genus"], 0);

    // Geometry.
    let r = get(addr, &format!("/api/mesh/{id}/geometry")).await;
    assert_eq!(r.status, 200);
    let gn = u32::from_le_bytes(r.body[0..4].try_into().unwrap()) as usize;
    let gm = u32::from_le_bytes(r.body[4..8].try_into().unwrap()) as usize;
    assert_eq!((gn, gm), (162, 320));
    assert_eq!(r.body.len(), 8 + 12 * gn + 12 * gm);

    // A harmonic map needs no basis; its critical points satisfy the Euler check.
    let field = format!("/api/mesh/{id}/field");
    let f = post_json(
        addr,
        &field,
        json!({"kind": "harmonic", "constraints": 2, "levels": 8}),
    )
    .await
    .field();
    assert_eq!(f.values.len(), n);
    assert!((f.header["min"].as_f64().unwrap() - 0.0).abs() < 1e-12);
    assert!((f.header["max"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(f.header["critical"]["holds"], true);
    assert_eq!(f.header["critical"]["chi"], 2);
    assert_eq!(f.header["level_counts"].as_array().unwrap().len(), 8);
    assert_eq!(f.header["marks"].as_array().unwrap().len(), 2);
    assert!(f.header["k"].is_null());
    let counted: u64 = f.header["level_counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(f.segments.len() as u64, 6 * counted);
    assert!(!f.segments.is_empty());
    // Explicit constraints come back resolved and marked.
    let f = post_json(
        addr,
        &field,
        json!({"kind": "harmonic", "constraints": [{"vertex": 3, "value": -1.0}, {"vertex": 50, "value": 2.0}]}),
    )
    .await
    .field();
    assert_eq!(f.values[3], -1.0);
    assert_eq!(f.values[50], 2.0);
    assert_eq!(f.header["marks"], json!([3, 50]));

    // A field that needs a basis before it exists: 409 naming what to do.
    let heat = json!({"kind": "heat", "k": 30, "t": 0.002, "anchor": 7});
    let r = post_json(addr, &field, heat.clone()).await;
    assert_eq!(r.status, 409);
    assert!(r.error().contains("/basis"), "{}", r.error());

    // Basis, polled to completion; asking again answers at once.
    let st = basis(addr, &id, json!({"laplacian": "fem", "k": 40})).await;
    assert_eq!(st["held_k"], 40);
    let r = post_json(addr, &format!("/api/mesh/{id}/basis"), json!({"k": 20})).await;
    assert_eq!(r.status, 200);
    assert_eq!(r.json()["state"], "done");

    // Heat from the basis (k = 30 of the 40 held): peak at the anchor.
    let f = post_json(addr, &field, heat).await.field();
    let argmax = (0..n)
        .max_by(|&a, &b| f.values[a].total_cmp(&f.values[b]))
        .unwrap();
    assert_eq!(argmax, 7);
    assert_eq!(f.header["k"], 30);
    assert_eq!(f.header["basis_k"], 40);
    assert_eq!(f.header["source"], 7);
    assert_eq!(f.header["normalized"], true);
    assert_eq!(f.header["laplacian"], "fem");
    assert_eq!(f.header["request"]["anchor"], 7);

    // Every kind answers with finite values; the default source is resolved.
    for body in [
        json!({"kind": "heat", "k": 40}),
        json!({"kind": "diffusion", "signal": {"ball": {"vertex": 3, "radius": 0.3}}, "t": 0.01, "k": 40}),
        json!({"kind": "distance", "distance": "wfem-diffusion:t=0.01", "k": 40}),
        json!({"kind": "distance", "distance": "mix:a=0.3,t=0.1", "k": 40, "source": 3}),
        json!({"kind": "spectral-function", "filter": "diffusion:t=0.1", "k": 40}),
        json!({"kind": "hks", "t": 0.01, "k": 40}),
        json!({"kind": "wks", "energy": 4.0, "k": 40}),
        json!({"kind": "adf", "k": 40}),
        json!({"kind": "segmentation", "signature": "hks:t=0.01", "k": 40}),
        json!({"kind": "embedding", "filter": "commute", "component": 2, "k": 40}),
        json!({"kind": "eigenfunction", "index": 3, "k": 40}),
        json!({"kind": "green", "k": 40}),
    ] {
        let f = post_json(addr, &field, body.clone()).await.field();
        assert!(f.values.iter().all(|v| v.is_finite()), "{body}");
        assert_eq!(f.header["kind"], body["kind"]);
        if matches!(body["kind"].as_str(), Some("heat" | "distance" | "green")) {
            assert!(f.header["source"].is_u64(), "{body}: {}", f.header);
        }
        if body["kind"] == "segmentation" {
            assert_eq!(f.header["categorical"], true);
            assert!(f.header["critical"].is_null() && f.segments.is_empty());
        } else {
            assert_eq!(f.header["critical"]["holds"], true, "{body}");
        }
    }
    let f = post_json(addr, &field, json!({"kind": "distance", "k": 40}))
        .await
        .field();
    assert_eq!(
        f.header["source"].as_u64().unwrap() as usize,
        mesh.vertex_of_largest_x()
    );

    // Distance is zero at the source; custom w = 1/s^2 and phi = s^2 equal bi-harmonic.
    let mut got = Vec::new();
    for distance in ["biharmonic", "custom-w:1/s^2", "custom-phi:s^2"] {
        let f = post_json(
            addr,
            &field,
            json!({"kind": "distance", "k": 40, "distance": distance, "source": 11}),
        )
        .await
        .field();
        assert_eq!(f.values[11], 0.0);
        got.push(f.values);
    }
    for i in 0..n {
        assert!((got[0][i] - got[1][i]).abs() <= 1e-6 * got[0][i].abs().max(1e-6));
        assert!((got[0][i] - got[2][i]).abs() <= 1e-6 * got[0][i].abs().max(1e-6));
    }

    // Downloads: txt is the field at full precision; ply, wrl, png, toml are well formed.
    let body = json!({"kind": "distance", "k": 30, "source": 11, "levels": 6});
    let dl = format!("/api/mesh/{id}/download");
    let q = |format: &str, extra: Value| {
        let mut b = body.clone();
        for (k, v) in extra.as_object().unwrap() {
            b[k] = v.clone();
        }
        format!("{dl}?format={format}&body={}", url_encode(&b.to_string()))
    };
    let r = get(addr, &q("txt", json!({}))).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let txt = numbers(&r.text());
    assert_eq!(txt.len(), n);
    let f = post_json(addr, &field, body.clone()).await.field();
    for i in 0..n {
        assert_eq!(txt[i] as f32, f.values[i]);
    }
    let r = post_json(
        addr,
        &dl,
        json!({"kind": "distance", "k": 30, "source": 11, "format": "txt"}),
    )
    .await;
    assert_eq!(numbers(&r.text()), txt);
    let r = get(addr, &q("ply", json!({}))).await;
    assert_eq!(r.status, 200);
    assert!(r.body.starts_with(b"ply\n"));
    assert!(r.text().contains("property double value"));
    let r = get(addr, &q("wrl", json!({}))).await;
    assert!(r.body.starts_with(b"#VRML V2.0 utf8"));
    let r = get(addr, &q("png", json!({"colormap": "viridis", "size": 96}))).await;
    assert_eq!(r.status, 200, "{}", r.error());
    assert!(r.body.starts_with(b"\x89PNG"));
    assert!(r.headers.contains("distance-"));
    let r = get(addr, &q("png", json!({"colormap": "nope"}))).await;
    assert_eq!(r.status, 400);
    assert!(r.error().contains("colormap"), "{}", r.error());

    // The experiment file: the resolved request, the basis it came from, the mesh hash.
    let r = get(addr, &q("toml", json!({"colormap": "turbo"}))).await;
    assert_eq!(r.status, 200, "{}", r.error());
    let exp = ExperimentFile::parse(&r.text(), "download.toml").unwrap();
    assert_eq!(exp.experiment, "field");
    assert_eq!(exp.mesh, "sphere:res=2");
    assert_eq!(exp.mesh_hash.as_deref(), Some(mesh.content_hash().as_str()));
    assert_eq!(exp.laplacian.as_deref(), Some("fem"));
    assert_eq!(exp.normalize, Some(true));
    assert_eq!(exp.basis_k, Some(40));
    let req = exp.request().unwrap();
    assert_eq!(req.eigenpairs(), Some(30));
    assert_eq!(req.source(), Some(11));
    let fig = exp.figure.unwrap();
    assert_eq!(fig.levels, Some(6));
    assert_eq!(fig.colormap.as_deref(), Some("turbo"));
    // A field from all the pairs held records no basis_k.
    let r = post_json(
        addr,
        &dl,
        json!({"kind": "heat", "k": 40, "format": "toml"}),
    )
    .await;
    let exp = ExperimentFile::parse(&r.text(), "d.toml").unwrap();
    assert_eq!(exp.basis_k, None);
    assert!(exp.request().unwrap().source().is_some());

    // Another discretization is another analysis, with its own basis.
    let r = post_json(
        addr,
        &field,
        json!({"kind": "heat", "k": 10, "laplacian": "voronoi-cot"}),
    )
    .await;
    assert_eq!(r.status, 409);
    basis(addr, &id, json!({"laplacian": "voronoi-cot", "k": 10})).await;
    let f = post_json(
        addr,
        &field,
        json!({"kind": "heat", "k": 10, "laplacian": "voronoi-cot"}),
    )
    .await
    .field();
    assert_eq!(f.header["laplacian"], "voronoi-cot");
    // Without normalisation, another analysis again.
    let r = post_json(
        addr,
        &field,
        json!({"kind": "heat", "k": 10, "normalize": false}),
    )
    .await;
    assert_eq!(r.status, 409);

    // Upload an OFF file.
    let off = b"OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let r = common::upload(addr, "tet.off", off).await;
    assert_eq!(r.status, 200, "{}", r.error());
    assert_eq!(r.json()["n"], 4);
    assert_eq!(r.json()["source"], "tet.off");
    assert_eq!(r.json()["info"]["euler_characteristic"], 2);

    // Two tetrahedra, constraints on one: the other floats and is left out of the check.
    let two = b"OFF\n8 8 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n5 0 0\n6 0 0\n5 1 0\n5 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 4 6 5\n3 4 5 7\n3 4 7 6\n3 5 6 7\n";
    let r = common::upload(addr, "two.off", two).await;
    assert_eq!(r.status, 200, "{}", r.error());
    let two_id = r.json()["mesh_id"].as_str().unwrap().to_string();
    let f = post_field(addr, &two_id, json!({"kind": "harmonic", "constraints": [{"vertex": 0, "value": 0.0}, {"vertex": 1, "value": 1.0}]}))
    .await
    .field();
    assert_eq!(
        f.header["floating"].as_array().unwrap().len(),
        1,
        "{}",
        f.header
    );
    assert_eq!(f.header["critical"]["excluded_components"], json!([1]));
    assert_eq!(
        f.header["critical"]["holds"], true,
        "{}",
        f.header["critical"]
    );
}

/// Basis jobs: the same or a smaller request joins the running one; other parameters
/// replace it (its solve is cancelled: the eigensolver checks its token inside the
/// iteration); DELETE cancels.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn basis_jobs_join_and_cancel() {
    let addr = start(1 << 20).await;
    let (id, _) = load(addr, "sphere:res=5").await;
    let path = format!("/api/mesh/{id}/basis");
    let r = post_json(addr, &path, json!({"k": 300})).await;
    assert_eq!(r.status, 202, "{}", r.error());
    for k in [300, 200] {
        let r = post_json(addr, &path, json!({ "k": k })).await;
        assert_eq!(r.status, 202);
        assert_eq!(r.json()["k"], 300, "k = {k} joins the running job");
    }
    // More pairs of the same analysis: a new job replaces the running one.
    let r = post_json(addr, &path, json!({"k": 350})).await;
    assert_eq!(r.status, 202);
    assert_eq!(r.json()["k"], 350);
    let r = request(addr, "DELETE", &path, "text/plain", "", b"").await;
    assert_eq!(r.status, 200, "{}", r.error());
    let st = wait_basis(addr, &id).await;
    assert_eq!(st["state"], "cancelled", "{st}");
    assert_eq!(st["k"], 350);
    // Neither solve finished: nothing is held, and a field request says what to do.
    assert_eq!(st["held_k"], 0, "{st}");
    let r = post_field(addr, &id, json!({"kind": "heat", "k": 50})).await;
    assert_eq!(r.status, 409, "{}", r.text());
    // A fresh request computes and then serves fields.
    let r = post_json(addr, &path, json!({"k": 50})).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let st = wait_basis(addr, &id).await;
    assert_eq!(st["state"], "done", "{st}");
    assert_eq!(st["held_k"], 50, "{st}");
    let r = post_field(addr, &id, json!({"kind": "heat", "k": 50})).await;
    assert_eq!(r.status, 200);
}

/// For every request kind with every default left alone, the web's field is the
/// library's `Analysis::field` (unit-area scale, default times, default source): the txt
/// download to 1e-12 (in fact to the bit), the binary reply to f32 rounding.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_kind_with_defaults_is_the_librarys_field() {
    let addr = start(1 << 20).await;
    let shape = "sphere:res=3";
    let (id, n) = load(addr, shape).await;
    let st = basis(addr, &id, json!({})).await;
    assert_eq!(st["k"], 100);
    assert_eq!(st["laplacian"], "fem");
    assert_eq!(st["normalize"], true);
    let an = Analysis::new(
        spectral_mesh::shapes::build_str(shape).unwrap(),
        AnalysisOptions::default(),
    );
    let bodies = [
        json!({"kind": "harmonic"}),
        json!({"kind": "heat"}),
        json!({"kind": "diffusion", "signal": {"impulse": 17}}),
        json!({"kind": "distance"}),
        json!({"kind": "distance", "distance": "wfem-diffusion"}),
        json!({"kind": "spectral-function"}),
        json!({"kind": "hks"}),
        json!({"kind": "wks", "energy": 4.0}),
        json!({"kind": "adf"}),
        json!({"kind": "segmentation"}),
        json!({"kind": "embedding"}),
        json!({"kind": "eigenfunction"}),
        json!({"kind": "green"}),
        json!({"kind": "geodesic"}),
    ];
    let mut kinds = std::collections::BTreeSet::new();
    for body in bodies {
        let req: FieldRequest = serde_json::from_value(body.clone()).unwrap();
        kinds.insert(req.kind());
        let lib = an.field(&req).unwrap();
        assert_eq!(lib.values.len(), n);
        let f = post_json(addr, &format!("/api/mesh/{id}/field"), body.clone())
            .await
            .field();
        let resolved: FieldRequest = serde_json::from_value(f.header["request"].clone()).unwrap();
        assert_eq!(resolved, lib.request, "{body}");
        for i in 0..n {
            assert_eq!(f.values[i], lib.values[i] as f32, "{body} vertex {i}");
        }
        let mut dl = body.clone();
        dl["format"] = json!("txt");
        let r = post_download(addr, &id, dl).await;
        assert_eq!(r.status, 200, "{body}: {}", r.text());
        let txt = numbers(&r.text());
        assert_eq!(lib.values.len(), n);
        common::assert_close(&txt, &lib.values, 1e-12, &format!("{body} vertex"));
    }
    assert_eq!(
        kinds.len(),
        spectral_mesh::analysis::request::KINDS.len(),
        "every kind is tested"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_is_a_4xx_with_a_message_and_the_server_stays_up() {
    let addr = start(4096).await;
    let (id, n) = load(addr, "sphere:res=1").await;
    let field = format!("/api/mesh/{id}/field");
    let basis_path = format!("/api/mesh/{id}/basis");
    basis(addr, &id, json!({"k": 20})).await;

    use Req::{Get, Json, Raw};
    // (name, request): a JSON body posted, a GET, or a raw request (method, path, content
    // type, extra header lines, body).
    #[rustfmt::skip]
    let bad = [
        ("malformed upload",
            Raw("POST", "/api/mesh".into(), "application/octet-stream",
                "X-Filename: broken.off\r\n", b"OFF\n3 1 0\n0 0 0\n1 zero 0\n".to_vec())),
        ("out-of-range face",
            Raw("POST", "/api/mesh".into(), "application/octet-stream", "",
                b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n".to_vec())),
        ("oversized upload",
            Raw("POST", "/api/mesh".into(), "application/octet-stream", "", vec![b'0'; 100_000])),
        ("unknown shape", Json("/api/mesh".into(), json!({"shape": "klein-bottle-9"}))),
        ("bad JSON", Raw("POST", "/api/mesh".into(), "application/json", "", b"{shape:".to_vec())),
        ("vertex out of range", Json(field.clone(), json!({"kind": "heat", "k": 20, "anchor": n}))),
        ("constraint vertex out of range",
            Json(field.clone(),
                json!({"kind": "harmonic", "constraints": [{"vertex": 0, "value": 0}, {"vertex": 99999, "value": 1}]}))),
        ("t = NaN",
            Raw("POST", field.clone(), "application/json", "",
                br#"{"kind":"heat","k":20,"t":NaN}"#.to_vec())),
        ("t < 0", Json(field.clone(), json!({"kind": "heat", "k": 20, "t": -1.0}))),
        ("k > n", Json(basis_path.clone(), json!({"k": n + 1}))),
        ("k > n in a field", Json(field.clone(), json!({"kind": "heat", "k": n + 5}))),
        ("unknown laplacian", Json(basis_path.clone(), json!({"laplacian": "nope", "k": 5}))),
        ("unknown basis key", Json(basis_path.clone(), json!({"pairs": 5}))),
        ("bad custom expression",
            Json(field.clone(),
                json!({"kind": "distance", "k": 20, "distance": "custom-w:exp(-t*;t=1"}))),
        ("non-positive custom weight",
            Json(field.clone(),
                json!({"kind": "distance", "k": 20, "distance": "custom-w:s-1000"}))),
        ("unknown kind", Json(field.clone(), json!({"kind": "astrology"}))),
        ("no kind (the old protocol)", Json(field.clone(), json!({"experiment": "heat", "k": 20}))),
        ("unknown request key",
            Json(field.clone(), json!({"kind": "heat", "k": 20, "filter": "commute"}))),
        ("too many levels",
            Json(field.clone(), json!({"kind": "heat", "k": 20, "levels": 100000}))),
        ("bad mesh id", Get("/api/mesh/..%2F..%2Fetc/geometry".into())),
        ("unknown mesh", Get("/api/mesh/0123456789abcdef/geometry".into())),
        ("bad download format",
            Json(format!("/api/mesh/{id}/download"),
                json!({"kind": "heat", "k": 20, "format": "exe"}))),
        ("download without a body", Get(format!("/api/mesh/{id}/download?format=txt"))),
        ("picture too large",
            Json(format!("/api/mesh/{id}/download"),
                json!({"kind": "heat", "k": 20, "format": "png", "size": 100000}))),
    ];
    let mut cases: Vec<(&str, Reply)> = Vec::new();
    for (name, req) in bad {
        cases.push((name, send(addr, req).await));
    }
    for (what, r) in &cases {
        assert!(
            (400..500).contains(&r.status),
            "{what}: status {} body {}",
            r.status,
            String::from_utf8_lossy(&r.body)
        );
        assert!(!r.error().is_empty(), "{what}: no JSON error message");
    }
    let by = |name: &str| &cases.iter().find(|c| c.0 == name).unwrap().1;
    assert_eq!(by("oversized upload").status, 413);
    assert!(by("unknown shape").error().contains("unknown shape"));
    assert!(by("vertex out of range").error().contains("out of range"));
    assert!(by("unknown request key").error().contains("filter"));
    assert!(by("no kind (the old protocol)").error().contains("kind"));
    let e = by("bad custom expression").error();
    assert!(e.contains("exp(-t*"), "{e}");
    // The server is still up and still answers correctly.
    let r = post_json(addr, &field, json!({"kind": "heat", "k": 20, "anchor": 1})).await;
    assert_eq!(r.status, 200);
    assert_eq!(get(addr, "/api/health").await.json()["ok"], true);
}

/// The experiment file of a download, replayed the way `spectral-mesh run` does it (the
/// mesh from its spec, checked against `mesh_hash`; an analysis with the file's
/// discretization and normalisation; a basis of `basis_k` pairs; the `[field]` request;
/// the render crate's text), gives the text download byte for byte.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_toml_download_replays_to_the_txt_download() {
    let addr = start(1 << 20).await;
    let (id, _) = load(addr, "sphere:res=3").await;
    basis(addr, &id, json!({"k": 50, "laplacian": "voronoi-cot"})).await;
    let dl = format!("/api/mesh/{id}/download");
    for request in [
        json!({"kind": "heat", "t": 0.01, "k": 30, "laplacian": "voronoi-cot"}),
        json!({"kind": "distance", "distance": "wfem-diffusion:t=0.05", "k": 50, "laplacian": "voronoi-cot"}),
        json!({"kind": "segmentation", "k": 20, "laplacian": "voronoi-cot"}),
        json!({"kind": "harmonic", "order": 2, "laplacian": "voronoi-cot"}),
    ] {
        let mut body = request.clone();
        body["format"] = json!("txt");
        let txt = post_json(addr, &dl, body.clone()).await;
        assert_eq!(txt.status, 200, "{}", txt.text());
        body["format"] = json!("toml");
        let toml = post_json(addr, &dl, body).await;
        let exp = ExperimentFile::parse(&toml.text(), "web.toml").unwrap();
        let mesh = spectral_mesh::shapes::build_str(&exp.mesh).unwrap();
        assert_eq!(exp.mesh_hash, Some(mesh.content_hash()));
        let an = Analysis::new(
            mesh,
            AnalysisOptions {
                laplacian: exp.laplacian().unwrap(),
                normalize: exp.normalize(),
                ..Default::default()
            },
        );
        let req = exp.request().unwrap();
        if let Some(k) = exp.basis_k.or(req.eigenpairs()) {
            an.basis(k, &mut |_| {}, &Default::default()).unwrap();
        }
        let field = an.field(&req).unwrap();
        let options =
            spectral_mesh_render::figure::FigureOptions::from_file(&exp.figure.unwrap()).unwrap();
        let fig =
            spectral_mesh_render::figure::Figure::of_field(an.mesh(), &field, options).unwrap();
        assert!(fig.txt() == txt.body, "{request}: the replay differs");
    }
}

/// A geodesic distance needs no basis; its reply is the library's field (the text
/// download to the last bit), with its isolines and the source at 0; a component the
/// source cannot reach is infinite, said in the header and left out of the critical
/// points; bad sources and Laplacians are 422s naming them.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn geodesic_fields_need_no_basis_and_say_what_they_cannot_reach() {
    let addr = start(1 << 20).await;
    let (id, n) = load(addr, "3torus").await;
    let body = json!({"kind": "geodesic", "source": 5, "levels": 12});
    let f = post_field(addr, &id, body.clone()).await.field();
    let h = &f.header;
    assert_eq!(h["kind"], "geodesic");
    assert_eq!(h["source"], 5);
    assert_eq!(h["k"], Value::Null);
    assert_eq!(
        h["normalized"], false,
        "a geodesic distance is in mesh units"
    );
    assert_eq!(h["request"]["time_factor"], 1.0);
    assert_eq!(h["request"]["convention"], "crane");
    assert_eq!(h["unreachable"], json!([]));
    assert_eq!(h["unreachable_message"], Value::Null);
    assert_eq!(f.values.len(), n);
    assert_eq!(f.values[5], 0.0);
    assert_eq!(h["min"], 0.0);
    let levels = h["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 12);
    // Evenly spaced isolines, each one drawn.
    let step = levels[1].as_f64().unwrap() - levels[0].as_f64().unwrap();
    for w in levels.windows(2) {
        let d = w[1].as_f64().unwrap() - w[0].as_f64().unwrap();
        assert!(
            (d - step).abs() <= 1e-12 * step.abs().max(1.0),
            "{levels:?}"
        );
    }
    assert!(
        h["level_counts"]
            .as_array()
            .unwrap()
            .iter()
            .all(|c| c.as_u64().unwrap() > 0),
        "{}",
        h["level_counts"]
    );
    let minima = h["critical"]["points"]["minima"].as_array().unwrap();
    assert!(minima.contains(&json!(5)), "{minima:?}");
    // The library's numbers.
    let an = Analysis::new(
        spectral_mesh::shapes::build_str("3torus").unwrap(),
        AnalysisOptions::default(),
    );
    let lib = an
        .field(
            &serde_json::from_value::<FieldRequest>(json!({"kind": "geodesic", "source": 5}))
                .unwrap(),
        )
        .unwrap();
    for (a, b) in f.values.iter().zip(&lib.values) {
        assert_eq!(*a, *b as f32);
    }
    let text = download_txt(addr, &id, json!({"kind": "geodesic", "source": 5})).await;
    assert_eq!(numbers(&text), lib.values);

    // Two tetrahedra: the second is out of reach of a source on the first.
    let two = b"OFF\n8 8 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n5 0 0\n6 0 0\n5 1 0\n5 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 4 6 5\n3 4 5 7\n3 4 7 6\n3 5 6 7\n";
    let r = common::upload(addr, "two.off", two).await;
    assert_eq!(r.status, 200, "{}", r.error());
    let two_id = r.json()["mesh_id"].as_str().unwrap().to_string();
    let f = post_field(addr, &two_id, json!({"kind": "geodesic", "source": 0}))
        .await
        .field();
    let h = &f.header;
    assert_eq!(h["unreachable"], json!([1]));
    let msg = h["unreachable_message"].as_str().unwrap();
    assert!(
        msg.starts_with("4 of 8 vertices cannot be reached"),
        "{msg}"
    );
    assert!(msg.contains("infinite"), "{msg}");
    assert!(f.values[..4].iter().all(|v| v.is_finite()));
    assert!(f.values[4..].iter().all(|&v| v == f32::INFINITY));
    assert!(h["max"].as_f64().unwrap() > 0.0, "{h}");
    assert_eq!(h["critical"]["excluded_components"], json!([1]));
    let cp = &h["critical"]["points"];
    for key in ["minima", "maxima"] {
        assert!(
            cp[key]
                .as_array()
                .unwrap()
                .iter()
                .all(|v| v.as_u64().unwrap() < 4),
            "{cp}"
        );
    }
    let text = download_txt(addr, &two_id, json!({"kind": "geodesic", "source": 0})).await;
    assert!(text.lines().skip(4).all(|l| l == "inf"), "{text}");

    for (body, says) in [
        (
            json!({"kind": "geodesic", "source": 8}),
            "source 8 is out of range",
        ),
        (
            json!({"kind": "geodesic", "sources": [1, 9]}),
            "sources 9 is out of range",
        ),
        (json!({"kind": "geodesic", "time_factor": 0}), "time_factor"),
        (
            json!({"kind": "geodesic", "laplacian": "uniform"}),
            "cotangent Laplacian",
        ),
    ] {
        let r = post_field(addr, &two_id, body.clone()).await;
        assert_eq!(r.status, 422, "{body}: {}", r.text());
        assert!(r.error().contains(says), "{body}: {}", r.error());
    }
}

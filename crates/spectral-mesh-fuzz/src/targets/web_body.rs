//! The web app's JSON bodies through the server's own handlers: the axum `Router` of
//! `spectral_mesh_web::api::router`, driven in process (`tower::ServiceExt::oneshot`, no
//! socket), on a fresh server state per input holding two small built-in meshes with
//! their eigenbases (`sphere:res=2`, 162 vertices, closed, fem basis of 100 pairs;
//! `disk:res=0`, 127 vertices, with a boundary, fem basis of all 127 pairs) and small
//! limits (16 MiB of memory, shapes of at most 400 vertices, k <= 200, JSON bodies of at
//! most 64 KiB, 1 s per request), so that no input can make one execution slow.
//!
//! Input: up to 4 requests separated by `\n---\n`. Each starts with a selector byte:
//! - bits 0-2, the endpoint: 0, 6, 7 `POST /api/mesh/{id}/field`; 1 `POST .../download`;
//!   2 `GET .../download?format=F&body=BYTES` (URL-encoded); 3 `POST .../basis` (then the
//!   job is polled to its end); 4 `POST /api/mesh` with `{"shape": ...}`; 5 `DELETE
//!   .../basis` and `GET .../basis/status` (no body);
//! - bits 3-4, the mesh: the sphere, the disk, the last mesh this input loaded (else the
//!   sphere), or an id that is not loaded;
//! - bits 5-6, `F` of the GET download: none (the body's `format`), `txt`, `png`, `toml`;
//! - bit 7: no `Content-Length` header (the body is read to its end).
//!
//! The rest of the part is the body, as the page sends it (`Content-Type:
//! application/json`). Asserted for every answer, beyond "no panic":
//! - the status is 2xx, 4xx or 503: never a 500 or another 5xx;
//! - a 4xx or 503 has a JSON body `{"error": "..."}` with a non-empty message; a message
//!   that names a key of the body at fault (`KEY: ...`, or serde's ``unknown field `KEY` ``)
//!   names one the body has;
//! - a field (200) is a well-formed binary reply (`field::parse_reply`): `n` values for
//!   the mesh's `n`, all finite, finite level sets and `min`/`max`/levels/`lambda_max`
//!   as numbers, 6 coordinates per segment counted by `level_counts`; the resolved
//!   request of its header sent back gives the same values (the documented promise);
//! - a download (200) is what its type says: a PNG, VRML or PLY file, one finite value
//!   per vertex (`txt`, read back with `io::read_field_text`), or an experiment file that
//!   `ExperimentFile::parse` accepts (`toml`);
//! - a basis request answers a job (`state`), which ends (polled): `done` on the
//!   built-in meshes (`error` or `cancelled` with a message allowed on a shape this input
//!   loaded; on any mesh, a 404 when the job's memory evicted the mesh);
//! - a shape answers `mesh_id` (16 hex digits), `n` and `m` within the limits.

use std::sync::{Arc, OnceLock};
use std::time::Duration;

use axum::Router;
use axum::body::Body;
use axum::http::{Method, Request, StatusCode, header};
use serde_json::{Value, json};
use spectral_mesh::analysis::{Analysis, AnalysisOptions};
use spectral_mesh::{Eigenbasis, Laplacian, Mesh, Operators};
use spectral_mesh_web::entries::AnalysisKey;
use spectral_mesh_web::state::AppState;
use spectral_mesh_web::{Limits, ServeConfig, api, field::parse_reply};
use tower::ServiceExt;

/// Separates the requests of one input.
const SEP: &[u8] = b"\n---\n";
/// Most requests per input.
const MAX_PARTS: usize = 4;
/// An id no mesh has.
const UNKNOWN_ID: &str = "0123456789abcdef";
/// The built-in meshes loaded in every state: (shape, eigenpairs held).
const MESHES: [(&str, usize); 2] = [("sphere:res=2", 100), ("disk:res=0", 127)];

/// The server's limits: small, so that nothing a body asks for can take long (every
/// field named; the default fills any the server adds later).
#[allow(clippy::needless_update)]
fn limits() -> Limits {
    Limits {
        memory_bytes: 16 << 20,
        cache_bytes: 8 << 20,
        max_upload_bytes: 1 << 20,
        max_json_bytes: 64 << 10,
        max_vertices: 400,
        max_faces: 1000,
        max_k: 200,
        max_jobs: 2,
        max_queued: 4,
        job_seconds: 2,
        job_idle_seconds: 10,
        request_seconds: 1,
        max_requests: 16,
        idle_seconds: 0,
        ..Limits::default()
    }
}

/// A reply, read whole.
struct Reply {
    status: StatusCode,
    content_type: String,
    body: Vec<u8>,
}

impl Reply {
    fn json(&self) -> Value {
        serde_json::from_slice(&self.body).unwrap_or(Value::Null)
    }
}

fn request(method: Method, uri: &str, body: Vec<u8>, content_length: bool) -> Request<Body> {
    let mut b = Request::builder()
        .method(method)
        .uri(uri)
        .header(header::HOST, "127.0.0.1:8000");
    if !body.is_empty() {
        b = b.header(header::CONTENT_TYPE, "application/json");
    }
    if content_length {
        b = b.header(header::CONTENT_LENGTH, body.len());
    }
    b.body(Body::from(body)).expect("a well-formed request")
}

async fn send(app: &Router, req: Request<Body>) -> Reply {
    let r = app
        .clone()
        .oneshot(req)
        .await
        .expect("the router is infallible");
    let status = r.status();
    let content_type = r
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string();
    let body = axum::body::to_bytes(r.into_body(), usize::MAX)
        .await
        .expect("a reply body reads")
        .to_vec();
    Reply {
        status,
        content_type,
        body,
    }
}

/// A built-in mesh: its id and what its basis is made from.
struct Builtin {
    shape: &'static str,
    id: String,
    n: usize,
    mesh: Arc<Mesh>,
    /// The fem operators as assembled (before the unit-area normalisation).
    ops: Operators,
    /// The eigenbasis of the normalised fem operators.
    basis: Eigenbasis,
}

struct Fixture {
    rt: tokio::runtime::Runtime,
    config: ServeConfig,
    meshes: Vec<Builtin>,
}

fn config() -> ServeConfig {
    ServeConfig {
        limits: limits(),
        ..ServeConfig::default()
    }
}

fn fem() -> AnalysisOptions {
    AnalysisOptions {
        laplacian: Laplacian::Fem,
        normalize: true,
        ..AnalysisOptions::default()
    }
}

/// Loads `shape` through the router (`POST /api/mesh`): its id.
async fn load_shape(app: &Router, shape: &str) -> String {
    let body = serde_json::to_vec(&json!({ "shape": shape })).expect("JSON");
    let r = send(app, request(Method::POST, "/api/mesh", body, true)).await;
    assert_eq!(r.status, StatusCode::OK, "loading {shape}");
    r.json()["mesh_id"].as_str().expect("mesh_id").to_string()
}

fn setup() -> Fixture {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("a tokio runtime");
    let config = config();
    let state = Arc::new(AppState::new(config.clone()));
    let app = api::router(state.clone());
    let meshes = rt.block_on(async {
        let mut out = Vec::new();
        for (shape, k) in MESHES {
            let id = load_shape(&app, shape).await;
            let mesh = Arc::new(spectral_mesh::shapes::build_str(shape).expect("a built-in shape"));
            assert_eq!(
                &mesh.content_hash()[..16],
                id,
                "{shape}: the id is the content hash"
            );
            let ops = Operators::new(&mesh, Laplacian::Fem);
            let analysis = Analysis::with_operators(mesh.clone(), ops.clone(), fem());
            let basis = analysis
                .basis(
                    k,
                    &mut |_: spectral_mesh::linalg::EigenProgress| {},
                    &spectral_mesh::CancelToken::new(),
                )
                .expect("the basis of a built-in mesh");
            out.push(Builtin {
                shape,
                id,
                n: mesh.n_vertices(),
                mesh,
                ops,
                basis: (*basis).clone(),
            });
        }
        out
    });
    Fixture { rt, config, meshes }
}

/// A fresh server state with the built-in meshes loaded through the router and their
/// fem bases installed (nothing an input does carries over to the next input).
async fn fresh(f: &Fixture) -> (Arc<AppState>, Router) {
    let state = Arc::new(AppState::new(f.config.clone()));
    let app = api::router(state.clone());
    for m in &f.meshes {
        let id = load_shape(&app, m.shape).await;
        assert_eq!(id, m.id, "{}", m.shape);
        let a = Analysis::with_operators(m.mesh.clone(), m.ops.clone(), fem());
        a.set_basis(m.basis.clone()).expect("the basis fits");
        let key = AnalysisKey {
            id: m.id.clone(),
            laplacian: Laplacian::Fem,
            normalize: true,
        };
        state.remember(&key, &Arc::new(a));
    }
    (state, app)
}

/// True when `key` is a key of an object anywhere in `v`.
fn has_key(v: &Value, key: &str) -> bool {
    match v {
        Value::Object(m) => m.contains_key(key) || m.values().any(|x| has_key(x, key)),
        Value::Array(a) => a.iter().any(|x| has_key(x, key)),
        _ => false,
    }
}

/// True when serde's ``unknown field `KEY` `` in `msg` names a key of `v` (the keys are
/// compared whole: one may hold a backquote).
fn names_unknown_key(v: &Value, msg: &str) -> bool {
    match v {
        Value::Object(m) => m.iter().any(|(k, x)| {
            msg.contains(&format!("unknown field `{k}`")) || names_unknown_key(x, msg)
        }),
        Value::Array(a) => a.iter().any(|x| names_unknown_key(x, msg)),
        _ => false,
    }
}

/// The key a refusal says is at fault: `KEY: ...` (after a `field request: ` prefix) or
/// the library's `KEY 123 is out of range`, KEY a lowercase word.
fn blamed_key(msg: &str) -> Option<&str> {
    let word = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_lowercase() || b == b'_');
    let m = msg.strip_prefix("field request: ").unwrap_or(msg);
    if let Some((head, _)) = m.split_once(" is out of range")
        && let Some((key, number)) = head.split_once(' ')
        && word(key)
        && number.bytes().all(|b| b.is_ascii_digit())
    {
        return Some(key);
    }
    let (head, _) = m.split_once(": ")?;
    word(head).then_some(head)
}

/// A refusal: 4xx or 503 with `{"error": message}`; a key it blames is in the body.
fn check_refusal(what: &str, r: &Reply, body: Option<&Value>) {
    let j = r.json();
    let msg = j["error"].as_str().unwrap_or_else(|| {
        panic!(
            "{what}: {} without a JSON error: {:?}",
            r.status,
            String::from_utf8_lossy(&r.body)
        )
    });
    assert!(
        !msg.trim().is_empty(),
        "{what}: {} with an empty message",
        r.status
    );
    let Some(body) = body.filter(|b| b.is_object()) else {
        return;
    };
    if !r.status.is_client_error() {
        return;
    }
    if msg.contains("unknown field `") {
        assert!(
            names_unknown_key(body, msg),
            "{what}: {} names an unknown field the body {body} does not have: {msg}",
            r.status
        );
    } else if let Some(key) = blamed_key(msg) {
        // A default can be at fault against a value given: the default `index` or
        // `component` (1) with `k = 1`.
        let default_at_fault =
            matches!(key, "index" | "component") && msg.contains("out of range for k");
        assert!(
            has_key(body, key) || default_at_fault,
            "{what}: {} blames `{key}`, which the body {body} does not have: {msg}",
            r.status
        );
    }
}

/// The status is 2xx, 4xx or 503 (a 4xx/503 checked by [`check_refusal`]); true for 2xx.
fn accepted(what: &str, r: &Reply, body: Option<&Value>) -> bool {
    let s = r.status;
    if s.is_success() {
        return true;
    }
    assert!(
        s.is_client_error() || s == StatusCode::SERVICE_UNAVAILABLE,
        "{what}: status {s}: {}",
        String::from_utf8_lossy(&r.body)
    );
    check_refusal(what, r, body);
    false
}

/// A field reply: well formed, `n` finite values, finite level sets. Returns the values
/// and the header.
fn check_field(what: &str, r: &Reply, n: usize) -> (Vec<f32>, Value) {
    assert_eq!(r.content_type, "application/octet-stream", "{what}");
    let p = parse_reply(&r.body).unwrap_or_else(|e| panic!("{what}: bad field reply: {e}"));
    let h = &p.header;
    assert_eq!(h["n"].as_u64(), Some(n as u64), "{what}: header n");
    assert_eq!(p.values.len(), n, "{what}: values");
    if let Some(i) = p.values.iter().position(|v| !v.is_finite()) {
        panic!("{what}: value {i} is {} (header {h})", p.values[i]);
    }
    assert!(
        p.segments.iter().all(|v| v.is_finite()),
        "{what}: non-finite level-set coordinate (header {h})"
    );
    let (min, max) = (h["min"].as_f64(), h["max"].as_f64());
    let (Some(min), Some(max)) = (min, max) else {
        panic!("{what}: min/max not numbers (non-finite?): {h}")
    };
    assert!(min <= max, "{what}: min {min} > max {max}");
    let levels = h["levels"].as_array().expect("levels");
    assert!(
        levels.iter().all(|l| l.as_f64().is_some()),
        "{what}: a level is not a number: {h}"
    );
    assert!(
        h["lambda_max"].is_null() || h["lambda_max"].as_f64().is_some(),
        "{what}: lambda_max {}",
        h["lambda_max"]
    );
    let counts: u64 = h["level_counts"]
        .as_array()
        .expect("level_counts")
        .iter()
        .map(|c| c.as_u64().expect("a count"))
        .sum();
    assert_eq!(
        6 * counts as usize,
        p.segments.len(),
        "{what}: level_counts against the segments"
    );
    assert_eq!(
        h["critical"].is_null(),
        h["categorical"] == json!(true),
        "{what}: critical points exactly when the field is not categorical: {h}"
    );
    (p.values, p.header)
}

/// A download: what its content type says.
fn check_download(what: &str, r: &Reply, n: usize) {
    let b = &r.body;
    assert!(!b.is_empty(), "{what}: empty download");
    match r.content_type.as_str() {
        "image/png" => assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{what}: not a PNG"),
        "model/vrml" => assert!(b.starts_with(b"#VRML"), "{what}: not VRML"),
        "application/octet-stream" => assert!(b.starts_with(b"ply"), "{what}: not a PLY"),
        "application/toml" => {
            let text = std::str::from_utf8(b).expect("TOML is UTF-8");
            if let Err(e) =
                spectral_mesh::experiments::file::ExperimentFile::parse(text, "download")
            {
                panic!("{what}: the experiment file does not parse: {e}\n{text}");
            }
        }
        "text/plain; charset=utf-8" => {
            let text = std::str::from_utf8(b).expect("text is UTF-8");
            if let Err(e) = spectral_mesh::io::read_field_text(text, "download", Some(n)) {
                panic!("{what}: the field file does not read back: {e}");
            }
        }
        other => panic!("{what}: unexpected content type {other}"),
    }
}

/// Percent-encodes every byte but the unreserved ones.
fn url_encode(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 3);
    for &b in bytes {
        if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
            s.push(b as char);
        } else {
            s.push_str(&format!("%{b:02X}"));
        }
    }
    s
}

/// Polls the basis job of mesh `id` until it is neither queued nor running (a job that
/// never ends is a hang for libFuzzer's `-timeout`): its final JSON, or `{"state": "evicted"}` when the mesh left the cache (the
/// job's memory may have evicted it: a 404 with its message).
async fn wait_job(app: &Router, id: &str) -> Value {
    loop {
        let r = send(
            app,
            request(
                Method::GET,
                &format!("/api/mesh/{id}/basis/status"),
                Vec::new(),
                true,
            ),
        )
        .await;
        if r.status == StatusCode::NOT_FOUND {
            check_refusal("basis status", &r, None);
            return json!({"state": "evicted", "message": r.json()["error"]});
        }
        assert_eq!(r.status, StatusCode::OK, "basis status");
        let j = r.json();
        let state = j["state"].as_str().expect("a job state").to_string();
        if state != "queued" && state != "running" {
            return j;
        }
        tokio::time::sleep(Duration::from_millis(2)).await;
    }
}

fn split_parts(data: &[u8]) -> Vec<&[u8]> {
    let mut parts = Vec::new();
    let mut rest = data;
    while parts.len() + 1 < MAX_PARTS {
        match rest.windows(SEP.len()).position(|w| w == SEP) {
            Some(i) => {
                parts.push(&rest[..i]);
                rest = &rest[i + SEP.len()..];
            }
            None => break,
        }
    }
    parts.push(rest);
    parts
}

static FIXTURE: OnceLock<Fixture> = OnceLock::new();

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let f = FIXTURE.get_or_init(setup);
    f.rt.block_on(async {
        let (state, app) = fresh(f).await;
        // The last mesh this input loaded: (id, vertices).
        let mut last: Option<(String, usize)> = None;
        for part in split_parts(data) {
            let Some((&sel, body)) = part.split_first() else {
                continue;
            };
            let (id, n, builtin) = match (sel >> 3) & 3 {
                0 => (f.meshes[0].id.clone(), f.meshes[0].n, true),
                1 => (f.meshes[1].id.clone(), f.meshes[1].n, true),
                2 => match &last {
                    Some((id, n)) => (id.clone(), *n, false),
                    None => (f.meshes[0].id.clone(), f.meshes[0].n, true),
                },
                _ => (UNKNOWN_ID.to_string(), 0, false),
            };
            let with_length = sel & 0x80 == 0;
            let parsed: Option<Value> = serde_json::from_slice(body).ok();
            let what = format!(
                "selector {sel:#04x} on {id}, body {:?}",
                String::from_utf8_lossy(body)
            );
            match sel & 7 {
                1 | 2 => {
                    let req = if sel & 7 == 1 {
                        let uri = format!("/api/mesh/{id}/download");
                        request(Method::POST, &uri, body.to_vec(), with_length)
                    } else if body.len() > 8192 {
                        continue; // (a URI of at most 64 kB: the http crate's limit)
                    } else {
                        let format = ["", "&format=txt", "&format=png", "&format=toml"]
                            [usize::from((sel >> 5) & 3)];
                        let uri =
                            format!("/api/mesh/{id}/download?body={}{format}", url_encode(body));
                        request(Method::GET, &uri, Vec::new(), true)
                    };
                    let r = send(&app, req).await;
                    if accepted(&what, &r, parsed.as_ref()) {
                        assert_eq!(r.status, StatusCode::OK, "{what}");
                        check_download(&what, &r, n);
                    }
                }
                3 => {
                    let uri = format!("/api/mesh/{id}/basis");
                    let r = send(
                        &app,
                        request(Method::POST, &uri, body.to_vec(), with_length),
                    )
                    .await;
                    if accepted(&what, &r, parsed.as_ref()) {
                        let j = r.json();
                        let st = j["state"].as_str().unwrap_or_else(|| {
                            panic!("{what}: {} without a job state: {j}", r.status)
                        });
                        let done = if r.status == StatusCode::ACCEPTED {
                            wait_job(&app, &id).await
                        } else {
                            assert_eq!(r.status, StatusCode::OK, "{what}");
                            assert_eq!(st, "done", "{what}: 200 for a job {j}");
                            j
                        };
                        let end = done["state"].as_str().unwrap_or("");
                        if builtin && end != "evicted" {
                            assert_eq!(end, "done", "{what}: basis job on a built-in mesh: {done}");
                        } else {
                            assert!(
                                ["done", "error", "cancelled", "evicted"].contains(&end),
                                "{what}: job ended as {done}"
                            );
                        }
                        if end != "done" {
                            let m = done["message"].as_str().unwrap_or("");
                            assert!(!m.is_empty(), "{what}: a job ended {end} without a message");
                        }
                    }
                }
                4 => {
                    let r = send(
                        &app,
                        request(Method::POST, "/api/mesh", body.to_vec(), with_length),
                    )
                    .await;
                    if accepted(&what, &r, parsed.as_ref()) {
                        let j = r.json();
                        let new_id = j["mesh_id"].as_str().unwrap_or_else(|| {
                            panic!("{what}: {} without a mesh_id: {j}", r.status)
                        });
                        assert!(
                            new_id.len() == 16 && new_id.bytes().all(|b| b.is_ascii_hexdigit()),
                            "{what}: mesh id {new_id}"
                        );
                        let (vn, vm) = (j["n"].as_u64(), j["m"].as_u64());
                        let (Some(vn), Some(vm)) = (vn, vm) else {
                            panic!("{what}: n, m: {j}")
                        };
                        let l = &f.config.limits;
                        assert!(
                            vn >= 3
                                && vn as usize <= l.max_vertices
                                && vm >= 1
                                && vm as usize <= l.max_faces,
                            "{what}: a mesh of {vn} vertices and {vm} triangles was accepted"
                        );
                        last = Some((new_id.to_string(), vn as usize));
                    }
                }
                5 => {
                    let uri = format!("/api/mesh/{id}/basis");
                    let r = send(&app, request(Method::DELETE, &uri, Vec::new(), true)).await;
                    if accepted(&what, &r, None) {
                        assert!(r.json()["state"].is_string(), "{what}: cancel: no job");
                    }
                    let uri = format!("/api/mesh/{id}/basis/status");
                    let r = send(&app, request(Method::GET, &uri, Vec::new(), true)).await;
                    if accepted(&what, &r, None) {
                        assert!(r.json()["state"].is_string(), "{what}: status: no job");
                    }
                }
                _ => {
                    let uri = format!("/api/mesh/{id}/field");
                    let r = send(
                        &app,
                        request(Method::POST, &uri, body.to_vec(), with_length),
                    )
                    .await;
                    if !accepted(&what, &r, parsed.as_ref()) {
                        continue;
                    }
                    assert_eq!(r.status, StatusCode::OK, "{what}");
                    let (values, header) = check_field(&what, &r, n);
                    // The resolved request sent back gives the same field.
                    let mut again = header["request"].clone();
                    let Some(obj) = again.as_object_mut() else {
                        panic!("{what}: the header's request is not an object: {header}")
                    };
                    let p = parsed.as_ref().expect("an accepted body is JSON");
                    for key in ["laplacian", "normalize"] {
                        if let Some(v) = p.get(key) {
                            obj.insert(key.into(), v.clone());
                        }
                    }
                    obj.insert("levels".into(), json!(0));
                    let bytes = serde_json::to_vec(&again).expect("JSON");
                    let r2 = send(&app, request(Method::POST, &uri, bytes, true)).await;
                    assert_eq!(
                        r2.status,
                        StatusCode::OK,
                        "{what}: the resolved request {again} was refused: {}",
                        String::from_utf8_lossy(&r2.body)
                    );
                    let (values2, _) = check_field(&what, &r2, n);
                    let scale = values.iter().fold(1e-30f32, |m, v| m.max(v.abs()));
                    for (i, (a, b)) in values.iter().zip(&values2).enumerate() {
                        assert!(
                            (a - b).abs() <= 1e-5 * scale,
                            "{what}: value {i} is {a}, but {b} for the resolved request {again}"
                        );
                    }
                }
            }
        }
        drop(app);
        drop(state);
    });
}

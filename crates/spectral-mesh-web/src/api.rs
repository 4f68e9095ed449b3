//! The router and its handlers. Every field is computed by the library's
//! [`spectral_mesh::analysis::Analysis`]; this module only parses, caches and encodes.

use std::sync::Arc;
use std::time::Instant;

use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, JsonRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::json;
use spectral_mesh::analysis::{Analysis, AnalysisError, request::DEFAULT_K};
use spectral_mesh::experiments::file::ExperimentFile;
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::spectral::eigenbasis::EigenError;
use spectral_mesh::{Laplacian, Mesh};
use spectral_mesh_render::figure::Figure;

use crate::body::{BodyError, FieldBody};
use crate::field::{FieldReply, field_reply};
use crate::state::{
    AnalysisKey, AppState, Item, Job, JobSlot, Key, MeshEntry, basis_bytes, mesh_bytes,
};

type St = State<Arc<AppState>>;

/// An error response: a status and a message, sent as `{"error": message}`.
#[derive(Debug)]
pub struct ApiError(pub StatusCode, pub String);

impl ApiError {
    fn bad(msg: impl Into<String>) -> Self {
        Self(StatusCode::BAD_REQUEST, msg.into())
    }
    fn unprocessable(msg: impl Into<String>) -> Self {
        Self(StatusCode::UNPROCESSABLE_ENTITY, msg.into())
    }
    fn not_found(msg: impl Into<String>) -> Self {
        Self(StatusCode::NOT_FOUND, msg.into())
    }
}

impl From<BodyError> for ApiError {
    fn from(b: BodyError) -> Self {
        Self::bad(b.0)
    }
}

impl From<AnalysisError> for ApiError {
    fn from(e: AnalysisError) -> Self {
        let status = match &e {
            AnalysisError::BasisTooSmall { .. } | AnalysisError::Eigen(EigenError::Cancelled) => {
                StatusCode::CONFLICT
            }
            AnalysisError::NoBasis | AnalysisError::CriticalPoints(_) => {
                StatusCode::INTERNAL_SERVER_ERROR
            }
            _ => StatusCode::UNPROCESSABLE_ENTITY,
        };
        Self(status, e.to_string())
    }
}

fn internal(e: impl std::fmt::Display) -> ApiError {
    ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string())
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.0, Json(json!({ "error": self.1 }))).into_response()
    }
}

type ApiResult<T> = Result<T, ApiError>;

/// Builds the router over `state`.
pub fn router(state: Arc<AppState>) -> Router {
    let limit = state.config.max_upload_bytes;
    Router::new()
        .route("/", get(index))
        .route("/index.html", get(index))
        .route("/app.js", get(app_js))
        .route("/style.css", get(style_css))
        .route("/vendor/three.module.js", get(three_js))
        .route("/vendor/OrbitControls.js", get(orbit_js))
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/api/health", get(health))
        .route("/api/shapes", get(shapes))
        .route("/api/mesh", post(load_mesh))
        .route("/api/mesh/{id}", get(mesh_info))
        .route("/api/mesh/{id}/geometry", get(geometry))
        .route(
            "/api/mesh/{id}/basis",
            post(start_basis).delete(cancel_basis),
        )
        .route("/api/mesh/{id}/basis/status", get(basis_status))
        .route("/api/mesh/{id}/field", post(field))
        .route(
            "/api/mesh/{id}/download",
            get(download_get).post(download_post),
        )
        .fallback(|| async { ApiError::not_found("no such page") })
        .layer(DefaultBodyLimit::max(limit))
        .with_state(state)
}

// ---------- static files (a fixed list: no path parameters) ----------

const INDEX_HTML: &str = include_str!("../static/index.html");
const APP_JS: &str = include_str!("../static/app.js");
const STYLE_CSS: &str = include_str!("../static/style.css");

async fn static_file(state: &AppState, name: &str, builtin: &'static str, mime: &str) -> Response {
    let body = match &state.config.static_dir {
        Some(dir) => match tokio::fs::read(dir.join(name)).await {
            Ok(b) => b,
            Err(e) => {
                return ApiError::not_found(format!("static file {name}: {e}")).into_response();
            }
        },
        None => builtin.as_bytes().to_vec(),
    };
    (
        [
            (header::CONTENT_TYPE, mime.to_string()),
            (header::CACHE_CONTROL, "no-cache".into()),
        ],
        body,
    )
        .into_response()
}

async fn index(State(s): St) -> Response {
    static_file(&s, "index.html", INDEX_HTML, "text/html; charset=utf-8").await
}
async fn app_js(State(s): St) -> Response {
    static_file(&s, "app.js", APP_JS, "text/javascript; charset=utf-8").await
}
async fn style_css(State(s): St) -> Response {
    static_file(&s, "style.css", STYLE_CSS, "text/css; charset=utf-8").await
}

/// The page's third-party assets (three.js), embedded by `build.rs` from npm's
/// `node_modules` at build time.
mod assets {
    include!(concat!(env!("OUT_DIR"), "/assets.rs"));
}

/// True when the binary carries its page's 3D library.
pub fn assets_embedded() -> bool {
    assets::THREE_MODULE_JS.is_some() && assets::ORBIT_CONTROLS_JS.is_some()
}

/// A vendored asset: from the `node_modules` folder the server was told about
/// (`--node-modules` or `SPECTRAL_MESH_WEB_NODE_MODULES`), else the copy embedded at build
/// time, else the source tree's `web/node_modules` (a binary built without npm). The
/// header `X-Spectral-Mesh-Asset` says which (`folder` or `embedded`).
async fn vendor(s: &AppState, rel: &str, embedded: Option<&'static [u8]>) -> Response {
    let told = s.config.node_modules.is_some()
        || std::env::var_os("SPECTRAL_MESH_WEB_NODE_MODULES").is_some();
    let reply = |origin: &'static str, body: Vec<u8>| {
        (
            [
                (header::CONTENT_TYPE, "text/javascript; charset=utf-8"),
                (header::CACHE_CONTROL, "max-age=3600"),
                (
                    header::HeaderName::from_static("x-spectral-mesh-asset"),
                    origin,
                ),
            ],
            body,
        )
            .into_response()
    };
    if let (Some(b), false) = (embedded, told) {
        return reply("embedded", b.to_vec());
    }
    let path = s.node_modules.join(rel);
    match tokio::fs::read(&path).await {
        Ok(b) => reply("folder", b),
        Err(_) => match embedded {
            Some(b) => reply("embedded", b.to_vec()),
            None => ApiError(
                StatusCode::NOT_FOUND,
                format!(
                    "the page's 3D library (three.js, {rel}) is not in this binary: {}. Build the binary from the source tree with npm installed (`cargo build` runs `npm ci` in web/), or pass --node-modules with a folder holding npm's three package",
                    if assets::MISSING_WHY.is_empty() { "not embedded" } else { assets::MISSING_WHY }
                ),
            )
            .into_response(),
        },
    }
}
async fn three_js(State(s): St) -> Response {
    vendor(&s, "three/build/three.module.js", assets::THREE_MODULE_JS).await
}
async fn orbit_js(State(s): St) -> Response {
    vendor(
        &s,
        "three/examples/jsm/controls/OrbitControls.js",
        assets::ORBIT_CONTROLS_JS,
    )
    .await
}

// ---------- meshes ----------

async fn health(State(s): St) -> Json<serde_json::Value> {
    Json(json!({
        "ok": true,
        "cache_used": s.cache.used(),
        "cache_capacity": s.cache.capacity(),
        "cache_entries": s.cache.len(),
    }))
}

async fn shapes() -> Json<serde_json::Value> {
    let list: Vec<_> = spectral_mesh::shapes::shape_names()
        .into_iter()
        .map(|s| {
            json!({"name": s.name, "description": s.description,
                   "default_vertices": s.default_vertices, "vertex_formula": s.vertex_formula})
        })
        .collect();
    Json(json!({ "shapes": list }))
}

#[derive(Deserialize)]
struct ShapeBody {
    shape: String,
}

fn check_id(id: &str) -> ApiResult<()> {
    if id.len() == 16 && id.bytes().all(|b| b.is_ascii_hexdigit()) {
        Ok(())
    } else {
        Err(ApiError::bad("a mesh id is 16 hexadecimal digits"))
    }
}

fn info_json(mesh: &Mesh, topo: &Topology) -> serde_json::Value {
    let report = spectral_mesh::mesh::validate::report(mesh);
    let problems = report.problems();
    let (lo, hi) = (report.bbox_min, report.bbox_max);
    let genus: Option<i64> = topo
        .components
        .iter()
        .map(|c| c.genus)
        .try_fold(0i64, |acc, g| g.map(|g| acc + g));
    json!({
        "vertices": mesh.n_vertices(),
        "triangles": mesh.n_triangles(),
        "edges": report.edges,
        "components": report.components,
        "euler_characteristic": report.euler_characteristic,
        "genus": genus,
        "boundary_loops": report.boundary_loops,
        "closed_manifold": report.closed_manifold,
        "area": report.area,
        "bbox_min": lo,
        "bbox_max": hi,
        "smallest_angle_degrees": report.smallest_angle_degrees,
        "problems": problems,
        "component_list": report.component_details,
    })
}

fn mesh_reply(e: &MeshEntry) -> serde_json::Value {
    json!({
        "mesh_id": e.id,
        "n": e.mesh.n_vertices(),
        "m": e.mesh.n_triangles(),
        "source": e.source,
        "info": e.info,
    })
}

/// Largest built-in shape the web app builds (a resolution typo must not exhaust memory).
pub const MAX_SHAPE_VERTICES: usize = 2_000_000;

fn insert_mesh(
    s: &AppState,
    mesh: Mesh,
    source: String,
    notes: Vec<String>,
) -> ApiResult<serde_json::Value> {
    let hash = mesh.content_hash();
    let id = hash[..16].to_string();
    if let Some(item) = s.mesh(&id)
        && let Item::Mesh(e) = &*item
    {
        return Ok(mesh_reply(e));
    }
    let topo = Topology::new(&mesh);
    let mut info = info_json(&mesh, &topo);
    info["reader_notes"] = json!(notes);
    let bytes = mesh_bytes(&mesh);
    let entry = MeshEntry {
        id: id.clone(),
        hash,
        source,
        mesh: Arc::new(mesh),
        info,
    };
    let reply = mesh_reply(&entry);
    if !s
        .cache
        .insert(Key::Mesh(id), Arc::new(Item::Mesh(Box::new(entry))), bytes)
    {
        return Err(ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("the mesh needs about {bytes} bytes, more than the cache holds"),
        ));
    }
    Ok(reply)
}

async fn load_mesh(
    State(s): St,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<serde_json::Value>> {
    let body = body.map_err(|r| {
        let status = r.status();
        let msg = if status == StatusCode::PAYLOAD_TOO_LARGE {
            format!(
                "the upload is larger than the limit of {} bytes",
                s.config.max_upload_bytes
            )
        } else {
            r.body_text()
        };
        ApiError(status, msg)
    })?;
    let is_json = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    let s2 = s.clone();
    let reply = if is_json {
        let req: ShapeBody =
            serde_json::from_slice(&body).map_err(|e| ApiError::bad(format!("bad JSON: {e}")))?;
        if req.shape.len() > 200 {
            return Err(ApiError::bad("the shape spec is too long"));
        }
        tokio::task::spawn_blocking(move || {
            let mesh = spectral_mesh::shapes::build_str(&req.shape)
                .map_err(|e| ApiError::bad(format!("shape '{}': {e}", req.shape)))?;
            if mesh.n_vertices() > MAX_SHAPE_VERTICES {
                return Err(ApiError::unprocessable(format!(
                    "shape '{}' has {} vertices, more than the web app's limit of {MAX_SHAPE_VERTICES}",
                    req.shape,
                    mesh.n_vertices()
                )));
            }
            insert_mesh(&s2, mesh, req.shape.clone(), Vec::new())
        })
        .await
        .map_err(internal)??
    } else {
        let name = headers
            .get("x-filename")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("upload.off")
            .chars()
            .filter(|c| !c.is_control())
            .take(200)
            .collect::<String>();
        if body.is_empty() {
            return Err(ApiError::bad("the upload is empty"));
        }
        tokio::task::spawn_blocking(move || {
            let loaded = spectral_mesh::io::read_mesh_from_bytes(&body, &name)
                .map_err(|e| ApiError::unprocessable(e.to_string()))?;
            let mut notes = loaded.warnings;
            if loaded.polygons_triangulated > 0 {
                notes.push(format!(
                    "{} polygons were split into triangles",
                    loaded.polygons_triangulated
                ));
            }
            insert_mesh(&s2, loaded.mesh, name, notes)
        })
        .await
        .map_err(internal)??
    };
    Ok(Json(reply))
}

fn get_mesh(s: &AppState, id: &str) -> ApiResult<Arc<Item>> {
    check_id(id)?;
    s.mesh(id).ok_or_else(|| {
        ApiError::not_found(format!(
            "mesh {id} is not loaded (it may have been evicted from the cache): load it again"
        ))
    })
}

fn entry(item: &Item) -> ApiResult<&MeshEntry> {
    match item {
        Item::Mesh(e) => Ok(e),
        _ => Err(internal("cache mix-up")),
    }
}

async fn mesh_info(State(s): St, Path(id): Path<String>) -> ApiResult<Json<serde_json::Value>> {
    let item = get_mesh(&s, &id)?;
    Ok(Json(mesh_reply(entry(&item)?)))
}

fn octet(body: Vec<u8>) -> Response {
    (
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/octet-stream"),
        )],
        body,
    )
        .into_response()
}

async fn geometry(State(s): St, Path(id): Path<String>) -> ApiResult<Response> {
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let (n, m) = (e.mesh.n_vertices(), e.mesh.n_triangles());
    let mut out = Vec::with_capacity(8 + 12 * n + 12 * m);
    out.extend((n as u32).to_le_bytes());
    out.extend((m as u32).to_le_bytes());
    for p in e.mesh.positions() {
        for c in p {
            out.extend((*c as f32).to_le_bytes());
        }
    }
    for t in e.mesh.triangles() {
        for c in t {
            out.extend((*c as u32).to_le_bytes());
        }
    }
    Ok(octet(out))
}

// ---------- eigenbasis ----------

/// Body of `POST /api/mesh/{id}/basis`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BasisBody {
    laplacian: Option<String>,
    normalize: Option<bool>,
    k: Option<usize>,
}

fn parse_laplacian(s: Option<&str>) -> ApiResult<Laplacian> {
    match s {
        None => Ok(Laplacian::Fem),
        Some(s) => s
            .parse::<Laplacian>()
            .map_err(|e| ApiError::bad(format!("laplacian: {e}"))),
    }
}

/// The progress of an eigenbasis computation as (fraction done, message).
fn progress_of(p: &EigenProgress) -> (f64, String) {
    match p {
        EigenProgress::Dense { n } => (0.1, format!("dense solver, n = {n}")),
        EigenProgress::Factorization { n, .. } => (0.02, format!("factoring, n = {n}")),
        EigenProgress::Iteration {
            iteration,
            converged,
            wanted,
            ..
        } => (
            0.05 + 0.9 * *converged as f64 / (*wanted).max(1) as f64,
            format!("iteration {iteration}: {converged} of {wanted} pairs converged"),
        ),
        EigenProgress::Finished { .. } => (0.99, "finishing".into()),
    }
}

fn job_of(key: &AnalysisKey, k: usize, held_k: usize, state: &str, message: String) -> Job {
    Job {
        state: state.into(),
        laplacian: key.laplacian.name().into(),
        normalize: key.normalize,
        k,
        held_k,
        progress: if state == "done" { 1.0 } else { 0.0 },
        message,
        seconds: 0.0,
    }
}

/// Starts `analysis.basis(k)` off the request thread. One computation per mesh: a request
/// for other parameters cancels the running one (its status becomes "cancelled").
async fn start_basis(
    State(s): St,
    Path(id): Path<String>,
    body: Result<Json<BasisBody>, JsonRejection>,
) -> ApiResult<(StatusCode, Json<Job>)> {
    let Json(body) = body.map_err(|r| ApiError::bad(r.body_text()))?;
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let n = e.mesh.n_vertices();
    let key = AnalysisKey {
        id: id.clone(),
        laplacian: parse_laplacian(body.laplacian.as_deref())?,
        normalize: body.normalize.unwrap_or(true),
    };
    let k = body.k.unwrap_or(DEFAULT_K);
    if k == 0 || k > n {
        return Err(ApiError::unprocessable(format!(
            "k must be in 1..={n} (the number of vertices); got {k}"
        )));
    }
    let need = basis_bytes(n, k);
    if need > s.cache.capacity() / 2 {
        return Err(ApiError::unprocessable(format!(
            "an eigenbasis of k = {k} on {n} vertices needs {need} bytes, more than half the cache ({} bytes)",
            s.cache.capacity()
        )));
    }
    // Assembling the operators is O(n): off the async threads.
    let (s2, key2, item2) = (s.clone(), key.clone(), item.clone());
    let analysis = tokio::task::spawn_blocking(move || -> ApiResult<Arc<Analysis>> {
        Ok(s2.analysis(entry(&item2)?, &key2))
    })
    .await
    .map_err(internal)??;
    let held = analysis.held_k();
    let mut jobs = s.jobs();
    if held >= k {
        let job = job_of(&key, k, held, "done", format!("held ({held} pairs)"));
        // A finished status is replaced; a running job for other parameters goes on.
        if jobs.get(&id).is_none_or(|j| j.job.state != "running") {
            jobs.insert(
                id.clone(),
                JobSlot {
                    job: job.clone(),
                    serial: s.serial(),
                    cancel: Default::default(),
                    analysis: None,
                    key,
                },
            );
        }
        return Ok((StatusCode::OK, Json(job)));
    }
    if let Some(slot) = jobs.get(&id)
        && slot.job.state == "running"
    {
        if slot.key == key && slot.job.k >= k {
            return Ok((StatusCode::ACCEPTED, Json(slot.job.clone())));
        }
        slot.cancel.cancel();
    }
    let serial = s.serial();
    let cancel = spectral_mesh::cancel::CancelToken::new();
    let mut job = job_of(&key, k, held, "running", "starting".into());
    job.progress = 0.0;
    jobs.insert(
        id.clone(),
        JobSlot {
            job: job.clone(),
            serial,
            cancel: cancel.clone(),
            analysis: Some(analysis.clone()),
            key: key.clone(),
        },
    );
    drop(jobs);
    let s2 = s.clone();
    tokio::task::spawn_blocking(move || run_basis(&s2, &key, &analysis, k, serial, &cancel));
    Ok((StatusCode::ACCEPTED, Json(job)))
}

/// The body of a basis job: computes, reports progress into the job (if it is still the
/// current one), and re-enters the analysis into the cache with its new size.
fn run_basis(
    s: &AppState,
    key: &AnalysisKey,
    analysis: &Arc<Analysis>,
    k: usize,
    serial: u64,
    cancel: &spectral_mesh::cancel::CancelToken,
) {
    let start = Instant::now();
    let update = |f: &mut dyn FnMut(&mut Job)| {
        if let Some(slot) = s.jobs().get_mut(&key.id)
            && slot.serial == serial
        {
            f(&mut slot.job);
            slot.job.seconds = start.elapsed().as_secs_f64();
        }
    };
    let mut progress = |p: EigenProgress| {
        let (frac, msg) = progress_of(&p);
        update(&mut |j| {
            j.progress = frac;
            j.message = msg.clone();
        });
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        analysis.basis(k, &mut progress, cancel)
    }));
    let held = analysis.held_k();
    let (state, message) = match result {
        Ok(Ok(b)) => (
            "done",
            format!("{} pairs in {:.2} s", b.k(), start.elapsed().as_secs_f64()),
        ),
        Ok(Err(AnalysisError::Eigen(EigenError::Cancelled))) => {
            ("cancelled", "cancelled by another request".to_string())
        }
        Ok(Err(e)) => ("error", e.to_string()),
        Err(_) => ("error", "the eigensolver failed unexpectedly".to_string()),
    };
    if let Some(slot) = s.jobs().get_mut(&key.id)
        && slot.serial == serial
    {
        slot.job.state = state.into();
        slot.job.message = message;
        slot.job.held_k = held;
        slot.job.seconds = start.elapsed().as_secs_f64();
        if state == "done" {
            slot.job.progress = 1.0;
        }
        slot.analysis = None;
    }
    s.remember(key, analysis);
}

/// Cancels the running eigenbasis computation of a mesh, if any.
async fn cancel_basis(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    let jobs = s.jobs();
    let slot = jobs
        .get(&id)
        .ok_or_else(|| ApiError::not_found("no eigenbasis computation for this mesh"))?;
    if slot.job.state == "running" {
        slot.cancel.cancel();
    }
    Ok(Json(slot.job.clone()))
}

async fn basis_status(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    let job = s.jobs().get(&id).map(|slot| slot.job.clone());
    Ok(Json(job.unwrap_or(Job {
        state: "idle".into(),
        laplacian: String::new(),
        normalize: true,
        k: 0,
        held_k: 0,
        progress: 0.0,
        message: "no eigenbasis requested yet".into(),
        seconds: 0.0,
    })))
}

// ---------- fields ----------

/// Parses a body (400 on bad JSON or keys).
fn parse_body(bytes: &[u8]) -> ApiResult<FieldBody> {
    let v: serde_json::Value =
        serde_json::from_slice(bytes).map_err(|e| ApiError::bad(format!("bad JSON: {e}")))?;
    Ok(FieldBody::from_value(v)?)
}

/// The reply to `body` on mesh `id` (off the request thread); 409 when the basis is not
/// there yet.
/// With `encode`, the binary reply too (on the field threads as well).
async fn compute(
    s: &Arc<AppState>,
    id: &str,
    body: FieldBody,
    encode: bool,
) -> ApiResult<(FieldReply, Option<Vec<u8>>, Arc<Item>)> {
    let item = get_mesh(s, id)?;
    let s2 = s.clone();
    let item2 = item.clone();
    let id = id.to_string();
    let (reply, bytes) = tokio::task::spawn_blocking(move || -> ApiResult<_> {
        let e = entry(&item2)?;
        let key = AnalysisKey {
            id: id.clone(),
            laplacian: body.laplacian,
            normalize: body.normalize,
        };
        let analysis = s2.analysis(e, &key);
        let before = analysis.held_k();
        let reply = s2.on_field_threads(|| -> ApiResult<_> {
            let Some(r) = field_reply(&analysis, &body.request, body.levels)? else {
                return Ok(None);
            };
            let bytes = if encode {
                Some(r.to_bytes().map_err(internal)?)
            } else {
                None
            };
            Ok(Some((r, bytes)))
        })?;
        match reply {
            Some((r, bytes)) => {
                if r.field.request.eigenpairs().is_none() && before == analysis.held_k() {
                    // Harmonic maps factor a solver: account for it.
                    s2.remember(&key, &analysis);
                }
                Ok((r, bytes))
            }
            None => Err(missing_basis(&s2, &key, &body, analysis.held_k())),
        }
    })
    .await
    .map_err(internal)??;
    Ok((reply, bytes, item))
}

/// The 409 of a field whose eigenbasis is not there yet.
fn missing_basis(s: &AppState, key: &AnalysisKey, body: &FieldBody, held: usize) -> ApiError {
    let k = body.request.eigenpairs().unwrap_or(0);
    let running = s
        .jobs()
        .get(&key.id)
        .filter(|slot| slot.job.state == "running" && slot.key == *key)
        .map(|slot| {
            format!(
                " (a basis of k = {} is being computed: {:.0}%)",
                slot.job.k,
                100.0 * slot.job.progress
            )
        })
        .unwrap_or_default();
    ApiError(
        StatusCode::CONFLICT,
        format!(
            "no eigenbasis of {k} pairs for this mesh yet ({}, normalize = {}; {held} pairs held){running}: POST /api/mesh/{}/basis with {{\"k\": {k}}} first",
            key.laplacian.name(),
            key.normalize,
            key.id
        ),
    )
}

async fn field(State(s): St, Path(id): Path<String>, body: Bytes) -> ApiResult<Response> {
    let body = parse_body(&body)?;
    let (_, bytes, _) = compute(&s, &id, body, true).await?;
    Ok(octet(bytes.unwrap_or_default()))
}

// ---------- downloads ----------

/// Query of `GET /api/mesh/{id}/download`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DownloadQuery {
    format: Option<String>,
    /// The same JSON object as the body of a field request.
    body: String,
}

async fn download_get(
    State(s): St,
    Path(id): Path<String>,
    query: Result<Query<DownloadQuery>, QueryRejection>,
) -> ApiResult<Response> {
    let Query(q) = query.map_err(|r| {
        ApiError::bad(format!(
            "{}: expected ?format=png|wrl|ply|txt|toml&body=<the field request as JSON>",
            r.body_text()
        ))
    })?;
    let mut body = parse_body(q.body.as_bytes())?;
    if q.format.is_some() {
        body.format = q.format;
    }
    download(&s, &id, body).await
}

async fn download_post(State(s): St, Path(id): Path<String>, body: Bytes) -> ApiResult<Response> {
    let body = parse_body(&body)?;
    download(&s, &id, body).await
}

/// Formats a download can have.
pub const DOWNLOAD_FORMATS: [&str; 5] = ["png", "wrl", "ply", "txt", "toml"];

async fn download(s: &Arc<AppState>, id: &str, body: FieldBody) -> ApiResult<Response> {
    let format = body
        .format
        .clone()
        .unwrap_or_else(|| "txt".into())
        .to_ascii_lowercase();
    if !DOWNLOAD_FORMATS.contains(&format.as_str()) {
        return Err(ApiError::bad(format!(
            "unknown format '{format}': expected {}",
            DOWNLOAD_FORMATS.join(", ")
        )));
    }
    let options = body.figure_options()?;
    let (laplacian, normalize) = (body.laplacian, body.normalize);
    let (reply, _, item) = compute(s, id, FieldBody { levels: 0, ..body }, false).await?;
    let name = format!("{}-{}.{format}", reply.field.request.kind(), &id[..8]);
    let mime = match format.as_str() {
        "png" => "image/png",
        "wrl" => "model/vrml",
        "ply" => "application/octet-stream",
        "toml" => "application/toml",
        _ => "text/plain; charset=utf-8",
    };
    let bytes = tokio::task::spawn_blocking(move || -> ApiResult<Vec<u8>> {
        let e = entry(&item)?;
        let field = &reply.field;
        if format == "toml" {
            let mut f = ExperimentFile::for_field(&e.source, field.request.clone());
            f.mesh_hash = Some(e.hash.clone());
            f.laplacian = Some(laplacian.name().into());
            f.normalize = Some(normalize);
            f.basis_k = match (field.k, field.basis_k) {
                (Some(k), Some(bk)) if bk > k => Some(bk),
                _ => None,
            };
            f.figure = Some(options.to_file());
            f.validate().map_err(internal)?;
            return Ok(f.to_toml().map_err(internal)?.into_bytes());
        }
        let fig = Figure::of_field(&e.mesh, field, options).map_err(internal)?;
        fig.bytes(&format).map_err(internal)
    })
    .await
    .map_err(internal)??;
    Ok((
        [
            (header::CONTENT_TYPE, mime.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{name}\""),
            ),
        ],
        bytes,
    )
        .into_response())
}

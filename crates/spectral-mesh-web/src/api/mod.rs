//! The router and its handlers. Every field is computed by the library's
//! [`spectral_mesh::analysis::Analysis`]; this module only parses, caches and encodes.

use std::sync::Arc;

use axum::body::{Body, Bytes};
use axum::extract::rejection::QueryRejection;
use axum::extract::{DefaultBodyLimit, Extension, Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use http_body_util::BodyExt;
use serde::Deserialize;
use serde_json::json;
use spectral_mesh::analysis::{Analysis, AnalysisError, AnalysisInput};
use spectral_mesh::experiments::file::{ExperimentFile, PointCloudFile};
use spectral_mesh::io::{Input, LoadedPoints};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::operators::PointCloudParams;
use spectral_mesh::shapes::ShapeError;
use spectral_mesh::spectral::eigenbasis::EigenError;
use spectral_mesh::{Laplacian, Mesh};
use spectral_mesh_render::figure::Figure;

use crate::body::{self, BodyError, FieldBody};
use crate::cache::Shortfall;
use crate::field::{FieldReply, field_reply};
use crate::jobs::{self, Job, Submit, Submitted};
use crate::limits::{Deadline, busy, guard, mib, read_inside};
use crate::state::{
    AnalysisKey, AppState, Item, Key, Loaded, MeshEntry, Reservation, analysis_creation_bytes,
    field_bytes,
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
        let mut r = (self.0, Json(json!({ "error": self.1 }))).into_response();
        if self.0 == StatusCode::SERVICE_UNAVAILABLE {
            r.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from_static("2"));
        }
        r
    }
}

type ApiResult<T> = Result<T, ApiError>;

/// Builds the router over `state`.
pub fn router(state: Arc<AppState>) -> Router {
    let limit = state.config.limits.max_json_bytes;
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
        // Bodies are read by the handlers themselves (limits, memory, deadline); this
        // only bounds extractors that might be added later.
        .layer(DefaultBodyLimit::max(limit))
        .layer(axum::middleware::from_fn_with_state(state.clone(), guard))
        .with_state(state)
}

// ---------- limits ----------

/// The answer to a reservation that failed: 503 when other work holds the memory (try
/// again), `never` (413 or 422) when it could never fit.
fn no_room(what: &str, short: &Shortfall, never: StatusCode) -> ApiError {
    if short.never_fits() {
        ApiError(
            never,
            format!(
                "{what} needs about {}, more than this server's memory budget of {} (--memory-mib)",
                mib(short.wanted),
                mib(short.limit)
            ),
        )
    } else {
        ApiError(
            StatusCode::SERVICE_UNAVAILABLE,
            format!(
                "the server's memory is busy: {what} needs about {}, and of the budget of {} the cache holds {} ({} in use) and work in progress {}; try again later",
                mib(short.wanted),
                mib(short.limit),
                mib(short.cached),
                mib(short.pinned),
                mib(short.reserved)
            ),
        )
    }
}

/// Reserves `bytes` of the memory budget, waiting until the request's deadline.
async fn reserve(
    s: &AppState,
    what: &str,
    bytes: usize,
    deadline: Deadline,
    never: StatusCode,
) -> ApiResult<Reservation> {
    s.cache
        .reserve(bytes, deadline.0)
        .await
        .map_err(|short| no_room(what, &short, never))
}

/// Reads a request body of at most `limit` bytes (413 beyond, at once when the
/// `Content-Length` says so), with `factor` times its length reserved from the memory
/// budget first (the body and what parsing it takes), before the request's deadline
/// (408 when the body has not arrived by then; 400 when the client stopped sending).
async fn read_body(
    s: &AppState,
    headers: &HeaderMap,
    body: Body,
    (limit, what, factor): (usize, &str, usize),
    deadline: Deadline,
) -> ApiResult<(Bytes, Reservation)> {
    let declared = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<usize>().ok());
    let too_large = || {
        ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!(
                "the {what} is larger than the limit of {limit} bytes ({})",
                if what == "upload" {
                    "--max-upload-mib"
                } else {
                    "JSON bodies"
                }
            ),
        )
    };
    let mut body = body;
    if declared.is_some_and(|n| n > limit) {
        drain(&mut body, deadline).await;
        return Err(too_large());
    }
    let expect = declared.unwrap_or(limit);
    let reservation = reserve(
        s,
        &format!("reading this {what}"),
        expect.saturating_mul(factor),
        deadline,
        StatusCode::PAYLOAD_TOO_LARGE,
    )
    .await?;
    let mut buf: Vec<u8> = Vec::with_capacity(expect.min(limit).min(1 << 20));
    let read = async {
        while let Some(frame) = body.frame().await {
            let frame = frame.map_err(|e| {
                ApiError::bad(format!(
                    "the {what} ended early after {} bytes: {e}",
                    buf.len()
                ))
            })?;
            if let Ok(data) = frame.into_data() {
                if buf.len() + data.len() > limit {
                    return Err(too_large());
                }
                buf.extend_from_slice(&data);
            }
        }
        Ok(())
    };
    match tokio::time::timeout_at(deadline.0, read).await {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            if e.0 == StatusCode::PAYLOAD_TOO_LARGE {
                drop(buf);
                drain(&mut body, deadline).await;
            }
            return Err(e);
        }
        Err(_) => {
            return Err(ApiError(
                StatusCode::REQUEST_TIMEOUT,
                format!(
                    "the {what} did not arrive within {} s (--request-seconds): {} bytes received",
                    s.config.limits.request_seconds,
                    buf.len()
                ),
            ));
        }
    }
    if declared.is_some_and(|n| n != buf.len()) {
        return Err(ApiError::bad(format!(
            "the {what} ended early: {} of {} bytes",
            buf.len(),
            declared.unwrap_or(0)
        )));
    }
    Ok((Bytes::from(buf), reservation))
}

/// Most bytes of a refused body read and dropped before the refusal is sent.
const DRAIN_BYTES: usize = 16 << 20;

/// Reads and drops up to [`DRAIN_BYTES`] more of a body refused as too large (for at most
/// 5 s, never past the deadline): a client still sending then reads the 413 instead of a
/// connection reset by the server's closing on unread data.
async fn drain(body: &mut Body, deadline: Deadline) {
    let until = deadline
        .0
        .min(tokio::time::Instant::now() + std::time::Duration::from_secs(5));
    let read = async {
        let mut seen = 0usize;
        while seen < DRAIN_BYTES {
            match body.frame().await {
                Some(Ok(frame)) => {
                    if let Ok(data) = frame.into_data() {
                        seen += data.len();
                    }
                }
                _ => break,
            }
        }
    };
    let _ = tokio::time::timeout_at(until, read).await;
}

/// Memory reserved per byte of a JSON body (the text, `serde_json::Value`, the request).
const JSON_FACTOR: usize = 8;

/// Memory reserved per byte of an uploaded mesh: the bytes, the parsed mesh, its
/// connectivity and validation report (see RELIABILITY.md for the measurement).
pub const UPLOAD_FACTOR: usize = 12;

/// Memory reserved per vertex while a shape is built and checked.
pub const SHAPE_BYTES_PER_VERTEX: usize = 1200;

async fn json_body(
    s: &AppState,
    headers: &HeaderMap,
    body: Body,
    deadline: Deadline,
) -> ApiResult<(Bytes, Reservation)> {
    read_body(
        s,
        headers,
        body,
        (s.config.limits.max_json_bytes, "JSON body", JSON_FACTOR),
        deadline,
    )
    .await
}

// ---------- static files (a fixed list: no path parameters) ----------

const INDEX_HTML: &str = include_str!("../static/index.html");
const APP_JS: &str = include_str!("../static/app.js");
const STYLE_CSS: &str = include_str!("../static/style.css");

async fn static_file(state: &AppState, name: &str, builtin: &'static str, mime: &str) -> Response {
    let body = match &state.config.static_dir {
        Some(dir) => match read_inside(dir, name).await {
            Ok(b) => b,
            Err(e) => {
                return ApiError::not_found(format!("static file {e}")).into_response();
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
    match read_inside(&s.node_modules, rel).await {
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
    let (running, queued) = s.jobs.counts();
    let (superseded, cancelled) = s.jobs.totals();
    Json(json!({
        "ok": true,
        "cache_used": s.cache.used(),
        "cache_capacity": s.cache.capacity(),
        "cache_entries": s.cache.len(),
        "memory_reserved": s.cache.reserved(),
        "memory_budget": s.cache.budget(),
        "jobs_running": running,
        "jobs_queued": queued,
        "jobs_superseded": superseded,
        "jobs_cancelled": cancelled,
        "requests_in_progress": s.in_flight.get(),
        "limits": s.config.limits,
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

fn check_id(id: &str) -> ApiResult<()> {
    if id.len() == 16 && id.bytes().all(|b| b.is_ascii_hexdigit()) {
        Ok(())
    } else {
        Err(ApiError::bad("a mesh id is 16 hexadecimal digits"))
    }
}

/// `k` against an input of `n` vertices or points (`noun`) and `--max-k` (422), in the
/// input's words.
fn check_k(k: usize, n: usize, noun: &str, max_k: usize) -> ApiResult<()> {
    body::check_k(k, n, max_k).map_err(|m| {
        ApiError::unprocessable(if noun == "points" {
            m.replace(
                "(the number of vertices)",
                "(the number of points of this point cloud)",
            )
        } else {
            m
        })
    })
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

/// The info panel of a point cloud: the points as read, and what its point-cloud
/// Laplacian (the analysis `an`, built at upload) found: the triangle union it uses for
/// connectivity, its pieces (as many zero eigenvalues), the mean point spacing.
fn cloud_info(
    cloud: &spectral_mesh::PointCloud,
    params: &PointCloudParams,
    an: &Analysis,
) -> serde_json::Value {
    let (lo, hi) = cloud.bounding_box();
    let topo = an.topology();
    let union = an.mesh();
    json!({
        "kind": "point cloud",
        "points": cloud.n_points(),
        "vertices": cloud.n_points(),
        "triangles": 0,
        "normals": cloud.n_normals(),
        "bbox_min": lo,
        "bbox_max": hi,
        "laplacian": Laplacian::Robust.name(),
        "neighbors": params.neighbors,
        "union_triangles": union.n_triangles(),
        "components": topo.n_components(),
        "point_spacing": an.point_spacing(),
        "problems": [],
    })
}

fn mesh_reply(e: &MeshEntry) -> serde_json::Value {
    json!({
        "mesh_id": e.id,
        "kind": e.kind(),
        "n": e.n(),
        "m": e.n_triangles(),
        "source": e.source,
        "laplacians": e.laplacians(),
        "point_spacing": e.info.get("point_spacing").cloned().unwrap_or(serde_json::Value::Null),
        // Splat radius over point spacing in the pictures (spectral-mesh-render's), so the
        // page draws clouds as the PNGs do without a constant of its own.
        "point_radius_factor": spectral_mesh_render::figure::POINT_RADIUS_FACTOR,
        "info": e.info,
    })
}

/// Largest built-in shape the web app builds whatever `--max-vertices` says (a
/// resolution typo must not exhaust memory).
pub const MAX_SHAPE_VERTICES: usize = 2_000_000;

/// Checks a mesh or a point cloud against the vertex and triangle limits (413); `noun`
/// is `vertices` or `points`.
fn check_size(s: &AppState, what: &str, noun: &str, n: usize, m: usize) -> ApiResult<()> {
    let l = &s.config.limits;
    if n > l.max_vertices {
        return Err(ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!(
                "{what} has {n} {noun}, more than this server's limit of {} (--max-vertices)",
                l.max_vertices
            ),
        ));
    }
    if m > l.max_faces {
        return Err(ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!(
                "{what} has {m} triangles, more than this server's limit of {} (--max-faces)",
                l.max_faces
            ),
        ));
    }
    Ok(())
}

/// The loaded entry of `id`, if any.
fn loaded(s: &AppState, id: &str) -> Option<serde_json::Value> {
    let item = s.mesh(id)?;
    match &*item {
        Item::Mesh(e) => Some(mesh_reply(e)),
        Item::Analysis(_) => None,
    }
}

/// Enters a checked mesh or cloud into the cache, with the reservation that covered its
/// reading and building released first (what stays is the entry itself).
fn enter(s: &AppState, entry: MeshEntry, reservation: Reservation) -> ApiResult<serde_json::Value> {
    let bytes = entry.bytes();
    let reply = mesh_reply(&entry);
    let id = entry.id.clone();
    drop(reservation);
    s.cache
        .insert(Key::Mesh(id), Arc::new(Item::Mesh(Box::new(entry))), bytes)
        .map_err(|short| {
            if short.never_fits() {
                ApiError(
                    StatusCode::PAYLOAD_TOO_LARGE,
                    format!(
                        "the input needs about {}, more than the cache holds ({}, --cache-mib)",
                        mib(bytes),
                        mib(short.limit)
                    ),
                )
            } else {
                no_room("this input", &short, StatusCode::PAYLOAD_TOO_LARGE)
            }
        })?;
    Ok(reply)
}

/// Enters a mesh into the cache (after its check and its info), with the reservation
/// that covered its reading released first (the parsed mesh is what stays).
fn insert_mesh(
    s: &AppState,
    mesh: Mesh,
    source: String,
    notes: Vec<String>,
    reservation: Reservation,
) -> ApiResult<serde_json::Value> {
    check_size(
        s,
        &format!("'{source}'"),
        "vertices",
        mesh.n_vertices(),
        mesh.n_triangles(),
    )?;
    let hash = mesh.content_hash();
    let id = hash[..16].to_string();
    if let Some(reply) = loaded(s, &id) {
        return Ok(reply);
    }
    let topo = Topology::new(&mesh);
    let mut info = info_json(&mesh, &topo);
    drop(topo);
    info["kind"] = json!("mesh");
    info["reader_notes"] = json!(notes);
    let entry = MeshEntry {
        id,
        hash,
        source,
        input: Loaded::Mesh(Arc::new(mesh)),
        info,
    };
    enter(s, entry, reservation)
}

/// Enters an uploaded point cloud: checked against the limits (its points count as
/// vertices), then its analysis for the page's defaults (robust, unit area) made at
/// once with [`Analysis::from_input`], so that a cloud whose Laplacian cannot be built
/// (collinear or coincident points) is refused at the upload (422) and the reply tells
/// the triangle union and the point spacing the page draws with.
async fn insert_cloud(
    s: &Arc<AppState>,
    points: LoadedPoints,
    source: String,
    reservation: Reservation,
    deadline: Deadline,
) -> ApiResult<serde_json::Value> {
    let n = points.cloud.n_points();
    check_size(s, &format!("'{source}'"), "points", n, 0)?;
    let hash = points.cloud.content_hash();
    let id = hash[..16].to_string();
    if let Some(reply) = loaded(s, &id) {
        return Ok(reply);
    }
    // The parsed cloud is small beside what the upload's reading reserved: let that go
    // and reserve the Laplacian's assembly instead.
    drop(reservation);
    let r = reserve(
        s,
        "building the point-cloud Laplacian",
        analysis_creation_bytes(n, Laplacian::Robust, true),
        deadline,
        StatusCode::PAYLOAD_TOO_LARGE,
    )
    .await?;
    let s2 = s.clone();
    tokio::task::spawn_blocking(move || -> ApiResult<serde_json::Value> {
        let params = PointCloudParams::default();
        let mut entry = MeshEntry {
            id: id.clone(),
            hash,
            source,
            input: Loaded::Points(AnalysisInput::Points {
                cloud: points.cloud,
                params,
            }),
            info: serde_json::Value::Null,
        };
        let key = AnalysisKey {
            id,
            laplacian: Laplacian::Robust,
            normalize: true,
        };
        let an = s2
            .analysis(&entry, &key)
            .map_err(|e| ApiError::unprocessable(format!("'{}': {e}", entry.source)))?;
        let mut info = match &entry.input {
            Loaded::Points(AnalysisInput::Points { cloud, params }) => {
                cloud_info(cloud, params, &an)
            }
            _ => serde_json::Value::Null,
        };
        info["reader_notes"] = json!(points.warnings);
        entry.info = info;
        let reply = enter(&s2, entry, r)?;
        // Now that the cloud is loaded, its analysis can stay in the cache.
        s2.remember(&key, &an);
        Ok(reply)
    })
    .await
    .map_err(internal)?
}

/// Refuses a shape spec whose mesh would exceed the vertex limit, before it is built.
fn shape_error(text: &str, cap: usize, e: ShapeError) -> ApiError {
    match e {
        ShapeError::TooLarge { vertices, .. } => ApiError(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!(
                "shape '{text}' would have {vertices} vertices{}, more than this server's limit of {cap} (--max-vertices): lower res",
                if text.contains("irregular") {
                    " (at most)"
                } else {
                    ""
                }
            ),
        ),
        e => ApiError::bad(format!("shape '{text}': {e}")),
    }
}

/// What an upload turned out to be once read.
enum Read {
    /// A mesh, entered: the reply.
    Entered(serde_json::Value),
    /// A point cloud, to be entered with its Laplacian.
    Points(LoadedPoints, String, Reservation),
}

async fn load_mesh(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    headers: HeaderMap,
    body: Body,
) -> ApiResult<Json<serde_json::Value>> {
    let is_json = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    let s2 = s.clone();
    let reply = if is_json {
        let (bytes, r) = json_body(&s, &headers, body, deadline).await?;
        let (text, spec, most) = body::parse_shape(&bytes)?;
        drop(r);
        let cap = s.config.limits.max_vertices.min(MAX_SHAPE_VERTICES);
        // `most` bounds the mesh from above (the irregular variants: the regular shape
        // one level finer); the library's `build_limited` refuses what exceeds the cap
        // before allocating it, so the reservation need not exceed the cap either.
        let r = reserve(
            &s,
            &format!("building shape '{text}'"),
            most.min(cap) * SHAPE_BYTES_PER_VERTEX,
            deadline,
            StatusCode::PAYLOAD_TOO_LARGE,
        )
        .await?;
        tokio::task::spawn_blocking(move || {
            let mesh = spectral_mesh::shapes::build_limited(&spec, cap)
                .map_err(|e| shape_error(&text, cap, e))?;
            insert_mesh(&s2, mesh, text, Vec::new(), r)
        })
        .await
        .map_err(internal)??
    } else {
        let name = body::upload_name(headers.get("x-filename").and_then(|v| v.to_str().ok()));
        let limit = s.config.limits.max_upload_bytes;
        let (bytes, r) = read_body(
            &s,
            &headers,
            body,
            (limit, "upload", UPLOAD_FACTOR),
            deadline,
        )
        .await?;
        if bytes.is_empty() {
            return Err(ApiError::bad("the upload is empty"));
        }
        let read = tokio::task::spawn_blocking(move || -> ApiResult<Read> {
            let input = spectral_mesh::io::read_input_from_bytes(&bytes, &name)
                .map_err(|e| ApiError::unprocessable(e.to_string()))?;
            drop(bytes);
            match input {
                Input::Mesh(loaded) => {
                    let mut notes = loaded.warnings;
                    if loaded.polygons_triangulated > 0 {
                        notes.push(format!(
                            "{} polygons were split into triangles",
                            loaded.polygons_triangulated
                        ));
                    }
                    insert_mesh(&s2, loaded.mesh, name, notes, r).map(Read::Entered)
                }
                Input::Points(points) => Ok(Read::Points(points, name, r)),
            }
        })
        .await
        .map_err(internal)??;
        match read {
            Read::Entered(reply) => reply,
            Read::Points(points, name, r) => insert_cloud(&s, points, name, r, deadline).await?,
        }
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

async fn geometry(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    Path(id): Path<String>,
) -> ApiResult<Response> {
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let (n, m) = (e.n(), e.n_triangles());
    let size = 8 + 12 * n + 12 * m;
    let _r = reserve(
        &s,
        "the geometry",
        size,
        deadline,
        StatusCode::UNPROCESSABLE_ENTITY,
    )
    .await?;
    let mut out = Vec::with_capacity(size);
    out.extend((n as u32).to_le_bytes());
    out.extend((m as u32).to_le_bytes());
    for p in e.positions() {
        for c in p {
            out.extend((*c as f32).to_le_bytes());
        }
    }
    for t in e.mesh().map_or(&[][..], |m| m.triangles()) {
        for c in t {
            out.extend((*c as u32).to_le_bytes());
        }
    }
    Ok(octet(out))
}

// ---------- eigenbasis ----------

/// The analysis of `key`: the existing one, or a new one made off the request thread
/// with the memory of its assembly reserved first.
async fn analysis_for(
    s: &Arc<AppState>,
    item: &Arc<Item>,
    key: &AnalysisKey,
    deadline: Deadline,
) -> ApiResult<Arc<Analysis>> {
    if let Some(a) = s.existing_analysis(key) {
        return Ok(a);
    }
    let e = entry(item)?;
    let (n, points) = (e.n(), e.is_points());
    let r = reserve(
        s,
        "assembling the operators",
        analysis_creation_bytes(n, key.laplacian, points),
        deadline,
        StatusCode::UNPROCESSABLE_ENTITY,
    )
    .await?;
    let (s2, key2, item2) = (s.clone(), key.clone(), item.clone());
    tokio::task::spawn_blocking(move || -> ApiResult<Arc<Analysis>> {
        let a = s2.analysis(entry(&item2)?, &key2)?;
        drop(r);
        Ok(a)
    })
    .await
    .map_err(internal)?
}

/// The `X-Client-Id` of a request, if it is a short visible ASCII string.
fn client_id(headers: &HeaderMap) -> Option<String> {
    let v = headers.get("x-client-id")?.to_str().ok()?.trim();
    (!v.is_empty() && v.len() <= 64 && v.bytes().all(|b| b.is_ascii_graphic()))
        .then(|| v.to_string())
}

/// Queues `analysis.basis(k)` (see [`crate::jobs`] for the queue, the admission and the
/// rules that stop a job).
async fn start_basis(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Body,
) -> ApiResult<Response> {
    check_id(&id)?;
    let (bytes, r) = json_body(&s, &headers, body, deadline).await?;
    let b = body::parse_basis(&bytes)?;
    drop(r);
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let (n, noun, mesh) = (e.n(), e.noun(), e.bytes());
    let laplacian = e.laplacian(b.laplacian).map_err(ApiError::unprocessable)?;
    let limits = &s.config.limits;
    check_k(b.k, n, noun, limits.max_k)?;
    let key = AnalysisKey {
        id: id.clone(),
        laplacian,
        normalize: b.normalize,
    };
    let analysis = analysis_for(&s, &item, &key, deadline).await?;
    let estimate = jobs::estimate(n, b.k, &analysis);
    let after = jobs::held_after(n, b.k, &analysis);
    if analysis.held_k() < b.k {
        if after + mesh > limits.cache_bytes {
            return Err(ApiError::unprocessable(format!(
                "an eigenbasis of k = {} on {n} {noun} would make this input and its analysis hold about {}, more than the cache's {} (--cache-mib): ask for fewer pairs",
                b.k,
                mib(after + mesh),
                mib(limits.cache_bytes)
            )));
        }
        let held = crate::state::analysis_bytes(&analysis) + mesh;
        if estimate + held > limits.memory_bytes {
            return Err(ApiError::unprocessable(format!(
                "an eigenbasis of k = {} on {n} {noun} needs about {} at its peak (estimate) besides the {} its input and analysis hold, more than this server's memory budget of {} (--memory-mib): ask for fewer pairs",
                b.k,
                mib(estimate),
                mib(held),
                mib(limits.memory_bytes)
            )));
        }
    }
    let submitted = s.jobs.submit(
        &s,
        Submit {
            id: id.clone(),
            key,
            k: b.k,
            analysis,
            estimate,
            client: client_id(&headers),
        },
    );
    match submitted {
        Submitted::Done(job) => Ok((StatusCode::OK, Json(job)).into_response()),
        Submitted::QueueFull(msg) => Ok(busy(msg, 5)),
        Submitted::Accepted(_) => {
            jobs::pump(&s);
            Ok((StatusCode::ACCEPTED, Json(s.jobs.status(&id))).into_response())
        }
    }
}

/// Cancels the eigenbasis job of a mesh (queued: removed; running: stopped).
async fn cancel_basis(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    let job = s
        .jobs
        .cancel(&id)
        .ok_or_else(|| ApiError::not_found("no eigenbasis computation for this mesh"))?;
    jobs::pump(&s);
    Ok(Json(job))
}

async fn basis_status(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    Ok(Json(s.jobs.status(&id)))
}

// ---------- fields ----------

/// A computed field with what it was computed on.
struct Computed {
    reply: FieldReply,
    /// The binary reply, when asked for.
    bytes: Option<Vec<u8>>,
    item: Arc<Item>,
    analysis: Arc<Analysis>,
}

/// The reply to `body` on mesh `id` (off the request thread, with its memory reserved
/// first); 409 when the basis is not there yet. With `encode`, the binary reply too (on
/// the field threads as well).
async fn compute(
    s: &Arc<AppState>,
    id: &str,
    body: FieldBody,
    encode: bool,
    deadline: Deadline,
) -> ApiResult<Computed> {
    let item = get_mesh(s, id)?;
    let e = entry(&item)?;
    let n = e.n();
    let laplacian = e
        .laplacian(body.laplacian)
        .map_err(ApiError::unprocessable)?;
    let key = AnalysisKey {
        id: id.to_string(),
        laplacian,
        normalize: body.normalize,
    };
    let needs_basis = body.request.eigenpairs().is_some();
    let analysis = match s.existing_analysis(&key) {
        Some(a) => a,
        None if needs_basis => {
            let k = body.request.eigenpairs().unwrap_or(0);
            if k > n {
                return Err(AnalysisError::TooManyPairs { k, n }.into());
            }
            body.request.validate().map_err(AnalysisError::from)?;
            return Err(missing_basis(s, &key, &body, 0));
        }
        None => analysis_for(s, &item, &key, deadline).await?,
    };
    let r = reserve(
        s,
        "this field",
        field_bytes(n, &body.request),
        deadline,
        StatusCode::UNPROCESSABLE_ENTITY,
    )
    .await?;
    let (s2, an) = (s.clone(), analysis.clone());
    let (reply, bytes) = tokio::task::spawn_blocking(move || -> ApiResult<_> {
        let before = an.memory_bytes();
        let reply = s2.on_field_threads(|| -> ApiResult<_> {
            let Some(r) = field_reply(&an, &body.request, body.levels)? else {
                return Ok(None);
            };
            let bytes = if encode {
                Some(r.to_bytes().map_err(internal)?)
            } else {
                None
            };
            Ok(Some((r, bytes)))
        });
        // A harmonic map factors a solver, the wFEM distance computes B X: account.
        if an.memory_bytes() != before {
            s2.remember(&key, &an);
        }
        drop(r);
        match reply? {
            Some((r, bytes)) => Ok((r, bytes)),
            None => Err(missing_basis(&s2, &key, &body, an.held_k())),
        }
    })
    .await
    .map_err(internal)??;
    Ok(Computed {
        reply,
        bytes,
        item,
        analysis,
    })
}

/// The 409 of a field whose eigenbasis is not there yet.
fn missing_basis(s: &AppState, key: &AnalysisKey, body: &FieldBody, held: usize) -> ApiError {
    let k = body.request.eigenpairs().unwrap_or(0);
    let running = s
        .jobs
        .peek(&key.id)
        .filter(|job| {
            job.active() && job.laplacian == key.laplacian.name() && job.normalize == key.normalize
        })
        .map(|job| {
            format!(
                " (a basis of k = {} is {}: {:.0}%)",
                job.k,
                if job.state == "queued" {
                    "queued"
                } else {
                    "being computed"
                },
                100.0 * job.progress
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

async fn field(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Body,
) -> ApiResult<Response> {
    check_id(&id)?;
    let (bytes, r) = json_body(&s, &headers, body, deadline).await?;
    let body = body::parse_field(&bytes)?;
    drop((bytes, r));
    let c = compute(&s, &id, body, true, deadline).await?;
    Ok(octet(c.bytes.unwrap_or_default()))
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
    Extension(deadline): Extension<Deadline>,
    Path(id): Path<String>,
    query: Result<Query<DownloadQuery>, QueryRejection>,
) -> ApiResult<Response> {
    let Query(q) = query.map_err(|r| {
        ApiError::bad(format!(
            "{}: expected ?format=png|wrl|ply|txt|toml&body=<the field request as JSON>",
            r.body_text()
        ))
    })?;
    let mut body = body::parse_field(q.body.as_bytes())?;
    if q.format.is_some() {
        body.format = q.format;
    }
    download(&s, &id, body, deadline).await
}

async fn download_post(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Body,
) -> ApiResult<Response> {
    check_id(&id)?;
    let (bytes, r) = json_body(&s, &headers, body, deadline).await?;
    let body = body::parse_field(&bytes)?;
    drop((bytes, r));
    download(&s, &id, body, deadline).await
}

/// Formats a download can have.
pub const DOWNLOAD_FORMATS: [&str; 5] = ["png", "wrl", "ply", "txt", "toml"];

async fn download(
    s: &Arc<AppState>,
    id: &str,
    body: FieldBody,
    deadline: Deadline,
) -> ApiResult<Response> {
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
    let normalize = body.normalize;
    let Computed {
        reply,
        item,
        analysis,
        ..
    } = compute(s, id, FieldBody { levels: 0, ..body }, false, deadline).await?;
    let laplacian = analysis.options().laplacian;
    let name = format!("{}-{}.{format}", reply.field.request.kind(), &id[..8]);
    let mime = match format.as_str() {
        "png" => "image/png",
        "wrl" => "model/vrml",
        "ply" => "application/octet-stream",
        "toml" => "application/toml",
        _ => "text/plain; charset=utf-8",
    };
    // A picture takes its pixels (size^2 x 4 bytes, several buffers); a text or mesh file
    // about 64 bytes per vertex and triangle.
    let n = reply.field.values.len();
    let size = options.size as usize;
    let need = match format.as_str() {
        "png" => 16 * size * size + 200 * n,
        _ => 200 * n,
    };
    let r = reserve(
        s,
        "this download",
        need,
        deadline,
        StatusCode::UNPROCESSABLE_ENTITY,
    )
    .await?;
    let bytes = tokio::task::spawn_blocking(move || -> ApiResult<Vec<u8>> {
        let e = entry(&item)?;
        let field = &reply.field;
        let out = if format == "toml" {
            let mut f = ExperimentFile::for_field(&e.source, field.request.clone());
            f.mesh_hash = Some(e.hash.clone());
            f.laplacian = Some(laplacian.name().into());
            f.normalize = Some(normalize);
            f.basis_k = match (field.k, field.basis_k) {
                (Some(k), Some(bk)) if bk > k => Some(bk),
                _ => None,
            };
            f.figure = Some(options.to_file());
            // A cloud's Laplacian parameters, so that `run` replays it with these even if
            // the defaults change.
            if let Loaded::Points(AnalysisInput::Points { params, .. }) = &e.input {
                f.point_cloud = Some(PointCloudFile::from_params(params));
            }
            f.validate().map_err(internal)?;
            f.to_toml().map_err(internal)?.into_bytes()
        } else {
            // A point cloud is drawn as discs sized from its point spacing, its files are
            // point sets; a mesh as before (its analysis holds the same mesh).
            let fig = Figure::of_analysis(&analysis, field, options).map_err(internal)?;
            fig.bytes(&format).map_err(internal)?
        };
        drop(r);
        Ok(out)
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

//! The router and its handlers.

use std::sync::Arc;
use std::time::Instant;

use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, JsonRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::json;
use spectral_mesh::mesh::topology::{Topology, VertexTriangles};
use spectral_mesh::{Eigenbasis, Laplacian, Mesh};
use spectral_mesh_render as render;

use crate::compute::{self, BadRequest, Experiment, FieldParams};
use crate::state::{AppState, Item, Job, Key, MeshEntry, basis_bytes, mesh_bytes};

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

impl From<BadRequest> for ApiError {
    fn from(b: BadRequest) -> Self {
        Self::unprocessable(b.0)
    }
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
        .route("/api/mesh/{id}/basis", post(start_basis))
        .route("/api/mesh/{id}/basis/status", get(basis_status))
        .route("/api/mesh/{id}/field", post(field))
        .route("/api/mesh/{id}/download", get(download))
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

async fn vendor(s: &AppState, rel: &str) -> Response {
    let path = s.node_modules.join(rel);
    match tokio::fs::read(&path).await {
        Ok(b) => (
            [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
            b,
        )
            .into_response(),
        Err(_) => ApiError(
            StatusCode::NOT_FOUND,
            format!("{rel} not found: run `npm ci` in the web/ folder of the source tree"),
        )
        .into_response(),
    }
}
async fn three_js(State(s): St) -> Response {
    vendor(&s, "three/build/three.module.js").await
}
async fn orbit_js(State(s): St) -> Response {
    vendor(&s, "three/examples/jsm/controls/OrbitControls.js").await
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

fn mesh_id(mesh: &Mesh) -> String {
    let mut h = blake3::Hasher::new();
    for p in mesh.positions() {
        for c in p {
            h.update(&c.to_le_bytes());
        }
    }
    for t in mesh.triangles() {
        for c in t {
            h.update(&(*c as u64).to_le_bytes());
        }
    }
    h.finalize().to_hex()[..16].to_string()
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
    let id = mesh_id(&mesh);
    if let Some(item) = s.mesh(&id)
        && let Item::Mesh(e) = &*item
    {
        return Ok(mesh_reply(e));
    }
    let topo = Topology::new(&mesh);
    let vt = VertexTriangles::new(&mesh);
    let mut info = info_json(&mesh, &topo);
    info["reader_notes"] = json!(notes);
    let bytes = mesh_bytes(&mesh);
    let entry = MeshEntry {
        id: id.clone(),
        source,
        mesh,
        topo,
        vt,
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
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))??
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
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))??
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
        _ => Err(ApiError(
            StatusCode::INTERNAL_SERVER_ERROR,
            "cache mix-up".into(),
        )),
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

#[derive(Deserialize)]
struct BasisBody {
    laplacian: Option<String>,
    k: Option<usize>,
}

fn parse_laplacian(s: Option<&str>) -> ApiResult<Laplacian> {
    match s {
        None => Ok(Laplacian::Fem),
        Some(s) => s.parse::<Laplacian>().map_err(ApiError::unprocessable),
    }
}

fn compute_basis(
    ops: &spectral_mesh::Operators,
    k: usize,
    progress: &mut dyn FnMut(f64, String),
) -> Result<Eigenbasis, String> {
    use spectral_mesh::spectral::eigenbasis::{EigenParams, EigenProgress, compute_eigenbasis};
    let params = EigenParams {
        k,
        ..Default::default()
    };
    let mut cb = |p: EigenProgress| match p {
        EigenProgress::Dense { n } => progress(0.1, format!("dense solver, n = {n}")),
        EigenProgress::Factorization { n, .. } => progress(0.02, format!("factoring, n = {n}")),
        EigenProgress::Iteration {
            iteration,
            converged,
            wanted,
            ..
        } => progress(
            0.05 + 0.9 * converged as f64 / wanted.max(1) as f64,
            format!("iteration {iteration}: {converged} of {wanted} pairs converged"),
        ),
        _ => progress(0.99, "finishing".into()),
    };
    compute_eigenbasis(ops, &params, &mut cb).map_err(|e| e.to_string())
}

async fn start_basis(
    State(s): St,
    Path(id): Path<String>,
    body: Result<Json<BasisBody>, JsonRejection>,
) -> ApiResult<(StatusCode, Json<Job>)> {
    let Json(body) = body.map_err(|r| ApiError::bad(r.body_text()))?;
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let n = e.mesh.n_vertices();
    let lap = parse_laplacian(body.laplacian.as_deref())?;
    let k = body.k.unwrap_or(100);
    if k == 0 || k > n {
        return Err(ApiError::unprocessable(format!(
            "k must be in 1..={n} (the number of vertices); got {k}"
        )));
    }
    let need = basis_bytes(n, k, 0);
    if need > s.cache.capacity() / 2 {
        return Err(ApiError::unprocessable(format!(
            "an eigenbasis of k = {k} on {n} vertices needs {need} bytes, more than half the cache"
        )));
    }
    if s.basis(&id, lap, k).is_some() {
        let job = Job {
            state: "done".into(),
            laplacian: lap.name().into(),
            k,
            progress: 1.0,
            message: "cached".into(),
            seconds: 0.0,
        };
        s.jobs().insert(id.clone(), job.clone());
        return Ok((StatusCode::OK, Json(job)));
    }
    {
        let mut jobs = s.jobs();
        if let Some(j) = jobs.get(&id)
            && j.state == "running"
        {
            if j.laplacian == lap.name() && j.k == k {
                return Ok((StatusCode::ACCEPTED, Json(j.clone())));
            }
            return Err(ApiError(
                StatusCode::CONFLICT,
                format!(
                    "an eigenbasis ({} , k = {}) is already being computed for this mesh; wait for it",
                    j.laplacian, j.k
                ),
            ));
        }
        let job = Job {
            state: "running".into(),
            laplacian: lap.name().into(),
            k,
            progress: 0.0,
            message: "assembling operators".into(),
            seconds: 0.0,
        };
        jobs.insert(id.clone(), job.clone());
    }
    let s2 = s.clone();
    let id2 = id.clone();
    let item2 = item.clone();
    tokio::task::spawn_blocking(move || {
        let start = Instant::now();
        let Ok(e) = entry(&item2) else { return };
        let ops_item = s2.ops(e, lap);
        let Item::Ops(ops) = &*ops_item else { return };
        let mut progress = |p: f64, msg: String| {
            if let Some(j) = s2.jobs().get_mut(&id2) {
                j.progress = p;
                j.message = msg;
                j.seconds = start.elapsed().as_secs_f64();
            }
        };
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            compute_basis(ops, k, &mut progress)
        }))
        .unwrap_or_else(|_| Err("the eigensolver failed unexpectedly".into()));
        let mut jobs = s2.jobs();
        let Some(j) = jobs.get_mut(&id2) else { return };
        j.seconds = start.elapsed().as_secs_f64();
        match result {
            Ok(b) => {
                let bytes = basis_bytes(b.n, b.k(), b.mass.nnz());
                s2.cache.insert(
                    Key::Basis(id2.clone(), lap, k),
                    Arc::new(Item::Basis(b)),
                    bytes,
                );
                j.state = "done".into();
                j.progress = 1.0;
                j.message = format!("{k} pairs in {:.2} s", j.seconds);
            }
            Err(msg) => {
                j.state = "error".into();
                j.message = msg;
            }
        }
    });
    let job = s.jobs().get(&id).cloned();
    Ok((
        StatusCode::ACCEPTED,
        Json(job.unwrap_or_else(|| unreachable_job(lap, k))),
    ))
}

fn unreachable_job(lap: Laplacian, k: usize) -> Job {
    Job {
        state: "running".into(),
        laplacian: lap.name().into(),
        k,
        progress: 0.0,
        message: String::new(),
        seconds: 0.0,
    }
}

async fn basis_status(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    let job = s.jobs().get(&id).cloned();
    Ok(Json(job.unwrap_or(Job {
        state: "idle".into(),
        laplacian: String::new(),
        k: 0,
        progress: 0.0,
        message: "no eigenbasis requested yet".into(),
        seconds: 0.0,
    })))
}

// ---------- fields ----------

/// A computed field with everything the page draws.
pub struct FieldOutput {
    /// The values (f64).
    pub values: Vec<f64>,
    /// The JSON header.
    pub header: serde_json::Value,
    /// Level-set segments.
    pub segments: Vec<f32>,
    /// Level sets (for the picture downloads).
    pub level_sets: Vec<render::LevelSet>,
    /// Critical points (for the picture downloads).
    pub critical: spectral_mesh::fields::critical_points::CriticalPoints,
}

fn compute_field(s: &AppState, e: &MeshEntry, p: &FieldParams) -> ApiResult<FieldOutput> {
    let start = Instant::now();
    let n = e.mesh.n_vertices();
    let c = compute::check(p, n)?;
    let lap = parse_laplacian(p.laplacian.as_deref())?;
    let basis_info;
    let values = if p.experiment.needs_basis() {
        let k = p.k.unwrap_or(100);
        if k == 0 || k > n {
            return Err(ApiError::unprocessable(format!(
                "k must be in 1..={n} (the number of vertices); got {k}"
            )));
        }
        let item = s.basis(&e.id, lap, k).ok_or_else(|| {
            ApiError(
                StatusCode::CONFLICT,
                format!(
                    "no eigenbasis ({}, k = {k}) for this mesh yet: compute it first",
                    lap.name()
                ),
            )
        })?;
        let Item::Basis(b) = &*item else {
            return Err(ApiError(
                StatusCode::INTERNAL_SERVER_ERROR,
                "cache mix-up".into(),
            ));
        };
        basis_info = json!({
            "laplacian": lap.name(), "k": k, "basis_k": b.k(),
            "lambda_min": b.values.first(), "lambda_max": b.values.get(k - 1),
        });
        compute::spectral_field(p.experiment, b, k, &c)?
    } else {
        let ops_item = s.ops(e, lap);
        let Item::Ops(ops) = &*ops_item else {
            return Err(ApiError(
                StatusCode::INTERNAL_SERVER_ERROR,
                "cache mix-up".into(),
            ));
        };
        let spec = compute::parse_constraints(p.constraints.as_deref().unwrap_or("2"), n)?;
        let cons = spec
            .resolve(&e.mesh)
            .map_err(|err| ApiError::unprocessable(err.to_string()))?;
        let f =
            spectral_mesh::fields::harmonic::harmonic_map_with_operators(&e.mesh, ops, &cons, 1)
                .map_err(|err| ApiError::unprocessable(err.to_string()))?;
        basis_info = json!({"laplacian": lap.name(), "constraints": cons});
        f
    };
    if values.iter().any(|v| !v.is_finite()) {
        return Err(ApiError::unprocessable(
            "the field has non-finite values (try a larger t or another filter)",
        ));
    }
    let compute_ms = start.elapsed().as_secs_f64() * 1e3;
    let (lo, hi) = compute::min_max(&values);
    let cp = spectral_mesh::fields::critical_points::critical_points(&e.mesh, &values)
        .map_err(|err| ApiError(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()))?;
    let chi = e.topo.euler_characteristic();
    let bordered = !e.topo.boundary_loops.is_empty();
    let (found, expected) = if bordered {
        cp.euler_check_doubled(chi)
    } else {
        cp.euler_check(chi)
    };
    let critical = json!({
        "minima": cp.minima, "maxima": cp.maxima, "saddles": cp.saddles,
        "on_boundary": cp.on_boundary, "non_manifold": cp.non_manifold,
        "saddle_count": cp.saddle_count(),
        "doubled": bordered, "euler_found": found, "euler_expected": expected,
        "euler_ok": found == expected, "chi": chi,
    });
    let isos = render::level_values(lo, hi, c.levels);
    let sets = render::extract_level_sets(&e.mesh, &values, &isos);
    let mut counts = Vec::with_capacity(sets.len());
    let mut segments = Vec::new();
    for ls in &sets {
        counts.push(ls.segments.len() as u32);
        for seg in &ls.segments {
            for q in seg {
                segments.extend(q.iter().map(|&x| x as f32));
            }
        }
    }
    let header = json!({
        "n": n,
        "experiment": p.experiment.name(),
        "min": lo,
        "max": hi,
        "source": c.source,
        "levels": isos,
        "level_counts": counts,
        "critical": critical,
        "basis": basis_info,
        "compute_ms": compute_ms,
        "total_ms": start.elapsed().as_secs_f64() * 1e3,
    });
    Ok(FieldOutput {
        values,
        header,
        segments,
        level_sets: sets,
        critical: cp,
    })
}

async fn run_field(s: &Arc<AppState>, id: &str, p: FieldParams) -> ApiResult<FieldOutput> {
    let item = get_mesh(s, id)?;
    let s2 = s.clone();
    tokio::task::spawn_blocking(move || {
        let e = entry(&item)?;
        compute_field(&s2, e, &p)
    })
    .await
    .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
}

async fn field(
    State(s): St,
    Path(id): Path<String>,
    body: Result<Json<FieldParams>, JsonRejection>,
) -> ApiResult<Response> {
    let Json(p) = body.map_err(|r| ApiError::bad(r.body_text()))?;
    let out = run_field(&s, &id, p).await?;
    let mut head = serde_json::to_vec(&out.header)
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?;
    while head.len() % 4 != 0 {
        head.push(b' ');
    }
    let mut buf =
        Vec::with_capacity(4 + head.len() + 4 * out.values.len() + 4 * out.segments.len());
    buf.extend((head.len() as u32).to_le_bytes());
    buf.extend(head);
    for v in &out.values {
        buf.extend((*v as f32).to_le_bytes());
    }
    for v in &out.segments {
        buf.extend(v.to_le_bytes());
    }
    Ok(octet(buf))
}

// ---------- downloads ----------

fn hue_rgb(v: f64) -> [u8; 3] {
    // Hue of HSV from red through yellow, green, cyan, blue, magenta (MATH.md).
    let h = (v.clamp(0.0, 1.0) * 300.0) / 60.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        _ => (x, 0.0, 1.0),
    };
    [(r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8]
}

fn normalized(values: &[f64]) -> Vec<f64> {
    let (lo, hi) = compute::min_max(values);
    let d = if hi > lo { hi - lo } else { 1.0 };
    values.iter().map(|v| (v - lo) / d).collect()
}

fn experiment_toml(e: &MeshEntry, p: &FieldParams) -> String {
    let mut t = toml::Table::new();
    let mut put = |k: &str, v: toml::Value| {
        t.insert(k.to_string(), v);
    };
    put("experiment", p.experiment.name().into());
    put("mesh", e.source.clone().into());
    put(
        "laplacian",
        p.laplacian.clone().unwrap_or_else(|| "fem".into()).into(),
    );
    if p.experiment != Experiment::Harmonic {
        put("k", (p.k.unwrap_or(100) as i64).into());
        put("t", p.t.unwrap_or(0.5).into());
        let filter = serde_json::to_value(p.filter.unwrap_or_default())
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_else(|| "biharmonic".into());
        if filter == "mix" {
            put("a", p.a.unwrap_or(0.5).into());
        }
        if filter == "custom" {
            put("custom", p.custom.clone().unwrap_or_default().into());
            put(
                "custom_kind",
                p.custom_kind.clone().unwrap_or_else(|| "w".into()).into(),
            );
        }
        put("filter", filter.into());
        put("source", (p.source.unwrap_or(0) as i64).into());
    } else {
        put(
            "constraints",
            p.constraints.clone().unwrap_or_else(|| "2".into()).into(),
        );
    }
    if let Some(c) = p.component {
        put("component", (c as i64).into());
    }
    if p.experiment == Experiment::Segmentation {
        put("segments", (p.segments.unwrap_or(5) as i64).into());
    }
    put("levels", (p.levels.unwrap_or(10) as i64).into());
    let body = toml::to_string(&t).unwrap_or_default();
    format!(
        "# spectral-mesh experiment, saved by the web app.\n# Replay: spectral-mesh run THIS_FILE.toml\n{body}"
    )
}

async fn download(
    State(s): St,
    Path(id): Path<String>,
    query: Result<Query<FieldParams>, axum::extract::rejection::QueryRejection>,
) -> ApiResult<Response> {
    let Query(p) = query.map_err(|r| ApiError::bad(r.body_text()))?;
    let format = p.format.clone().unwrap_or_else(|| "txt".into());
    let item = get_mesh(&s, &id)?;
    let e = entry(&item)?;
    let stem = format!("{}-{}", p.experiment.name(), &id[..8]);
    let attach = |name: String, mime: &'static str, body: Vec<u8>| -> Response {
        (
            [
                (header::CONTENT_TYPE, mime.to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    format!("attachment; filename=\"{name}\""),
                ),
            ],
            body,
        )
            .into_response()
    };
    if format == "toml" {
        compute::check(&p, e.mesh.n_vertices())?;
        return Ok(attach(
            format!("{stem}.toml"),
            "application/toml",
            experiment_toml(e, &p).into_bytes(),
        ));
    }
    if !matches!(format.as_str(), "txt" | "ply" | "wrl" | "png") {
        return Err(ApiError::bad(format!(
            "unknown format '{format}': expected txt, ply, wrl, png or toml"
        )));
    }
    let p_colormap = p.colormap.clone().unwrap_or_else(|| "hue".into());
    let uses_source = matches!(
        p.experiment,
        Experiment::Heat | Experiment::Diffusion | Experiment::Distance
    );
    let source = p.source.unwrap_or(0);
    let out = run_field(&s, &id, p).await?;
    let values = &out.values;
    match format.as_str() {
        "txt" => {
            let mut s = String::with_capacity(values.len() * 24);
            for v in values {
                s.push_str(&format!("{v}\n"));
            }
            Ok(attach(format!("{stem}.txt"), "text/plain", s.into_bytes()))
        }
        "ply" => {
            let norm = normalized(values);
            let mut s = format!(
                "ply\nformat ascii 1.0\ncomment spectral-mesh field\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty double value\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
                e.mesh.n_vertices(),
                e.mesh.n_triangles()
            );
            for ((p, v), u) in e.mesh.positions().iter().zip(values).zip(&norm) {
                let c = hue_rgb(*u);
                s.push_str(&format!(
                    "{} {} {} {} {} {} {}\n",
                    p[0], p[1], p[2], c[0], c[1], c[2], v
                ));
            }
            for t in e.mesh.triangles() {
                s.push_str(&format!("3 {} {} {}\n", t[0], t[1], t[2]));
            }
            Ok(attach(
                format!("{stem}.ply"),
                "application/octet-stream",
                s.into_bytes(),
            ))
        }
        _ => {
            let cmap: render::Colormap = p_colormap
                .parse()
                .map_err(|_| ApiError::bad(format!("unknown colour map '{p_colormap}'")))?;
            let mut scene = render::Scene::with_field(&e.mesh, values, cmap, None);
            scene.level_sets = out.level_sets;
            let pos = e.mesh.positions();
            let mut mark = |v: usize, kind| {
                scene.markers.push(render::Marker {
                    position: pos[v],
                    kind,
                })
            };
            out.critical
                .minima
                .iter()
                .for_each(|&v| mark(v, render::MarkerKind::Minimum));
            out.critical
                .maxima
                .iter()
                .for_each(|&v| mark(v, render::MarkerKind::Maximum));
            out.critical
                .saddles
                .iter()
                .for_each(|&(v, _)| mark(v, render::MarkerKind::Saddle));
            if uses_source {
                mark(source, render::MarkerKind::Source);
            }
            let mut buf = Vec::new();
            if format == "wrl" {
                render::write_vrml(&mut buf, &scene)
                    .map_err(|err| ApiError(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()))?;
                Ok(attach(format!("{stem}.wrl"), "model/vrml", buf))
            } else {
                let img = render::render_scene(&scene, &render::RenderOptions::default())
                    .map_err(|err| ApiError(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()))?;
                img.write_png(&mut buf)
                    .map_err(|err| ApiError(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()))?;
                Ok(attach(format!("{stem}.png"), "image/png", buf))
            }
        }
    }
}

//! Routes of meshes and point clouds: health, shapes, upload, info, geometry.

use std::sync::Arc;

use axum::Json;
use axum::body::Body;
use axum::extract::{Extension, Path, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;
use spectral_mesh::analysis::memory::creation_bytes;
use spectral_mesh::analysis::{Analysis, AnalysisInput};
use spectral_mesh::io::{Input, LoadedPoints};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::operators::PointCloudParams;
use spectral_mesh::shapes::ShapeError;
use spectral_mesh::{Laplacian, Mesh};

use super::reading::{
    SHAPE_BYTES_PER_VERTEX, UPLOAD_FACTOR, check_id, json_body, no_room, read_body, reserve,
};
use crate::body;
use crate::entries::{AnalysisKey, Item, Key, Loaded, MeshEntry, Reservation};
use crate::error::{ApiError, ApiResult, internal};
use crate::limits::{Deadline, mib};
use crate::state::{AppState, St};

pub(super) async fn health(State(s): St) -> Json<serde_json::Value> {
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

pub(super) async fn shapes() -> Json<serde_json::Value> {
    let list: Vec<_> = spectral_mesh::shapes::shape_names()
        .into_iter()
        .map(|s| {
            json!({"name": s.name, "description": s.description,
                   "default_vertices": s.default_vertices, "vertex_formula": s.vertex_formula})
        })
        .collect();
    Json(json!({ "shapes": list }))
}

/// `k` against an input of `n` vertices or points (`noun`) and `--max-k` (422), in the
/// input's words.
pub(super) fn check_k(k: usize, n: usize, noun: &str, max_k: usize) -> ApiResult<()> {
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

pub(super) fn info_json(mesh: &Mesh, topo: &Topology) -> serde_json::Value {
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
pub(super) fn cloud_info(
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

pub(super) fn mesh_reply(e: &MeshEntry) -> serde_json::Value {
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

/// Largest built-in shape the web app builds whatever `--max-vertices` says: the
/// library's limit.
pub use spectral_mesh::defaults::server::MAX_SHAPE_VERTICES;

/// Checks a mesh or a point cloud against the vertex and triangle limits (413); `noun`
/// is `vertices` or `points`.
pub(super) fn check_size(
    s: &AppState,
    what: &str,
    noun: &str,
    n: usize,
    m: usize,
) -> ApiResult<()> {
    let l = &s.config.limits;
    let within = |count: usize, noun: &str, limit: usize, option: &str| {
        if count > limit {
            return Err(ApiError(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!(
                    "{what} has {count} {noun}, more than this server's limit of {limit} ({option})"
                ),
            ));
        }
        Ok(())
    };
    within(n, noun, l.max_vertices, "--max-vertices")?;
    within(m, "triangles", l.max_faces, "--max-faces")
}

/// The loaded entry of `id`, if any.
pub(super) fn loaded(s: &AppState, id: &str) -> Option<serde_json::Value> {
    let item = s.mesh(id)?;
    match &*item {
        Item::Mesh(e) => Some(mesh_reply(e)),
        Item::Analysis(_) => None,
    }
}

/// Enters a checked mesh or cloud into the cache, with the reservation that covered its
/// reading and building released first (what stays is the entry itself).
pub(super) fn enter(
    s: &AppState,
    entry: MeshEntry,
    reservation: Reservation,
) -> ApiResult<serde_json::Value> {
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
pub(super) fn insert_mesh(
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
pub(super) async fn insert_cloud(
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
        creation_bytes(n, Laplacian::Robust, true),
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
pub(super) fn shape_error(text: &str, cap: usize, e: ShapeError) -> ApiError {
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
pub(super) enum Read {
    /// A mesh, entered: the reply.
    Entered(serde_json::Value),
    /// A point cloud, to be entered with its Laplacian.
    Points(LoadedPoints, String, Reservation),
}

pub(super) async fn load_mesh(
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

pub(super) fn get_mesh(s: &AppState, id: &str) -> ApiResult<Arc<Item>> {
    check_id(id)?;
    s.mesh(id).ok_or_else(|| {
        ApiError::not_found(format!(
            "mesh {id} is not loaded (it may have been evicted from the cache): load it again"
        ))
    })
}

pub(super) fn entry(item: &Item) -> ApiResult<&MeshEntry> {
    match item {
        Item::Mesh(e) => Ok(e),
        _ => Err(internal("cache mix-up")),
    }
}

pub(super) async fn mesh_info(
    State(s): St,
    Path(id): Path<String>,
) -> ApiResult<Json<serde_json::Value>> {
    let item = get_mesh(&s, &id)?;
    Ok(Json(mesh_reply(entry(&item)?)))
}

pub(super) fn octet(body: Vec<u8>) -> Response {
    (
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/octet-stream"),
        )],
        body,
    )
        .into_response()
}

pub(super) async fn geometry(
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

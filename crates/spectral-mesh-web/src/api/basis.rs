//! Routes of the eigenbasis job: start, cancel, status.

use std::sync::Arc;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use spectral_mesh::analysis::Analysis;
use spectral_mesh::analysis::memory::creation_bytes;

use super::meshes::{check_k, entry, get_mesh};
use super::reading::{MeshPost, reserve};
use crate::body;
use crate::entries::{AnalysisKey, Item};
use crate::error::{ApiError, ApiResult, busy, internal};
use crate::jobs::{self, Job, Submit, Submitted};
use crate::limits::{Deadline, mib};
use crate::state::{AppState, St};

/// The analysis of `key`: the existing one, or a new one made off the request thread
/// with the memory of its assembly reserved first.
pub(super) async fn analysis_for(
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
        creation_bytes(n, key.laplacian, points),
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
pub(super) fn client_id(headers: &HeaderMap) -> Option<String> {
    let v = headers.get("x-client-id")?.to_str().ok()?.trim();
    (!v.is_empty() && v.len() <= 64 && v.bytes().all(|b| b.is_ascii_graphic()))
        .then(|| v.to_string())
}

/// Queues `analysis.basis(k)` (see [`crate::jobs`] for the queue, the admission and the
/// rules that stop a job).
pub(super) async fn start_basis(
    State(s): St,
    headers: HeaderMap,
    mut post: MeshPost,
) -> ApiResult<Response> {
    let b = post.parse(body::parse_basis)?;
    let (id, deadline) = (post.id, post.deadline);
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
    let estimate = analysis.basis_peak_bytes(b.k);
    let after = analysis.bytes_with_basis(b.k);
    if analysis.held_k() < b.k {
        if after + mesh > limits.cache_bytes {
            return Err(ApiError::unprocessable(format!(
                "an eigenbasis of k = {} on {n} {noun} would make this input and its analysis hold about {}, more than the cache's {} (--cache-mib): ask for fewer pairs",
                b.k,
                mib(after + mesh),
                mib(limits.cache_bytes)
            )));
        }
        let held = analysis.cached_bytes() + mesh;
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
        limits.max_queued,
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
pub(super) async fn cancel_basis(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    let job = s
        .jobs
        .cancel(&id)
        .ok_or_else(|| ApiError::not_found("no eigenbasis computation for this mesh"))?;
    jobs::pump(&s);
    Ok(Json(job))
}

pub(super) async fn basis_status(State(s): St, Path(id): Path<String>) -> ApiResult<Json<Job>> {
    get_mesh(&s, &id)?;
    Ok(Json(s.jobs.status(&id)))
}

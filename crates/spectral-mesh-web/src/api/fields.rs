//! The field route: one field of a loaded mesh, computed by the analysis.

use std::sync::Arc;

use axum::extract::State;
use axum::http::StatusCode;
use axum::response::Response;
use spectral_mesh::analysis::memory::field_bytes;
use spectral_mesh::analysis::{Analysis, AnalysisError};

use super::basis::analysis_for;
use super::meshes::{entry, get_mesh, octet};
use super::reading::{MeshPost, reserve};
use crate::body::{self, FieldBody};
use crate::entries::{AnalysisKey, Item};
use crate::error::{ApiError, ApiResult, internal};
use crate::field::{FieldReply, field_reply};
use crate::limits::Deadline;
use crate::state::{AppState, St};

/// A computed field with what it was computed on.
pub(super) struct Computed {
    /// The field's reply.
    pub(super) reply: FieldReply,
    /// The binary reply, when asked for.
    pub(super) bytes: Option<Vec<u8>>,
    /// The mesh entry it was computed on.
    pub(super) item: Arc<Item>,
    /// The analysis that computed it.
    pub(super) analysis: Arc<Analysis>,
}

/// The reply to `body` on mesh `id` (off the request thread, with its memory reserved
/// first); 409 when the basis is not there yet. With `encode`, the binary reply too (on
/// the field threads as well).
pub(super) async fn compute(
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
    let figure = body.figure_options()?;
    let (s2, an) = (s.clone(), analysis.clone());
    let (reply, bytes) = tokio::task::spawn_blocking(move || -> ApiResult<_> {
        let before = an.memory_bytes();
        let reply = s2.on_field_threads(|| -> ApiResult<_> {
            let segments = body.segments && body.levels > 0;
            let Some(r) = field_reply(&an, &body.request, &figure, segments)? else {
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
pub(super) fn missing_basis(
    s: &AppState,
    key: &AnalysisKey,
    body: &FieldBody,
    held: usize,
) -> ApiError {
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

pub(super) async fn field(State(s): St, mut post: MeshPost) -> ApiResult<Response> {
    let body = post.parse(body::parse_field)?;
    let c = compute(&s, &post.id, body, true, post.deadline).await?;
    Ok(octet(c.bytes.unwrap_or_default()))
}

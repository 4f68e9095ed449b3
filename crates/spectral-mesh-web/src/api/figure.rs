//! The figure route: a field's figure described again for other picture options (the
//! page changes its colour map or its levels without asking for the field again).

use axum::Json;
use axum::body::Body;
use axum::extract::{Extension, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use spectral_mesh::experiments::file::FigureFile;
use spectral_mesh_render::description::{FieldSummary, describe};
use spectral_mesh_render::figure::FigureOptions;

use super::reading::json_body;
use crate::error::{ApiError, ApiResult};
use crate::limits::Deadline;
use crate::state::St;

/// The body of `POST /api/figure`: the summary of a field reply's `figure` and the
/// picture options (the keys of an experiment file's `[figure]` table).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FigureBody {
    summary: FieldSummary,
    #[serde(default)]
    options: FigureFile,
}

/// `POST /api/figure`: the render crate's description of the figure.
pub(super) async fn figure(
    State(s): St,
    Extension(deadline): Extension<Deadline>,
    headers: HeaderMap,
    body: Body,
) -> ApiResult<Response> {
    let (bytes, r) = json_body(&s, &headers, body, deadline).await?;
    let b: FigureBody = serde_json::from_slice(&bytes).map_err(|e| {
        ApiError::bad(format!(
            "figure: {e} (expected {{\"summary\": ..., \"options\": {{...}}}})"
        ))
    })?;
    drop((bytes, r));
    let options = FigureOptions::from_file(&b.options).map_err(|e| ApiError::bad(e.to_string()))?;
    Ok(Json(describe(&b.summary, &options)).into_response())
}

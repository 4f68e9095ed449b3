//! Downloads of a field: picture, VRML, PLY, text, experiment file.

use std::sync::Arc;

use axum::extract::rejection::QueryRejection;
use axum::extract::{Extension, Path, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use spectral_mesh::analysis::AnalysisInput;
use spectral_mesh::experiments::file::{ExperimentFile, PointCloudFile};
use spectral_mesh_render::figure::Figure;

use super::fields::{Computed, compute};
use super::meshes::entry;
use super::reading::{MeshPost, reserve};
use crate::body::{self, FieldBody};
use crate::entries::Loaded;
use crate::error::{ApiError, ApiResult, internal};
use crate::limits::Deadline;
use crate::state::{AppState, St};

/// Query of `GET /api/mesh/{id}/download`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DownloadQuery {
    format: Option<String>,
    /// The same JSON object as the body of a field request.
    body: String,
}

pub(super) async fn download_get(
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

pub(super) async fn download_post(State(s): St, mut post: MeshPost) -> ApiResult<Response> {
    let body = post.parse(body::parse_field)?;
    download(&s, &post.id, body, post.deadline).await
}

/// Formats a download can have.
pub const DOWNLOAD_FORMATS: [&str; 5] = ["png", "wrl", "ply", "txt", "toml"];

pub(super) async fn download(
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
    let pixels = options.canvas.size as usize * options.canvas.height() as usize;
    let need = match format.as_str() {
        "png" => 16 * pixels + 200 * n,
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

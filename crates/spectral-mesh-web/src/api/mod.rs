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

mod basis;
mod downloads;
mod fields;
mod figure;
mod meshes;
mod reading;
mod static_files;

use basis::*;
use downloads::*;
use fields::*;
use figure::*;
use meshes::*;
use reading::*;
use static_files::*;

pub use downloads::DOWNLOAD_FORMATS;
pub use meshes::MAX_SHAPE_VERTICES;
pub use reading::{SHAPE_BYTES_PER_VERTEX, UPLOAD_FACTOR};
pub use static_files::assets_embedded;

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
        .route("/api/figure", post(figure))
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

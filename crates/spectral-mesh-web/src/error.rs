//! The error reply of every route: a status and `{"error": message}`.

use axum::Json;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;
use spectral_mesh::analysis::AnalysisError;
use spectral_mesh::spectral::eigenbasis::EigenError;

use crate::body::BodyError;

/// An error response: a status and a message, sent as `{"error": message}`.
#[derive(Debug)]
pub struct ApiError(pub StatusCode, pub String);

impl ApiError {
    pub(crate) fn bad(msg: impl Into<String>) -> Self {
        Self(StatusCode::BAD_REQUEST, msg.into())
    }
    pub(crate) fn unprocessable(msg: impl Into<String>) -> Self {
        Self(StatusCode::UNPROCESSABLE_ENTITY, msg.into())
    }
    pub(crate) fn not_found(msg: impl Into<String>) -> Self {
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

/// A 500 naming the cause.
pub(crate) fn internal(e: impl std::fmt::Display) -> ApiError {
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

/// The result of a route.
pub type ApiResult<T> = Result<T, ApiError>;

/// A 503 with `Retry-After`.
pub fn busy(msg: impl Into<String>, retry_after: u64) -> Response {
    let mut r = ApiError(StatusCode::SERVICE_UNAVAILABLE, msg.into()).into_response();
    if let Ok(v) = HeaderValue::from_str(&retry_after.to_string()) {
        r.headers_mut().insert(header::RETRY_AFTER, v);
    }
    r
}

//! Reading request bodies within the limits: memory reservations, deadlines, draining refused bodies.

use std::sync::Arc;

use axum::body::{Body, Bytes};
use axum::extract::{FromRequest, FromRequestParts, Path, Request};
use axum::http::{HeaderMap, StatusCode, header};
use http_body_util::BodyExt;

use crate::cache::Shortfall;
use crate::entries::Reservation;
use crate::error::{ApiError, ApiResult, internal};
use crate::limits::{Deadline, mib};
use crate::state::AppState;

/// A mesh id as the server hands them out: 16 hexadecimal digits (400 otherwise).
pub(super) fn check_id(id: &str) -> ApiResult<()> {
    if id.len() == 16 && id.bytes().all(|b| b.is_ascii_hexdigit()) {
        Ok(())
    } else {
        Err(ApiError::bad("a mesh id is 16 hexadecimal digits"))
    }
}

/// The answer to a reservation that failed: 503 when other work holds the memory (try
/// again), `never` (413 or 422) when it could never fit.
pub(super) fn no_room(what: &str, short: &Shortfall, never: StatusCode) -> ApiError {
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
pub(super) async fn reserve(
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
pub(super) async fn read_body(
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
pub(super) const DRAIN_BYTES: usize = 16 << 20;

/// Reads and drops up to [`DRAIN_BYTES`] more of a body refused as too large (for at most
/// 5 s, never past the deadline): a client still sending then reads the 413 instead of a
/// connection reset by the server's closing on unread data.
pub(super) async fn drain(body: &mut Body, deadline: Deadline) {
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
pub(super) const JSON_FACTOR: usize = 8;

/// Memory reserved per byte of an uploaded input and per vertex of a built shape: the
/// library's estimates.
pub use spectral_mesh::analysis::memory::{READ_FACTOR as UPLOAD_FACTOR, SHAPE_BYTES_PER_VERTEX};

pub(super) async fn json_body(
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

/// The JSON body posted to a mesh's route (`/api/mesh/{id}/...`): the mesh id (checked
/// before the body is read), the body read within the JSON limit with its memory
/// reserved ([`json_body`]), and the request's deadline.
pub(super) struct MeshPost {
    /// The mesh id of the path.
    pub(super) id: String,
    /// The request's deadline.
    pub(super) deadline: Deadline,
    /// The body with the memory reserved for it and its parsing, until parsed.
    body: Option<(Bytes, Reservation)>,
}

impl MeshPost {
    /// The body parsed by `parse`; the body's bytes and reservation are freed then.
    pub(super) fn parse<T, E>(&mut self, parse: impl FnOnce(&[u8]) -> Result<T, E>) -> ApiResult<T>
    where
        ApiError: From<E>,
    {
        let (bytes, _reservation) = self
            .body
            .take()
            .ok_or_else(|| internal("the body was parsed already"))?;
        Ok(parse(&bytes)?)
    }
}

impl FromRequest<Arc<AppState>> for MeshPost {
    type Rejection = ApiError;

    async fn from_request(req: Request, s: &Arc<AppState>) -> ApiResult<Self> {
        let (mut parts, body) = req.into_parts();
        let Path(id) = Path::<String>::from_request_parts(&mut parts, s)
            .await
            .map_err(|e| ApiError::bad(e.body_text()))?;
        check_id(&id)?;
        let deadline = *parts
            .extensions
            .get::<Deadline>()
            .ok_or_else(|| internal("the request has no deadline"))?;
        let body = json_body(s, &parts.headers, body, deadline).await?;
        Ok(Self {
            id,
            deadline,
            body: Some(body),
        })
    }
}

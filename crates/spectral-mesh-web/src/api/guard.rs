//! The layer every request passes first: host and origin checks, the cap on requests
//! in progress and the request deadline.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::{Request, State};
use axum::http::{StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::error::{ApiError, busy};
use crate::limits::{Deadline, check_host_and_origin};
use crate::state::AppState;

/// The layer every request passes first: host and origin checks (403), the cap on
/// requests in progress (503), and the request deadline (a [`Deadline`] extension for
/// the handlers, which answer 408 or 503 themselves; past it plus two seconds the
/// request is answered 503 here).
pub(super) async fn guard(
    State(s): State<Arc<AppState>>,
    mut req: Request,
    next: Next,
) -> Response {
    let headers = req.headers();
    let text = |name: header::HeaderName| headers.get(name).and_then(|v| v.to_str().ok());
    if let Err(msg) = check_host_and_origin(s.config.host, text(header::HOST), text(header::ORIGIN))
    {
        return ApiError(StatusCode::FORBIDDEN, msg).into_response();
    }
    let limits = &s.config.limits;
    let (now, _ticket) = s.in_flight.enter();
    if now > limits.max_requests {
        return busy(
            format!(
                "the server is busy: {} requests in progress, the limit is {} (--max-requests); try again",
                now - 1,
                limits.max_requests
            ),
            1,
        );
    }
    let deadline = Deadline::after(limits.request_seconds);
    req.extensions_mut().insert(deadline);
    let backstop = deadline.0 + Duration::from_secs(2);
    match tokio::time::timeout_at(backstop, next.run(req)).await {
        Ok(r) => r,
        Err(_) => busy(
            format!(
                "the request took longer than {} s (--request-seconds)",
                limits.request_seconds
            ),
            5,
        ),
    }
}

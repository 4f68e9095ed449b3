//! `GET /api/defaults`: every default the page needs, from the library (request keys,
//! analysis, pictures; [`spectral_mesh_render::defaults::to_json`]) and this server's
//! limits as configured (`limits`, see [`crate::Limits`]). The page states no default of
//! its own: it reads this object before its first request.

use std::sync::Arc;

use axum::Json;
use axum::extract::State;
use serde_json::Value;

use crate::state::AppState;

pub(super) async fn defaults(State(s): State<Arc<AppState>>) -> Json<Value> {
    let mut d = spectral_mesh_render::defaults::to_json();
    d["limits"] = serde_json::to_value(&s.config.limits).unwrap_or(Value::Null);
    Json(d)
}

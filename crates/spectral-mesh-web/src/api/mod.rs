//! The router and its handlers, one file a concern (routes of inputs, of the basis job,
//! of fields, of downloads, the page's files, reading bodies, the guard layer). Every
//! field is computed by the library's [`spectral_mesh::analysis::Analysis`]; these only
//! parse, cache and encode. The error reply is [`crate::error::ApiError`].

use std::sync::Arc;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::routing::{get, post};

use crate::state::AppState;

mod basis;
mod defaults;
mod downloads;
mod fields;
mod figure;
mod guard;
mod meshes;
mod reading;
mod static_files;

use basis::{basis_status, cancel_basis, start_basis};
use downloads::{download_get, download_post};
use fields::field;
use figure::figure;
use guard::guard;
use meshes::{geometry, health, load_mesh, mesh_info, shapes};
use static_files::{app_js, index, orbit_js, style_css, three_js};

pub use crate::error::ApiError;
pub use downloads::DOWNLOAD_FORMATS;
pub use meshes::MAX_SHAPE_VERTICES;
pub use reading::{SHAPE_BYTES_PER_VERTEX, UPLOAD_FACTOR};
pub use static_files::assets_embedded;

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
        .route("/api/defaults", get(defaults::defaults))
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

//! The page's static files and its vendored 3D library (a fixed list: no path parameters).

use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

use crate::error::ApiError;
use crate::limits::read_inside;
use crate::state::{AppState, St};

pub(super) const INDEX_HTML: &str = include_str!("../../static/index.html");
pub(super) const APP_JS: &str = include_str!("../../static/app.js");
pub(super) const STYLE_CSS: &str = include_str!("../../static/style.css");

pub(super) async fn static_file(
    state: &AppState,
    name: &str,
    builtin: &'static str,
    mime: &str,
) -> Response {
    let body = match &state.config.static_dir {
        Some(dir) => match read_inside(dir, name).await {
            Ok(b) => b,
            Err(e) => {
                return ApiError::not_found(format!("static file {e}")).into_response();
            }
        },
        None => builtin.as_bytes().to_vec(),
    };
    (
        [
            (header::CONTENT_TYPE, mime.to_string()),
            (header::CACHE_CONTROL, "no-cache".into()),
        ],
        body,
    )
        .into_response()
}

pub(super) async fn index(State(s): St) -> Response {
    static_file(&s, "index.html", INDEX_HTML, "text/html; charset=utf-8").await
}
pub(super) async fn app_js(State(s): St) -> Response {
    static_file(&s, "app.js", APP_JS, "text/javascript; charset=utf-8").await
}
pub(super) async fn style_css(State(s): St) -> Response {
    static_file(&s, "style.css", STYLE_CSS, "text/css; charset=utf-8").await
}

/// The page's third-party assets (three.js), embedded by `build.rs` from npm's
/// `node_modules` at build time.
mod assets {
    include!(concat!(env!("OUT_DIR"), "/assets.rs"));
}

/// True when the binary carries its page's 3D library.
pub fn assets_embedded() -> bool {
    assets::THREE_MODULE_JS.is_some() && assets::ORBIT_CONTROLS_JS.is_some()
}

/// A vendored asset: from the `node_modules` folder the server was told about
/// (`--node-modules` or `SPECTRAL_MESH_WEB_NODE_MODULES`), else the copy embedded at build
/// time, else the source tree's `web/node_modules` (a binary built without npm). The
/// header `X-Spectral-Mesh-Asset` says which (`folder` or `embedded`).
pub(super) async fn vendor(s: &AppState, rel: &str, embedded: Option<&'static [u8]>) -> Response {
    let told = s.config.node_modules.is_some()
        || std::env::var_os("SPECTRAL_MESH_WEB_NODE_MODULES").is_some();
    let reply = |origin: &'static str, body: Vec<u8>| {
        (
            [
                (header::CONTENT_TYPE, "text/javascript; charset=utf-8"),
                (header::CACHE_CONTROL, "max-age=3600"),
                (
                    header::HeaderName::from_static("x-spectral-mesh-asset"),
                    origin,
                ),
            ],
            body,
        )
            .into_response()
    };
    if let (Some(b), false) = (embedded, told) {
        return reply("embedded", b.to_vec());
    }
    match read_inside(&s.node_modules, rel).await {
        Ok(b) => reply("folder", b),
        Err(_) => match embedded {
            Some(b) => reply("embedded", b.to_vec()),
            None => ApiError(
                StatusCode::NOT_FOUND,
                format!(
                    "the page's 3D library (three.js, {rel}) is not in this binary: {}. Build the binary from the source tree with npm installed (`cargo build` runs `npm ci` in web/), or pass --node-modules with a folder holding npm's three package",
                    if assets::MISSING_WHY.is_empty() { "not embedded" } else { assets::MISSING_WHY }
                ),
            )
            .into_response(),
        },
    }
}
pub(super) async fn three_js(State(s): St) -> Response {
    vendor(&s, "three/build/three.module.js", assets::THREE_MODULE_JS).await
}
pub(super) async fn orbit_js(State(s): St) -> Response {
    vendor(
        &s,
        "three/examples/jsm/controls/OrbitControls.js",
        assets::ORBIT_CONTROLS_JS,
    )
    .await
}

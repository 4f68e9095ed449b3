//! # spectral-mesh-web
//!
//! The interactive local web app of spectral-mesh: one process serving a static page and
//! a JSON + binary API. Pick a shape or open a file, click a vertex, move a slider: the
//! field, its level sets and its critical points follow.
//!
//! ## API (all under `/api`)
//! - `GET  /api/shapes` -> `{shapes: [{name, description}]}`
//! - `POST /api/mesh` with JSON `{"shape": "sphere:res=3"}`, or the raw bytes of a mesh
//!   file (`Content-Type: application/octet-stream`, file name in `X-Filename`)
//!   -> `{mesh_id, n, m, info}`. Uploads stay in memory; over the cap: 413.
//! - `GET  /api/mesh/{id}` -> `{mesh_id, n, m, info}`
//! - `GET  /api/mesh/{id}/geometry` -> binary, little-endian: `u32 n, u32 m`,
//!   `f32 positions[3n]`, `u32 triangles[3m]`.
//! - `POST /api/mesh/{id}/basis` `{laplacian, k}` -> starts the eigenbasis off the request
//!   thread (one computation per mesh at a time; 409 when another is running);
//!   `GET /api/mesh/{id}/basis/status` -> `{state, laplacian, k, progress, message}`.
//! - `POST /api/mesh/{id}/field` with [`compute::FieldParams`] as JSON -> binary:
//!   `u32 header_len`, the JSON header (padded with spaces to a multiple of 4 bytes),
//!   `f32 values[n]`, `f32 segments[6 * total_segments]` (level-set segments
//!   `x1 y1 z1 x2 y2 z2`). The header has `min, max, levels, level_counts, critical`.
//! - `GET  /api/mesh/{id}/download?format=txt|ply|wrl|png|toml&...` with the same
//!   parameters as the field request, as a query string.
//!
//! Every error is a 4xx/5xx with `{"error": message}`. No endpoint takes a file path.
//!
//! ## Experiment file (`format=toml`)
//! A TOML file that `spectral-mesh run FILE.toml` replays. Keys (all but `experiment`
//! optional): `experiment` (harmonic | heat | diffusion | distance | signature |
//! segmentation | embedding | eigenfunction), `mesh` (a built-in shape spec such as
//! `"sphere:res=3"`, or the uploaded file's name), `laplacian` (cot | voronoi-cot | fem |
//! mixed-voronoi | uniform), `k`, `t`, `a`, `filter` (diffusion | commute | biharmonic | mix
//! | custom), `custom` (expression in s, t, a), `custom_kind` (w | phi), `source` (vertex,
//! 0-based), `constraints` (`"2"`, `"4"`, `"6"` or `"v=x,v=x"`), `levels`, `component`,
//! `segments`.

// Index loops over vertex ids read more plainly than zipped iterators in mesh code.
#![allow(clippy::needless_range_loop)]

pub mod api;
pub mod cache;
pub mod compute;
pub mod state;

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

/// Configuration of the server.
#[derive(Debug, Clone)]
pub struct ServeConfig {
    /// Address to listen on (default 127.0.0.1: another one must be asked for explicitly).
    pub host: IpAddr,
    /// Port (default 8000; 0 = any free port).
    pub port: u16,
    /// Memory cap of the mesh and eigenbasis cache, in bytes (default 1 GiB).
    pub cache_bytes: usize,
    /// Largest accepted upload, in bytes (default 64 MiB); larger ones get 413.
    pub max_upload_bytes: usize,
    /// Serve `index.html`, `app.js`, `style.css` from this folder instead of the built-in copies.
    pub static_dir: Option<PathBuf>,
    /// Folder holding `three/` (npm's `node_modules`); default: `web/node_modules` of the
    /// source tree, or `SPECTRAL_MESH_WEB_NODE_MODULES` when set.
    pub node_modules: Option<PathBuf>,
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            host: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 8000,
            cache_bytes: 1 << 30,
            max_upload_bytes: 64 << 20,
            static_dir: None,
            node_modules: None,
        }
    }
}

/// Errors that stop the server from starting.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The address could not be bound.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// The cause.
        source: std::io::Error,
    },
    /// The server stopped with an I/O error.
    #[error("server error: {0}")]
    Io(#[from] std::io::Error),
}

/// A bound server, not yet serving: lets the caller learn the URL (port 0) first.
pub struct BoundServer {
    listener: tokio::net::TcpListener,
    app: axum::Router,
    /// The address actually bound.
    pub addr: SocketAddr,
}

impl BoundServer {
    /// `http://host:port/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Serves until the process ends.
    pub async fn run(self) -> Result<(), ServeError> {
        axum::serve(self.listener, self.app).await?;
        Ok(())
    }
}

/// Binds the listening socket and builds the app.
pub async fn bind(config: ServeConfig) -> Result<BoundServer, ServeError> {
    let addr = SocketAddr::new(config.host, config.port);
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .map_err(|source| ServeError::Bind { addr, source })?;
    let addr = listener.local_addr()?;
    let state = Arc::new(state::AppState::new(config));
    Ok(BoundServer {
        listener,
        app: api::router(state),
        addr,
    })
}

/// Binds, prints `spectral-mesh web app: URL` on stdout, and serves until the process ends.
pub async fn serve(config: ServeConfig) -> Result<(), ServeError> {
    let server = bind(config).await?;
    println!("spectral-mesh web app: {}", server.url());
    server.run().await
}

/// [`serve`] on a fresh multi-threaded tokio runtime, for callers without one.
pub fn serve_blocking(config: ServeConfig) -> Result<(), ServeError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(serve(config))
}

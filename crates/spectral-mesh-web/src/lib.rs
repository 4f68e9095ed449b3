//! # spectral-mesh-web
//!
//! The interactive local web app of spectral-mesh: one process serving a static page and
//! a JSON + binary API. Pick a shape or open a file, click a vertex, move a slider: the
//! field, its level sets and its critical points follow.
//!
//! The server is a thin face over the library's [`spectral_mesh::analysis::Analysis`]:
//! it keeps one analysis per (mesh, Laplacian, normalisation) in a byte-bounded cache
//! (least recently used out), computes eigenbases off the request threads, and answers
//! field requests from the held basis only. Every field is the analysis' own
//! (`Analysis::field_if_ready`), so the page, the CLI, Python and experiment files give
//! the same numbers for the same request, with the same defaults: the shape scaled to
//! unit area, k = 100, t = 0.5, the bi-harmonic filter, the source at the vertex of
//! largest x.
//!
//! ## API (all under `/api`)
//!
//! - `GET  /api/defaults` -> every default and limit of the library (request keys,
//!   analysis, pictures, point clouds, batch: [`spectral_mesh_render::defaults::to_json`])
//!   and this server's `limits`; the page reads its defaults from it.
//!
//! Meshes and point clouds:
//! - `GET  /api/shapes` -> `{shapes: [{name, description, default_vertices, vertex_formula}]}`
//! - `POST /api/mesh` with JSON `{"shape": "sphere:res=3"}` (built with
//!   [`spectral_mesh::shapes::build_limited`] under the vertex limit: a spec whose mesh
//!   would be larger is refused with 413 before anything is built), or the raw bytes of a
//!   mesh or point file (`Content-Type: application/octet-stream`, file name in
//!   `X-Filename`), read by [`spectral_mesh::io::read_input_from_bytes`]: meshes (OFF, OBJ,
//!   PLY, STL) and point clouds (`.xyz`/`.pts`/`.txt`/`.csv` text, PLY with vertices and
//!   no faces, with or without normals)
//!   -> `{mesh_id, kind, n, m, source, laplacians, point_spacing, point_radius_factor, info}`. `kind` is
//!   `"mesh"` or `"point cloud"`; `laplacians` the discretizations that apply (a cloud:
//!   `["robust"]` only); `m` is 0 for a cloud. The id is the first 16 hex digits of the
//!   content hash ([`spectral_mesh::Mesh::content_hash`], or
//!   [`spectral_mesh::PointCloud::content_hash`]). A cloud is kept as the library's
//!   [`spectral_mesh::analysis::AnalysisInput`] and its analysis for the page's defaults
//!   (robust, unit area) is built at the upload with
//!   [`spectral_mesh::analysis::Analysis::from_input`]: a cloud whose point-cloud
//!   Laplacian cannot be built (collinear points) is refused there (422), and the reply
//!   gives its triangle union (`info.union_triangles`, `info.components`) and its mean
//!   point spacing. Every limit applies to clouds as to meshes (upload bytes, points as
//!   vertices, `k <= n`). Uploads stay in memory; over the cap: 413.
//! - `GET  /api/mesh/{id}` -> the same object.
//! - `GET  /api/mesh/{id}/geometry` -> binary, little-endian: `u32 n, u32 m`,
//!   `f32 positions[3n]`, `u32 triangles[3m]` (a cloud: its points, `m = 0`).
//!
//! The discretization (`laplacian` in basis, field and download bodies) defaults to the
//! input's: `fem` for a mesh, `robust` for a point cloud (its point-cloud Laplacian, Sharp
//! and Crane 2020, 30 neighbours), as in the CLI. Any other on a cloud is refused with 422
//! and a message saying why (those need triangles).
//!
//! Eigenbases (one computation per mesh at a time):
//! - `POST /api/mesh/{id}/basis` `{"k": 100, "laplacian": "fem", "normalize": true}` (all
//!   optional, these are the defaults) -> a job `{state, laplacian, normalize, k, held_k,
//!   progress, message, seconds}`: 200 with `state = "done"` when the analysis already
//!   holds `k` pairs, else 202 and `analysis.basis(k)` runs off the request thread. The
//!   same or a smaller `k` of the same analysis joins the running job; other parameters
//!   replace it and cancel its token (its state becomes `"cancelled"`). The eigensolver
//!   checks the token inside its iteration: a cancelled solve stops within a fraction of
//!   a second (the factorization itself is not interrupted).
//! - `GET  /api/mesh/{id}/basis/status` -> the job (`state`: `idle`, `running`, `done`,
//!   `error` or `cancelled`).
//! - `DELETE /api/mesh/{id}/basis` cancels the running computation.
//! - A request may carry `X-Client-Id` (the page sends a random id made once per tab on
//!   every request): a newer basis request of the same client for another mesh cancels
//!   its older job ([`jobs`]). `GET /api/health` counts the jobs superseded
//!   (`jobs_superseded`) and cancelled for any reason (`jobs_cancelled`) since the start.
//!
//! Fields:
//! - `POST /api/mesh/{id}/field` with a JSON object: a
//!   [`spectral_mesh::analysis::FieldRequest`] in the library's serde form (`kind` and its
//!   keys, unknown keys refused: `{"kind": "heat", "t": 0.01, "anchor": 12, "k": 200}`,
//!   `{"kind": "distance", "distance": "wfem-diffusion:t=0.1"}`, `{"kind": "harmonic",
//!   "constraints": [{"vertex": 3, "value": 0}, {"vertex": 9, "value": 1}]}`, ...) plus the
//!   analysis keys `laplacian` (default `fem`, `robust` for a point cloud) and `normalize` (default `true`) and the
//!   picture key `levels` (level sets, default the library's
//!   [`spectral_mesh::defaults::LEVELS`], at most [`spectral_mesh::defaults::MAX_LEVELS`]). Answered from the held
//!   basis only: 409 with a message when the analysis holds fewer than the request's `k`
//!   pairs (compute the basis first). The reply is binary, little-endian:
//!   `u32 header_len`, the JSON header (padded with spaces to a multiple of 4 bytes),
//!   `f32 values[n]`, `f32 segments[6 * total]` (level-set segments `x1 y1 z1 x2 y2 z2`,
//!   level after level). The header ([`field::FieldHeader`]) has `n`, `kind`, `request`
//!   (every default resolved, e.g. the source filled in), `source`, `marks`,
//!   `constraints`, `floating` (components a harmonic map left unconstrained), `laplacian`, `point_cloud`, `point_spacing` (a cloud's mean
//!   neighbour spacing, `null` for a mesh), `normalized`, `k`, `basis_k`, `lambda_max`,
//!   `categorical` (segmentation labels), `min`, `max`, `levels`, `level_counts`,
//!   `critical` (the library's `CriticalReport`: `points {minima, maxima, saddles,
//!   on_boundary, non_manifold}`, counts, `chi`, `doubled`, `lhs`, `rhs`, `holds`,
//!   `formula`, the check per component, and the plateau rule: `flat`, `flat_tolerance`,
//!   `plateau_components`; `null` for labels), `truncation` (heat and diffusion fields: the
//!   library's [`spectral_mesh::analysis::TruncationHint`], the weight of the first
//!   omitted eigenpair against the first varying one and a warning when truncation
//!   dominates; `null` otherwise) and `timing_ms {field, critical, levels, total}`. The
//!   page asks for `levels = 0` for a mesh (it draws level sets in its shader) and reads
//!   the values straight into a `Float32Array`; for a point cloud it asks for the level
//!   sets (the library's, on the triangle union of the cloud's Laplacian) and draws the
//!   segments over its splats.
//!
//! Downloads:
//! - `POST /api/mesh/{id}/download` with the body of a field request plus `format` (`png`,
//!   `wrl`, `ply`, `txt`, `toml`; default `txt`) and the picture keys `colormap`, `view`,
//!   `size` ([`spectral_mesh::defaults::MIN_PICTURE`] to [`spectral_mesh::defaults::MAX_PICTURE`]), `transparent`, `critical_points`, `colorbar` (as the `[figure]`
//!   table of experiment files), or `GET /api/mesh/{id}/download?format=F&body=JSON`
//!   with the same object URL-encoded. `png`, `wrl`, `ply` and `txt` are the render
//!   crate's [`spectral_mesh_render::figure::Figure::of_analysis`] of the field (`txt`: one
//!   value per line at full precision; a point cloud is drawn as discs sized from its
//!   point spacing, its `ply` and `wrl` files are point sets); `toml` is the experiment file
//!   ([`spectral_mesh::experiments::file::ExperimentFile::for_field`]) that
//!   `spectral-mesh run FILE.toml` replays to the same bits: `experiment = "field"`,
//!   `mesh` (the shape spec, or the uploaded file's name: put the file beside the
//!   experiment file), `mesh_hash`, `laplacian`, `normalize`, `basis_k` (when the basis
//!   held more pairs than the `k` used), the resolved request as `[field]` and the picture
//!   options as `[figure]`.
//!
//! Every error is a 4xx/5xx with `{"error": message}`: 400 for malformed JSON, unknown
//! keys or bad picture options, 404 for an unknown or evicted mesh, 409 for a missing
//! eigenbasis, 413 for an upload over the cap, 422 for values the analysis refuses (a
//! vertex out of range, `k` larger than the mesh, a filter that is not positive, ...).
//! No endpoint takes a file path. The server listens on 127.0.0.1 unless told otherwise.
//!
//! ## The page's assets
//! `index.html`, `app.js` and `style.css` are compiled in. The page's 3D library
//! (three.js, from npm) is embedded by `build.rs` from `web/node_modules` of the source
//! tree, which it fills with `npm ci` when missing and npm is available (offline-safe: a
//! failure only warns). A binary built without it serves a page that says how to get it.
//! So an installed binary, copied anywhere, serves its page without a source tree and the
//! page fetches nothing from the network. `ServeConfig::node_modules` (or
//! `SPECTRAL_MESH_WEB_NODE_MODULES`) serves the library from a folder instead.

pub mod api;
pub mod body;
pub mod cache;
pub mod config;
pub mod entries;
pub mod error;
pub mod field;
pub mod jobs;
pub mod limits;
pub mod state;

pub use config::ServeConfig;
pub use limits::Limits;

use std::net::SocketAddr;
use std::sync::Arc;

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
    tokio::spawn(watchdog(Arc::downgrade(&state)));
    Ok(BoundServer {
        listener,
        app: api::router(state),
        addr,
    })
}

/// Every half second: stops the jobs whose client went away or that ran too long, drops
/// the cache entries idle for longer than `idle_seconds`, forgets the jobs of meshes no
/// longer loaded, and starts what waits in the queue. Ends with the server.
async fn watchdog(state: std::sync::Weak<state::AppState>) {
    let mut tick = tokio::time::interval(std::time::Duration::from_millis(500));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    loop {
        tick.tick().await;
        let Some(s) = state.upgrade() else {
            return;
        };
        let l = &s.config.limits;
        s.jobs.enforce(l.job_seconds, l.job_idle_seconds);
        if l.idle_seconds > 0 {
            s.cache
                .expire(std::time::Duration::from_secs(l.idle_seconds));
        }
        s.jobs
            .forget(|id| s.cache.peek(&entries::Key::Mesh(id.to_string())).is_some());
        jobs::pump(&s);
    }
}

/// Binds, prints `spectral-mesh web app: URL` on stdout, and serves until the process ends.
/// Says so on stderr when the address is not a loopback one (other machines can reach
/// the server).
pub async fn serve(config: ServeConfig) -> Result<(), ServeError> {
    let server = bind(config).await?;
    println!("spectral-mesh web app: {}", server.url());
    if !server.addr.ip().is_loopback() {
        eprintln!(
            "warning: listening on {}: other machines on the network can use this server",
            server.addr
        );
    }
    server.run().await
}

/// [`serve`] on a fresh multi-threaded tokio runtime, for callers without one.
pub fn serve_blocking(config: ServeConfig) -> Result<(), ServeError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(serve(config))
}

/// A server running on a thread of its own (tests, tools): stops when dropped.
pub struct RunningServer {
    /// The address bound.
    pub addr: SocketAddr,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl RunningServer {
    /// `http://host:port/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }
}

impl Drop for RunningServer {
    fn drop(&mut self) {
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// [`bind`]s on a new thread with its own tokio runtime and serves there until the
/// returned handle is dropped; returns once the socket is bound.
pub fn spawn(config: ServeConfig) -> Result<RunningServer, ServeError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let server = rt.block_on(bind(config))?;
    let addr = server.addr;
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let thread = std::thread::spawn(move || {
        rt.block_on(async move {
            let _ = axum::serve(server.listener, server.app)
                .with_graceful_shutdown(async {
                    let _ = rx.await;
                })
                .await;
        });
    });
    Ok(RunningServer {
        addr,
        shutdown: Some(tx),
        thread: Some(thread),
    })
}

//! The defaults and limits defined here (the rest stay beside their types and are
//! re-exported by [`crate::defaults`]). This file imports nothing of the library, so any
//! module may read it.

/// Fields are computed on the shape scaled to unit area unless told otherwise (every
/// face: `AnalysisOptions::default()`, the batch, the web bodies, the page).
pub const NORMALIZE: bool = true;

/// Relative gap below which consecutive eigenvalues count as one cluster (the report of
/// `eigs`, [`crate::experiments::paper::eigenvalue_clusters`]).
pub const CLUSTER_TOLERANCE: f64 = 1e-6;

/// Coordinates of a spectral embedding written by default (the first pairs of non-zero
/// weight; a mesh output always has three).
pub const EMBED_DIMS: usize = 3;

/// Level sets drawn over a field (the figures of every face and the page's slider).
pub const LEVELS: usize = 20;
/// Most level sets a request, a figure or an experiment file may ask for.
pub const MAX_LEVELS: usize = 1000;
/// Picture width and height in pixels.
pub const PICTURE_SIZE: u32 = 800;
/// Smallest picture (and thumbnail), in pixels per side.
pub const MIN_PICTURE: u32 = 16;
/// Largest picture (and thumbnail), in pixels per side: the web server's downloads,
/// experiment files and batch thumbnails.
pub const MAX_PICTURE: u32 = 4096;

const _: () = assert!(MIN_PICTURE <= PICTURE_SIZE && PICTURE_SIZE <= MAX_PICTURE);
const _: () = assert!(LEVELS <= MAX_LEVELS);

/// Checks a picture size against [`MIN_PICTURE`] and [`MAX_PICTURE`] (the message says
/// the bounds).
pub fn check_picture_size(size: u32) -> Result<(), String> {
    if (MIN_PICTURE..=MAX_PICTURE).contains(&size) {
        Ok(())
    } else {
        Err(format!(
            "{size} pixels: use {MIN_PICTURE} to {MAX_PICTURE} pixels per side"
        ))
    }
}

/// Declares each limit as a public constant, and `to_json`, which names every one by its
/// name in lower case (`MAX_K` -> `max_k`): a limit is written once.
macro_rules! limits {
    ($($(#[$doc:meta])* $name:ident: $ty:ty = $value:expr;)*) => {
        $($(#[$doc])* pub const $name: $ty = $value;)*

        /// Every limit but [`HOST`], keyed by its name in lower case (`GET /api/defaults`'
        /// `server` object).
        pub fn to_json() -> serde_json::Value {
            let mut m = serde_json::Map::new();
            $(m.insert(stringify!($name).to_ascii_lowercase(), $name.into());)*
            serde_json::Value::Object(m)
        }
    };
}

/// The web server's limits (`spectral-mesh serve`'s options and the web crate's
/// `Limits::default()`): memory, sizes, counts and times.
pub mod server {
    use std::net::{IpAddr, Ipv4Addr};

    /// Address to listen on: this machine only.
    pub const HOST: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

    limits! {
        /// Port.
        PORT: u16 = 8000;
        /// Memory budget (cache plus work in progress), in MiB.
        MEMORY_MIB: usize = 2048;
        /// Most the cache of meshes and analyses may hold, in MiB.
        CACHE_MIB: usize = 1024;
        /// Largest mesh upload, in MiB.
        MAX_UPLOAD_MIB: usize = 64;
        /// Largest JSON body, in bytes.
        MAX_JSON_BYTES: usize = 1 << 20;
        /// Most vertices (or points) of an input.
        MAX_VERTICES: usize = 1_000_000;
        /// Largest built-in shape the server builds whatever `MAX_VERTICES` says (a
        /// resolution typo must not exhaust memory).
        MAX_SHAPE_VERTICES: usize = 2_000_000;
        /// Most triangles of a mesh, after polygons are split.
        MAX_FACES: usize = 2_000_000;
        /// Most eigenpairs of a basis.
        MAX_K: usize = 1000;
        /// Eigenbasis computations running at once.
        MAX_JOBS: usize = 2;
        /// Eigenbasis requests waiting in the queue.
        MAX_QUEUED: usize = 16;
        /// Longest an eigenbasis computation may run, in seconds.
        JOB_SECONDS: u64 = 600;
        /// A job nobody asked about for this many seconds is cancelled.
        JOB_IDLE_SECONDS: u64 = 60;
        /// Longest time of any other request, in seconds.
        REQUEST_SECONDS: u64 = 120;
        /// Requests in progress at once.
        MAX_REQUESTS: usize = 64;
        /// Inputs and analyses unused for this many seconds are dropped (0: never).
        IDLE_SECONDS: u64 = 3600;
    }
}

/// Default `m` of the heat method's time step `t = m h^2` (`h` the mean edge length;
/// potpourri3d's `t_coef`): geodesic field requests and [`crate::geodesic::GeodesicParams`].
pub const DEFAULT_GEODESIC_TIME_FACTOR: f64 = 1.0;

//! The server's configuration: address, port, limits and where the page's files come
//! from. The defaults are the library's ([`spectral_mesh::defaults::server`]).

use std::net::IpAddr;
use std::path::PathBuf;

use crate::limits::Limits;

/// Configuration of the server.
#[derive(Debug, Clone)]
pub struct ServeConfig {
    /// Address to listen on (default 127.0.0.1: another one must be asked for explicitly).
    pub host: IpAddr,
    /// Port (default 8000; 0 = any free port).
    pub port: u16,
    /// Memory, size, count and time limits (see [`Limits`]).
    pub limits: Limits,
    /// Serve `index.html`, `app.js`, `style.css` from this folder instead of the built-in copies.
    pub static_dir: Option<PathBuf>,
    /// Folder holding `three/` (npm's `node_modules`) to serve the page's 3D library from
    /// instead of the copy embedded at build time (`SPECTRAL_MESH_WEB_NODE_MODULES` does
    /// the same); default: the embedded copy, else `web/node_modules` of the source tree.
    pub node_modules: Option<PathBuf>,
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            host: spectral_mesh::defaults::server::HOST,
            port: spectral_mesh::defaults::server::PORT,
            limits: Limits::default(),
            static_dir: None,
            node_modules: None,
        }
    }
}

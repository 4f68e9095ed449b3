//! `spectral-mesh serve`: the interactive local web app.

use std::net::IpAddr;
use std::path::PathBuf;

use anyhow::Result;
use spectral_mesh_web::{ServeConfig, serve_blocking};

/// Arguments of `serve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Address to listen on. Only 127.0.0.1 (this machine) unless you ask for another.
    #[arg(long, default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// Port (0 picks a free one).
    #[arg(long, default_value_t = 8000)]
    pub port: u16,
    /// Memory cap of the mesh and eigenbasis cache, in MiB (least recently used out).
    #[arg(long, default_value_t = 1024)]
    pub cache_mib: usize,
    /// Largest accepted upload, in MiB.
    #[arg(long, default_value_t = 64)]
    pub max_upload_mib: usize,
    /// Folder holding npm's `node_modules` with three.js, served instead of the copy
    /// embedded in this binary at build time.
    #[arg(long)]
    pub node_modules: Option<PathBuf>,
}

/// Runs the server until interrupted.
pub fn run(args: Args) -> Result<()> {
    let cfg = ServeConfig {
        host: args.host,
        port: args.port,
        cache_bytes: args.cache_mib << 20,
        max_upload_bytes: args.max_upload_mib << 20,
        node_modules: args.node_modules,
        ..ServeConfig::default()
    };
    serve_blocking(cfg)?;
    Ok(())
}

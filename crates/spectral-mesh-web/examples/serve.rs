//! Runs the web app without the CLI: `cargo run -p spectral-mesh-web --example serve --
//! [--host 127.0.0.1] [--port 8000] [--memory-mib 2048] [--cache-mib 1024]
//! [--max-upload-mib 64]` (the other limits at their defaults; `spectral-mesh serve` sets
//! them all). Prints `spectral-mesh web app: URL` once listening (port 0 picks a free
//! port).

use spectral_mesh_web::{ServeConfig, serve_blocking};

fn main() {
    let mut cfg = ServeConfig::default();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let value = args.get(i + 1).cloned().unwrap_or_default();
        let mib = value.parse::<usize>().map(|v| v << 20);
        let l = &mut cfg.limits;
        let ok = match args[i].as_str() {
            "--host" => value.parse().map(|v| cfg.host = v).is_ok(),
            "--port" => value.parse().map(|v| cfg.port = v).is_ok(),
            "--memory-mib" => mib.map(|v| l.memory_bytes = v).is_ok(),
            "--cache-mib" => mib.map(|v| l.cache_bytes = v).is_ok(),
            "--max-upload-mib" => mib.map(|v| l.max_upload_bytes = v).is_ok(),
            _ => false,
        };
        if !ok {
            eprintln!("bad argument {} {}", args[i], value);
            std::process::exit(2);
        }
        i += 2;
    }
    if let Err(e) = serve_blocking(cfg) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

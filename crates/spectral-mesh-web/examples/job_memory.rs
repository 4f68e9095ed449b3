//! Peak memory of one eigenbasis job, as the server runs it, to fit the memory-admission
//! estimate (the library's `Analysis::basis_peak_bytes`): one (mesh, k) per process.
//!
//! `cargo run --release -p spectral-mesh-web --example job_memory -- MESH K [LAPLACIAN]`
//! prints one line of JSON: `n`, `m`, `k`, the resident memory before the job (mesh and
//! operators built), the peak during it (`VmHWM` after resetting it through
//! `/proc/self/clear_refs`), the factor's values, `Analysis::memory_bytes` after, and the
//! server's estimate. Linux only. MESH is a shape spec or a mesh file.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::sync::Arc;
use std::time::Instant;

use spectral_mesh::Laplacian;
use spectral_mesh::analysis::{Analysis, AnalysisOptions};
use spectral_mesh::cancel::CancelToken;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn status(key: &str) -> usize {
    let s = std::fs::read_to_string("/proc/self/status").unwrap();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap()
        * 1024
}

fn main() {
    let (args, spec, k) = common::spec_and_k("sphere:res=5", 100);
    let laplacian: Laplacian = args.get(2).map_or(Laplacian::Fem, |v| v.parse().unwrap());
    let mesh = if spectral_mesh::shapes::is_shape_spec(&spec) {
        spectral_mesh::shapes::build_str(&spec).unwrap()
    } else {
        spectral_mesh::io::read_mesh(std::path::Path::new(&spec))
            .unwrap()
            .mesh
    };
    let (n, m) = (mesh.n_vertices(), mesh.n_triangles());
    let analysis = Arc::new(Analysis::new(
        mesh,
        AnalysisOptions {
            laplacian,
            ..AnalysisOptions::default()
        },
    ));
    let held_before = analysis.memory_bytes();
    let estimate = analysis.basis_peak_bytes(k);
    let rss0 = status("VmRSS:");
    std::fs::write("/proc/self/clear_refs", "5").unwrap();
    let t = Instant::now();
    analysis.basis(k, &mut |_| {}, &CancelToken::new()).unwrap();
    let secs = t.elapsed().as_secs_f64();
    let peak = status("VmHWM:");
    let rss1 = status("VmRSS:");
    println!(
        "{}",
        serde_json::json!({
            "mesh": spec, "n": n, "m": m, "k": k, "seconds": secs,
            "rss_before": rss0, "peak": peak, "rss_after": rss1,
            "peak_increment": peak.saturating_sub(rss0),
            "held_before": held_before,
            "held_after": analysis.memory_bytes(),
            "factor_len": analysis.factor_len(),
            "columns": spectral_mesh::linalg::eigen::search_columns(n, k),
            "estimate": estimate,
        })
    );
}

//! Benchmark of the eigenbasis engine.
//!
//! `cargo run --release -p spectral-mesh --example bench_eigs -- MESH K [LAPLACIAN] [--out BASIS.npz] [--method auto|dense|block] [--block P] [--basis M] [--davidson] [--ks-plain]`
//!
//! Prints one line of `key=value` pairs: n, k, seconds (assembly excluded, factorization
//! included), iterations, solves, max residual, orthogonality error, peak RSS.

#![allow(clippy::unwrap_used, clippy::expect_used)]

/// The allocator of the `spectral-mesh` binary, so that the benchmark measures what users run.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::PathBuf;
use std::time::Instant;

use spectral_mesh::Operators;
use spectral_mesh::io::read_mesh;
use spectral_mesh::linalg::{SparseAlgorithm, SparseEigenOptions, sparse_generalized_eigen};
use spectral_mesh::operators::Laplacian;
use spectral_mesh::spectral::eigenbasis::{
    EigenMethod, EigenParams, EigenProgress, compute_eigenbasis,
};
use spectral_mesh::spectral::store::{BasisMeta, save_npz};

fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map(|kib| kib / 1024.0)
        .unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!(
            "usage: bench_eigs MESH K [LAPLACIAN] [--out BASIS.npz] [--method auto|dense|block] [--block P] [--verbose]"
        );
        std::process::exit(2);
    }
    let path = PathBuf::from(&args[0]);
    let k: usize = args[1].parse()?;
    let mut lap = Laplacian::Fem;
    let mut out: Option<PathBuf> = None;
    let mut params = EigenParams {
        k,
        ..Default::default()
    };
    let mut verbose = false;
    let mut raw_soft = false;
    let mut raw_krylov = false;
    let mut raw_davidson = false;
    let mut raw_basis = 0usize;
    let mut raw_plain = false;
    let mut i = 2;
    while i < args.len() {
        match args[i].as_str() {
            "--out" => {
                out = Some(PathBuf::from(&args[i + 1]));
                i += 1;
            }
            "--method" => {
                params.method = match args[i + 1].as_str() {
                    "dense" => EigenMethod::Dense,
                    "block" => EigenMethod::ShiftInvertBlock,
                    _ => EigenMethod::Auto,
                };
                i += 1;
            }
            "--block" => {
                params.block_size = args[i + 1].parse()?;
                i += 1;
            }
            "--verbose" => verbose = true,
            "--tol" => {
                params.tolerance = args[i + 1].parse()?;
                i += 1;
            }
            "--soft" => raw_soft = true,
            "--krylov" => raw_krylov = true,
            "--davidson" => raw_davidson = true,
            "--ks-plain" => raw_plain = true,
            "--basis" => {
                raw_basis = args[i + 1].parse()?;
                i += 1;
            }
            other => lap = other.parse()?,
        }
        i += 1;
    }
    let mesh = read_mesh(&path)?.mesh;
    let t0 = Instant::now();
    let ops = Operators::new(&mesh, lap);
    let t_ops = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let mut iterations = 0;
    let mut solves = 0;
    let mut t_fact = 0.0;
    let davidson = raw_soft || raw_krylov || raw_davidson;
    if davidson || raw_plain || raw_basis > 0 {
        // Solver experiments: call the sparse solver directly.
        let opts = SparseEigenOptions {
            k,
            tolerance: params.tolerance,
            block_size: params.block_size,
            max_basis: raw_basis,
            locking: false,
            krylov: raw_krylov,
            ks_plain: raw_plain,
            algorithm: if davidson {
                SparseAlgorithm::Davidson
            } else {
                SparseAlgorithm::KrylovSchur
            },
            ..Default::default()
        };
        let r = sparse_generalized_eigen(&ops.stiffness, &ops.mass, &opts, &mut |e| {
            if verbose {
                eprintln!("{:8.3}s {e:?}", t1.elapsed().as_secs_f64());
            }
        })?;
        println!(
            "raw davidson={davidson} soft={raw_soft} krylov={raw_krylov} ks_plain={raw_plain} basis={raw_basis} n={} k={k} seconds={:.3} iterations={} solves={} max_residual={:.2e} lambda_k={:.12e} peak_rss_mib={:.0}",
            ops.n(),
            t1.elapsed().as_secs_f64(),
            r.iterations,
            r.solves,
            r.residuals.iter().cloned().fold(0.0, f64::max),
            r.values[k - 1],
            peak_rss_mib()
        );
        return Ok(());
    }
    let basis = compute_eigenbasis(&ops, &params, &mut |e| {
        match &e {
            EigenProgress::Iteration { .. } if t_fact == 0.0 => t_fact = t1.elapsed().as_secs_f64(),
            EigenProgress::Finished {
                iterations: it,
                solves: so,
                ..
            } => {
                iterations = *it;
                solves = *so;
            }
            _ => {}
        }
        if verbose {
            eprintln!("{:8.3}s {e:?}", t1.elapsed().as_secs_f64());
        }
    })?;
    let secs = t1.elapsed().as_secs_f64();
    let maxres = basis.residuals.iter().cloned().fold(0.0, f64::max);
    let orth = basis.orthogonality_error();
    println!(
        "mesh={} n={} k={} laplacian={} seconds={:.3} assembly={:.3} first_iter_at={:.3} iterations={} solves={} max_residual={:.2e} orth_error={:.2e} lambda_k={:.12e} peak_rss_mib={:.0}",
        path.display(),
        ops.n(),
        k,
        lap,
        secs,
        t_ops,
        t_fact,
        iterations,
        solves,
        maxres,
        orth,
        basis.values[k - 1],
        peak_rss_mib()
    );
    if let Some(o) = out {
        let meta = BasisMeta::new(&basis, Some(&mesh), &params);
        save_npz(&basis, &o, &meta)?;
    }
    Ok(())
}

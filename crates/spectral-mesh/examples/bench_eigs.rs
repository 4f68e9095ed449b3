//! Benchmark of the eigenbasis engine.
//!
//! `cargo run --release -p spectral-mesh --example bench_eigs -- MESH K [LAPLACIAN] [--out BASIS.npz] [--method auto|dense|block] [--block P] [--basis M] [--davidson] [--ks-plain] [--raw] [--no-deflate] [--solver K1,K2,...] [--cancel-after S] [--copies N [--copy-scale F]] [--per-component] [--coarse] [--oracle M EPS] [--below]`
//!
//! Prints one line of `key=value` pairs: n, k, seconds (assembly excluded, factorization
//! included), iterations, solves, max residual, orthogonality error, peak RSS.
//!
//! `--coarse` starts the sparse solver from a coarse space (`SparseEigenOptions::coarse_start`);
//! `--oracle M EPS` from the first `M` exact eigenvectors (of a reference solve with `3M`
//! pairs, not timed) each perturbed by `EPS` times random combinations of all `3M`: an
//! upper bound of what any start subspace of that accuracy can save.
//!
//! `--below` takes the shift below the spectrum (the default shift of
//! [`spectral_mesh::linalg::default_shift`]) instead of the interior one the solver picks
//! from k = 24 on.
//!
//! `--per-component` compares the deflated solve of the whole mesh with a lower bound of
//! solving each connected component alone (see `per_component_bound`).
//!
//! MESH is a mesh file or a built-in shape spec (`irregular-double-torus:res=5`);
//! `--copies N` solves on N disjoint copies of it side by side (`--copy-scale F`: copy `c`
//! scaled by `F^c`, so that the copies' eigenvalues differ).
//!
//! `--solver K1,K2,...` instead asks one `EigenSolver` for `K1`, then `K2`, ... pairs (K is
//! then unused) and prints one line per solve: its seconds, the factorizations so far,
//! and a hash of the bits of the pairs (equal hashes: equal results). With
//! `--cancel-after S` each of those solves is cancelled from another thread after `S`
//! seconds, and the line gives the time from `cancel()` to the solve's return.

#![allow(clippy::unwrap_used, clippy::expect_used)]

/// The allocator of the `spectral-mesh` binary, so that the benchmark measures what users run.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod common;
use common::peak_rss_mib;

use std::path::PathBuf;
use std::time::Instant;

use spectral_mesh::Operators;
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::io::read_mesh;
use spectral_mesh::linalg::{SparseAlgorithm, SparseEigenOptions, sparse_generalized_eigen};
use spectral_mesh::operators::Laplacian;
use spectral_mesh::spectral::eigenbasis::{
    EigenMethod, EigenParams, EigenProgress, EigenSolver, compute_eigenbasis,
};
use spectral_mesh::spectral::store::{BasisMeta, save_npz};

/// `copies` disjoint copies of `mesh` in a row along x (`copies` connected components per
/// component of `mesh`), copy `c` scaled by `scale^c` (1: identical copies, whose
/// eigenvalues all repeat `copies` times).
fn side_by_side(
    mesh: &spectral_mesh::mesh::Mesh,
    copies: usize,
    scale: f64,
) -> Result<spectral_mesh::mesh::Mesh, Box<dyn std::error::Error>> {
    let p = mesh.positions();
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v[0]), hi.max(v[0]))
        });
    let width = (hi - lo).max(f64::MIN_POSITIVE);
    let mut pos = Vec::with_capacity(p.len() * copies);
    let mut tri = Vec::with_capacity(mesh.triangles().len() * copies);
    let mut at = 0.0;
    for c in 0..copies {
        let base = pos.len();
        let f = scale.powi(c as i32);
        pos.extend(p.iter().map(|v| [at + f * (v[0] - lo), f * v[1], f * v[2]]));
        at += 1.5 * f * width;
        tri.extend(
            mesh.triangles()
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    Ok(spectral_mesh::mesh::Mesh::new(pos, tri)?)
}

/// The deflated solve of the whole mesh against a lower bound of solving each component
/// separately and merging: each component is solved alone for exactly the number of
/// pairs the whole solve found on it (known only afterwards, so the real per-component
/// method would need more), and the times are summed. Components left without a pair
/// cost nothing in this bound.
fn per_component_bound(
    ops: &Operators,
    k: usize,
    params: &EigenParams,
) -> Result<(), Box<dyn std::error::Error>> {
    use spectral_mesh::linalg::ComponentNullSpace;
    let (s, b) = (&ops.stiffness, &ops.mass);
    let opts = SparseEigenOptions {
        k,
        tolerance: params.tolerance,
        ..Default::default()
    };
    let t = Instant::now();
    let whole = sparse_generalized_eigen(s, b, &opts, &mut |_| {})?;
    let t_whole = t.elapsed().as_secs_f64();
    let n = ops.n();
    let comps = ComponentNullSpace::find(s, b, opts.effective_tolerance())?;
    let bx = spectral_mesh::linalg::sym_spmm(b, &whole.vectors, k);
    let mut t_parts = 0.0;
    let mut solved = 0;
    let mut lambda_k: f64 = 0.0;
    for c in 0..comps.count() {
        let verts = comps.vertices(c);
        // Pairs of the whole solve on this component: the B-mass of the first k vectors
        // there (the trace of the projector; vectors of eigenvalues shared by several
        // components spread over them), rounded.
        let share: f64 = (0..k)
            .map(|j| {
                verts
                    .iter()
                    .map(|&v| whole.vectors[j * n + v] * bx[j * n + v])
                    .sum::<f64>()
            })
            .sum();
        let kc = share.round() as usize;
        if kc == 0 {
            continue;
        }
        let (sc, bc) = (s.submatrix(verts, verts), b.submatrix(verts, verts));
        let t = Instant::now();
        let vals = if verts.len() <= 300 || 3 * kc > verts.len() {
            let (v, _) = spectral_mesh::linalg::dense_generalized_eigen(&sc, &bc)?;
            v[..kc].to_vec()
        } else {
            let o = SparseEigenOptions {
                k: kc,
                ..opts.clone()
            };
            sparse_generalized_eigen(&sc, &bc, &o, &mut |_| {})?.values
        };
        t_parts += t.elapsed().as_secs_f64();
        lambda_k = lambda_k.max(vals[kc - 1]);
        solved += 1;
    }
    println!(
        "per_component n={n} k={k} components={} whole_seconds={t_whole:.3} whole_solves={} parts_solved={solved} parts_seconds_bound={t_parts:.3} lambda_k_whole={:.12e} lambda_k_parts={lambda_k:.12e}",
        comps.count(),
        whole.solves,
        whole.values[k - 1]
    );
    Ok(())
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
    let mut raw_no_deflate = false;
    let mut per_component = false;
    let mut raw = false;
    let mut solver_ks: Vec<usize> = Vec::new();
    let mut copies = 1usize;
    let mut copy_scale = 1.0f64;
    let mut cancel_after: Option<f64> = None;
    let mut oracle: Option<(usize, f64)> = None;
    let mut coarse = false;
    let mut below = false;
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
            "--no-deflate" => raw_no_deflate = true,
            "--raw" => raw = true,
            "--below" => {
                below = true;
                raw = true;
            }
            "--coarse" => {
                coarse = true;
                raw = true;
            }
            "--per-component" => per_component = true,
            "--basis" => {
                raw_basis = args[i + 1].parse()?;
                i += 1;
            }
            "--oracle" => {
                oracle = Some((args[i + 1].parse()?, args[i + 2].parse()?));
                raw = true;
                i += 2;
            }
            "--cancel-after" => {
                cancel_after = Some(args[i + 1].parse()?);
                i += 1;
            }
            "--copy-scale" => {
                copy_scale = args[i + 1].parse()?;
                i += 1;
            }
            "--copies" => {
                copies = args[i + 1].parse()?;
                i += 1;
            }
            "--solver" => {
                for v in args[i + 1].split(',') {
                    solver_ks.push(v.parse()?);
                }
                i += 1;
            }
            other => lap = other.parse()?,
        }
        i += 1;
    }
    let mesh = if spectral_mesh::shapes::is_shape_spec(&args[0]) {
        spectral_mesh::shapes::build_str(&args[0])?
    } else {
        read_mesh(&path)?.mesh
    };
    let mesh = if copies > 1 {
        side_by_side(&mesh, copies, copy_scale)?
    } else {
        mesh
    };
    let t0 = Instant::now();
    let ops = Operators::new(&mesh, lap);
    let t_ops = t0.elapsed().as_secs_f64();
    if per_component {
        return per_component_bound(&ops, k, &params);
    }
    if !solver_ks.is_empty() {
        let mut solver = EigenSolver::new(std::sync::Arc::new(ops), params.clone());
        let cancel = CancelToken::new();
        for &ks in &solver_ks {
            let t = Instant::now();
            if let Some(after) = cancel_after {
                // Cancel from another thread after `after` seconds; report how long the
                // solve took to return from there.
                let token = CancelToken::new();
                let remote = token.clone();
                let canceller = std::thread::spawn(move || {
                    std::thread::sleep(std::time::Duration::from_secs_f64(after));
                    remote.cancel();
                    Instant::now()
                });
                let r = solver.solve(ks, &mut |_| {}, &token);
                let back = Instant::now();
                let at = canceller.join().map_err(|_| "canceller thread")?;
                println!(
                    "cancel mesh={} k={ks} cancel_at={after:.3} outcome={} latency_seconds={:.3} factorizations={}",
                    path.display(),
                    match &r {
                        Ok(_) => "finished".to_string(),
                        Err(e) => format!("{e:?}"),
                    },
                    back.saturating_duration_since(at).as_secs_f64(),
                    solver.factorizations()
                );
                continue;
            }
            let basis = solver.solve(ks, &mut |_| {}, &cancel)?;
            let secs = t.elapsed().as_secs_f64();
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            for v in basis.values.iter().chain(&basis.vectors) {
                v.to_bits().hash(&mut h);
            }
            println!(
                "solver mesh={} n={} k={ks} seconds={secs:.3} factorizations={} lambda_k={:.12e} bits={:016x} peak_rss_mib={:.0}",
                path.display(),
                basis.n,
                solver.factorizations(),
                basis.values[ks - 1],
                h.finish(),
                peak_rss_mib()
            );
        }
        return Ok(());
    }
    let t1 = Instant::now();
    let mut iterations = 0;
    let mut solves = 0;
    let mut t_fact = 0.0;
    let davidson = raw_soft || raw_krylov || raw_davidson;
    if raw || davidson || raw_plain || raw_no_deflate || raw_basis > 0 {
        // Solver experiments: call the sparse solver directly.
        let start_vectors = match oracle {
            Some((m, eps)) => {
                // Experiment: start from the first m exact eigenvectors (of a reference
                // solve with 3m pairs), each perturbed by eps times random combinations
                // of all 3m.
                let r3 = 3 * m;
                let o = SparseEigenOptions {
                    k: r3,
                    ..Default::default()
                };
                let refr = sparse_generalized_eigen(&ops.stiffness, &ops.mass, &o, &mut |_| {})?;
                let n = ops.n();
                let mut x0 = vec![0.0; n * m];
                let mut seed = 12345u64;
                let mut rnd = || {
                    seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
                };
                for i in 0..m {
                    let col = &mut x0[i * n..(i + 1) * n];
                    col.copy_from_slice(&refr.vectors[i * n..(i + 1) * n]);
                    for j in 0..r3 {
                        let g = eps * rnd() * (3.0 / r3 as f64).sqrt();
                        for (x, &u) in col.iter_mut().zip(&refr.vectors[j * n..(j + 1) * n]) {
                            *x += g * u;
                        }
                    }
                }
                Some(std::sync::Arc::new(x0))
            }
            None => None,
        };
        let t1 = Instant::now();
        let opts = SparseEigenOptions {
            start_vectors,
            coarse_start: coarse,
            k,
            tolerance: params.tolerance,
            block_size: params.block_size,
            max_basis: raw_basis,
            shift: below.then(|| spectral_mesh::linalg::default_shift(&ops.stiffness, &ops.mass)),
            locking: false,
            krylov: raw_krylov,
            ks_plain: raw_plain,
            deflate: !raw_no_deflate,
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
            "raw davidson={davidson} soft={raw_soft} krylov={raw_krylov} ks_plain={raw_plain} deflate={} basis={raw_basis} n={} k={k} seconds={:.3} iterations={} solves={} max_residual={:.2e} lambda_k={:.12e} peak_rss_mib={:.0}",
            !raw_no_deflate,
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

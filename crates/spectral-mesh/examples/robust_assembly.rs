//! Robust Laplacian of a mesh or a point cloud, for benchmarks and the point-cloud study.
//!
//! `cargo run --release -p spectral-mesh --example robust_assembly -- FILE [--neighbors K]
//! [--eigs K] [--mollify F] [--use-normals] [--multiplicity | --interleaved | --consensus-only] [--dump TRIANGLES.off]`
//!
//! Reads FILE (a mesh, or points: `.xyz`/`.pts`/`.txt`, a PLY without faces), assembles the
//! robust pair (S, B) (mesh: `robust_laplacian`; points: `point_cloud_laplacian`), writes
//! nothing, and prints one JSON line: n, read and assembly seconds, total mass, nnz(S),
//! peak RSS in MiB, the pipeline's counts and, with `--eigs K`, the K smallest generalized
//! eigenvalues.

#![allow(clippy::unwrap_used, clippy::expect_used)]

/// The allocator of the `spectral-mesh` binary, so that the benchmark measures what users run.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod common;
use common::peak_rss_mib;

use std::path::PathBuf;
use std::time::Instant;

use spectral_mesh::io::{Input, read_input};
use spectral_mesh::operators::{
    Laplacian, NormalSource, Operators, PointCloudParams, RobustParams, TriangleUnion,
    point_cloud_laplacian, point_cloud_triangles, robust_laplacian,
};
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut file = None;
    let mut neighbors = PointCloudParams::default().neighbors;
    let mut eigs = 0usize;
    let mut mollify = RobustParams::default().mollify_factor;
    let mut normals = NormalSource::Estimate;
    let mut union = TriangleUnion::Consensus;
    let mut dump: Option<PathBuf> = None;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--neighbors" => {
                i += 1;
                neighbors = args[i].parse()?;
            }
            "--eigs" => {
                i += 1;
                eigs = args[i].parse()?;
            }
            "--mollify" => {
                i += 1;
                mollify = args[i].parse()?;
            }
            "--use-normals" => normals = NormalSource::FromCloud,
            "--multiplicity" => union = TriangleUnion::Multiplicity,
            "--interleaved" => union = TriangleUnion::Interleaved,
            "--consensus-only" => union = TriangleUnion::ConsensusOnly,
            "--dump" => {
                i += 1;
                dump = Some(PathBuf::from(&args[i]));
            }
            a => file = Some(PathBuf::from(a)),
        }
        i += 1;
    }
    let file = file.ok_or("usage: robust_assembly FILE [--neighbors K] [--eigs K]")?;
    let t0 = Instant::now();
    let input = read_input(&file)?;
    let read_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let (ops, counts) = match &input {
        Input::Mesh(m) => {
            let r = robust_laplacian(
                &m.mesh,
                &RobustParams {
                    mollify_factor: mollify,
                    ..Default::default()
                },
            )?;
            let c = serde_json::to_value(&r.stats)?;
            (
                Operators {
                    laplacian: Laplacian::Robust,
                    stiffness: r.stiffness,
                    mass: r.mass,
                },
                c,
            )
        }
        Input::Points(p) => {
            let params = PointCloudParams {
                neighbors,
                mollify_factor: mollify,
                normals,
                union,
                ..Default::default()
            };
            let r = point_cloud_laplacian(&p.cloud, &params)?;
            if let Some(d) = &dump {
                let t = point_cloud_triangles(&p.cloud, &params)?;
                let mesh = spectral_mesh::Mesh::new(p.cloud.positions().to_vec(), t)?;
                spectral_mesh::io::write_mesh(d, &mesh, &Default::default())?;
            }
            let mut c = serde_json::to_value(&r.stats)?;
            if let Some(o) = c.as_object_mut() {
                let iso = r.stats.isolated_points.len();
                o.insert("isolated_points".into(), iso.into());
            }
            (
                Operators {
                    laplacian: Laplacian::Robust,
                    stiffness: r.stiffness,
                    mass: r.mass,
                },
                c,
            )
        }
    };
    let assembly_s = t1.elapsed().as_secs_f64();
    let mass: f64 = ops.mass.values().iter().sum();
    let mut out = serde_json::json!({
        "file": file.display().to_string(),
        "n": ops.n(),
        "read_s": read_s,
        "assembly_s": assembly_s,
        "mass": mass,
        "nnz_s": ops.stiffness.nnz(),
        "counts": counts,
        "peak_rss_mib": peak_rss_mib(),
    });
    if eigs > 0 {
        let t2 = Instant::now();
        let basis = compute_eigenbasis(
            &ops,
            &EigenParams {
                k: eigs,
                ..Default::default()
            },
            &mut |_| {},
        )?;
        out["eigs_s"] = t2.elapsed().as_secs_f64().into();
        out["eigenvalues"] = basis.values.clone().into();
    }
    println!("{out}");
    Ok(())
}

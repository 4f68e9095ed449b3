//! Why the server runs field work on threads of its own: the same distance kernel timed
//! on a rayon pool made before an eigensolver run, on rayon's global pool (where the
//! solver ran) and on a pool made after it.
//!
//! `cargo run --release -p spectral-mesh-web --example thread_probe -- [SHAPE] [K]`
//! (defaults `torus:res=5`, 200).

#![allow(clippy::unwrap_used)]

mod common;

use std::time::Instant;

use spectral_mesh::analysis::{Analysis, AnalysisOptions};
use spectral_mesh::spectral::Eigenbasis;
use spectral_mesh::spectral::distances::distances_from;
use spectral_mesh::spectral::filters::Filter;

/// Median of 9 bi-harmonic distance fields, in ms.
fn distance_ms(b: &Eigenbasis) -> f64 {
    let mut t: Vec<f64> = (0..9)
        .map(|i| {
            let s = Instant::now();
            std::hint::black_box(distances_from(b, i, &Filter::Biharmonic).unwrap());
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[4]
}

fn main() {
    let (_, spec, k) = common::spec_and_k("torus:res=5", 200);
    let pool = || rayon::ThreadPoolBuilder::new().build().unwrap();
    let early = pool();
    let an = Analysis::new(
        spectral_mesh::shapes::build_str(&spec).unwrap(),
        AnalysisOptions::default(),
    );
    let b = an.basis(k, &mut |_| {}, &Default::default()).unwrap();
    println!("{spec}, k = {k}: distance field, median of 9, after an eigensolver run:");
    println!(
        "  pool made before the solver ran: {:.1} ms",
        early.install(|| distance_ms(&b))
    );
    println!(
        "  rayon's global pool (the solver's): {:.1} ms",
        distance_ms(&b)
    );
    println!(
        "  pool made after the solver ran: {:.1} ms",
        pool().install(|| distance_ms(&b))
    );
}

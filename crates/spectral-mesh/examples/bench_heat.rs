//! Times `HeatSolver` queries (one basis function `K_t e_i` each) on a basis that is
//! computed once: the interactive use of the heat kernel.
//!
//! ```text
//! cargo run --release -p spectral-mesh --example bench_heat -- [SHAPE] [K] [QUERIES]
//! ```
//! Default: `3torus:res=5` (102,396 vertices), k = 200, 50 queries at random anchors and
//! times. Prints the basis time and the median, min and max query time.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Instant;

use spectral_mesh::shapes::build_str;
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use spectral_mesh::spectral::heat::{HeatSolver, Kernel, ScaleNormalization};
use spectral_mesh::{Laplacian, Operators};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = args.get(1).map(String::as_str).unwrap_or("3torus:res=5");
    let k: usize = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(200);
    let q: usize = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(50);
    let mesh = build_str(shape).unwrap();
    let n = mesh.n_vertices();
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let t0 = Instant::now();
    let params = EigenParams {
        k,
        ..Default::default()
    };
    let basis = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
    let basis_s = t0.elapsed().as_secs_f64();
    let solver = HeatSolver::new(&basis, Kernel::Wfem, ScaleNormalization::UnitArea);
    let mut times = Vec::with_capacity(q);
    let mut state = 0x9e3779b97f4a7c15u64;
    let mut checksum = 0.0;
    for i in 0..q {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let anchor = (state >> 33) as usize % n;
        let t = 1e-3 * (1.0 + i as f64);
        let t1 = Instant::now();
        let f = solver.basis_function(anchor, t).unwrap();
        times.push(t1.elapsed().as_secs_f64() * 1e3);
        checksum += f[anchor];
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{shape}: n = {n}, k = {k}; basis {basis_s:.2} s; {q} queries: median {:.2} ms, min {:.2} ms, max {:.2} ms (checksum {checksum:.3e})",
        times[q / 2],
        times[0],
        times[q - 1]
    );
}

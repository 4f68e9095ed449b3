//! Benchmark of the triangular solves alone: the factor of `S - sigma B` (FEM) of a mesh,
//! then `REPS` solves of a block of `C` right-hand sides on the library's thread pool.
//!
//! `cargo run --release -p spectral-mesh --example bench_solve -- MESH [C] [REPS] [STREAM_MB]`
//!
//! Prints one line: n, the factor's values, the block width, and the minimum and median
//! milliseconds of one block's solve (gather, forward and backward sweeps, scatter).
//! `STREAM_MB` (default 0): before each solve, sum a buffer of that many MB, as the
//! eigensolver's products with its basis do between two solves (the factor then no longer
//! sits in the cache).

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::time::Instant;

use spectral_mesh::Operators;
use spectral_mesh::io::read_mesh;
use spectral_mesh::linalg::ShiftInvert;
use spectral_mesh::operators::Laplacian;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: bench_solve MESH [C] [REPS] [STREAM_MB]")?;
    let c: usize = args.get(1).map_or(Ok(4), |s| s.parse())?;
    let reps: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let stream_mb: usize = args.get(3).map_or(Ok(0), |s| s.parse())?;
    let stream: Vec<f64> = (0..stream_mb * 131_072).map(|i| i as f64).collect();
    let mesh = read_mesh(std::path::Path::new(path))?.mesh;
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let op = ShiftInvert::new(&ops.stiffness, &ops.mass, None, &mut |_| {})?;
    let chol = op.cholesky();
    let n = chol.n();
    let rhs: Vec<f64> = (0..n * c)
        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
        .collect();
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        std::hint::black_box(stream.iter().sum::<f64>());
        let mut b = rhs.clone();
        let t = Instant::now();
        chol.solve_many_in_place(&mut b, c);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(&b);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "n={n} factor={} c={c} reps={reps} min_ms={:.3} median_ms={:.3}",
        chol.factor_len(),
        times[0],
        times[reps / 2]
    );
    Ok(())
}

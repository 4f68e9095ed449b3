#![allow(missing_docs, clippy::unwrap_used)]
use spectral_mesh::io::read_mesh;
use spectral_mesh::operators::{RobustParams, robust_laplacian};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let m = read_mesh(std::path::Path::new(&a[1])).unwrap().mesh;
    let tol: f64 = a[2].parse().unwrap();
    let r = robust_laplacian(
        &m,
        &RobustParams {
            delaunay_tolerance: tol,
            ..Default::default()
        },
    )
    .unwrap();
    println!("{:?}", r.stats);
    let d = r.mass.diag();
    println!("mass {:?}", &d[..d.len().min(19)]);
    let mut s = Vec::new();
    for c in 0..r.stiffness.ncols() {
        let (rows, vals) = r.stiffness.col(c);
        for (&rr, &v) in rows.iter().zip(vals) {
            if rr != c && v > 0.0 {
                s.push((rr, c, v));
            }
        }
    }
    println!("positive offdiag {:?}", s);
}

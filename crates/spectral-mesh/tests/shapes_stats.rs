//! Diagnostic: prints statistics of every shape (run with `--ignored --nocapture`).

#![allow(clippy::unwrap_used)]

use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::shapes::{build_str, shape_names};

fn min_angle_deg(m: &spectral_mesh::Mesh) -> f64 {
    use spectral_mesh::mesh::{dot, norm, sub};
    let mut best = f64::INFINITY;
    for t in 0..m.n_triangles() {
        let c = m.corners(t);
        for k in 0..3 {
            let (a, b, d) = (c[k], c[(k + 1) % 3], c[(k + 2) % 3]);
            let u = sub(b, a);
            let v = sub(d, a);
            let cos = dot(u, v) / (norm(u) * norm(v));
            best = best.min(cos.clamp(-1.0, 1.0).acos().to_degrees());
        }
    }
    best
}

#[test]
#[ignore]
fn print_stats() {
    let res: Vec<u32> = std::env::var("SHAPE_RES")
        .ok()
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or(vec![3]);
    for info in shape_names() {
        for &r in &res {
            let spec = format!("{}:res={}", info.name, r);
            let m = build_str(&spec).unwrap();
            let t = Topology::new(&m);
            let a = m.triangle_areas();
            let amax = a.iter().cloned().fold(0.0, f64::max);
            let amin = a.iter().cloned().fold(f64::INFINITY, f64::min);
            let vol: f64 = (0..m.n_triangles())
                .map(|i| {
                    let [p, q, s] = m.corners(i);
                    spectral_mesh::mesh::dot(p, spectral_mesh::mesh::cross(q, s)) / 6.0
                })
                .sum();
            println!(
                "{spec:28} V={:7} F={:7} chi={:3} genus={:?} loops={} nm_e={} nm_v={} incons={} vol={:.4} area_ratio={:8.1} min_angle={:.2}",
                m.n_vertices(),
                m.n_triangles(),
                t.euler_characteristic(),
                t.components[0].genus,
                t.boundary_loops.len(),
                t.non_manifold_edges.len(),
                t.non_manifold_vertices.len(),
                t.inconsistently_oriented_edges,
                vol,
                amax / amin,
                min_angle_deg(&m)
            );
        }
    }
}

#[test]
#[ignore]
fn dump_off() {
    let dir = std::env::var("SHAPE_DUMP").unwrap_or("/tmp/shapes".into());
    std::fs::create_dir_all(&dir).unwrap();
    for info in shape_names() {
        let m = build_str(&format!("{}:res=2", info.name)).unwrap();
        let mut s = format!("OFF\n{} {} 0\n", m.n_vertices(), m.n_triangles());
        for p in m.positions() {
            s += &format!("{} {} {}\n", p[0], p[1], p[2]);
        }
        for t in m.triangles() {
            s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
        }
        std::fs::write(format!("{dir}/{}.off", info.name), s).unwrap();
    }
}

#[test]
#[ignore]
fn where_extremes() {
    let m = build_str("3torus:res=4").unwrap();
    let a = m.triangle_areas();
    let mut idx: Vec<usize> = (0..a.len()).collect();
    idx.sort_by(|&i, &j| a[i].partial_cmp(&a[j]).unwrap());
    for &t in idx.iter().take(3).chain(idx.iter().rev().take(3)) {
        let c = m.corners(t);
        println!("area {:.3e} at {:?}", a[t], c[0]);
    }
}

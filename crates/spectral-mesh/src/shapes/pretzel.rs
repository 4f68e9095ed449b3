//! Smooth genus-g surfaces: a quad "plate with g holes in a row", Catmull-Clark subdivided,
//! vertices moved to their limit positions, each quad split along its shorter diagonal.

use std::collections::HashMap;

use super::parametric::Arrays;
use crate::mesh::{add, norm, scale, sub};

/// Width of the bars between and around the holes.
const BAR: f64 = 1.0;
/// Width of a hole.
const HOLE: f64 = 2.2;
/// Half thickness of the plate.
const HALF_THICK: f64 = 0.5;
/// How far the middle ring of a wall bulges outwards.
const BULGE: f64 = 0.25;

/// Closed quad control mesh of genus `g`: a grid of `(2g+1) x 3` cells with the cells
/// `(2i+1, 1)` removed, thickened into a top, a bottom and two-quad-high walls.
/// It has `26g + 22` quads: `10g + 6` on top and bottom, `16g + 16` on the walls.
pub(crate) fn control_mesh(g: usize) -> (Vec<[f64; 3]>, Vec<[usize; 4]>) {
    let nx = 2 * g + 1;
    let ny = 3;
    let widths = |n: usize| -> Vec<f64> {
        let mut x = vec![0.0];
        for i in 0..n {
            let w = if i % 2 == 0 { BAR } else { HOLE };
            x.push(x[i] + w);
        }
        let c = 0.5 * x[n];
        x.into_iter().map(|v| v - c).collect()
    };
    let xs = widths(nx);
    let ys = widths(ny);
    let plate = |i: isize, j: isize| -> bool {
        i >= 0 && j >= 0 && (i as usize) < nx && (j as usize) < ny && !(j == 1 && i % 2 == 1)
    };
    let gw = nx + 1;
    let gid = |i: usize, j: usize| j * gw + i;
    let n_grid = gw * (ny + 1);
    let mut pos: Vec<[f64; 3]> = Vec::with_capacity(3 * n_grid);
    for z in [HALF_THICK, -HALF_THICK] {
        for &y in &ys {
            for &x in &xs {
                pos.push([x, y, z]);
            }
        }
    }
    let mut quads = Vec::new();
    // Directed boundary edges (a -> b, plate on the left seen from +z).
    let mut boundary: Vec<(usize, usize)> = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if !plate(i as isize, j as isize) {
                continue;
            }
            let c = [gid(i, j), gid(i + 1, j), gid(i + 1, j + 1), gid(i, j + 1)];
            quads.push(c);
            quads.push([c[3] + n_grid, c[2] + n_grid, c[1] + n_grid, c[0] + n_grid]);
            let (ii, jj) = (i as isize, j as isize);
            let across = [(ii, jj - 1), (ii + 1, jj), (ii, jj + 1), (ii - 1, jj)];
            for (k, &(ni, nj)) in across.iter().enumerate() {
                if !plate(ni, nj) {
                    boundary.push((c[k], c[(k + 1) % 4]));
                }
            }
        }
    }
    // Middle ring: one vertex per boundary grid point, pushed outwards in the plane.
    let mut outward: Vec<[f64; 3]> = vec![[0.0; 3]; n_grid];
    for &(a, b) in &boundary {
        let d = sub(pos[b], pos[a]);
        let n = [d[1], -d[0], 0.0];
        let l = norm(n);
        outward[a] = add(outward[a], scale(n, 1.0 / l));
        outward[b] = add(outward[b], scale(n, 1.0 / l));
    }
    let mut mid: Vec<usize> = vec![usize::MAX; n_grid];
    for &(a, _) in &boundary {
        if mid[a] == usize::MAX {
            mid[a] = pos.len();
            let o = outward[a];
            let l = norm(o);
            let o = if l > 0.0 { scale(o, BULGE / l) } else { o };
            pos.push([pos[a][0] + o[0], pos[a][1] + o[1], 0.0]);
        }
    }
    for &(a, b) in &boundary {
        quads.push([b, a, mid[a], mid[b]]);
        quads.push([mid[b], mid[a], a + n_grid, b + n_grid]);
    }
    (pos, quads)
}

/// One Catmull-Clark step on a closed quad mesh (vertices, then edge points, then face points).
fn catmull_clark(pos: &[[f64; 3]], quads: &[[usize; 4]]) -> (Vec<[f64; 3]>, Vec<[usize; 4]>) {
    let nv = pos.len();
    let nf = quads.len();
    let mut index: HashMap<(usize, usize), usize> = HashMap::with_capacity(2 * nf);
    let mut edges: Vec<[usize; 2]> = Vec::with_capacity(2 * nf);
    let mut edge_faces: Vec<[usize; 2]> = Vec::with_capacity(2 * nf);
    let mut face_edges: Vec<[usize; 4]> = Vec::with_capacity(nf);
    for (f, q) in quads.iter().enumerate() {
        let mut fe = [0; 4];
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            let key = (a.min(b), a.max(b));
            let e = *index.entry(key).or_insert_with(|| {
                edges.push([key.0, key.1]);
                edge_faces.push([usize::MAX; 2]);
                edges.len() - 1
            });
            if edge_faces[e][0] == usize::MAX {
                edge_faces[e][0] = f;
            } else {
                edge_faces[e][1] = f;
            }
            fe[k] = e;
        }
        face_edges.push(fe);
    }
    let ne = edges.len();
    let face_pt: Vec<[f64; 3]> = quads
        .iter()
        .map(|q| {
            let s = q.iter().fold([0.0; 3], |s, &v| add(s, pos[v]));
            scale(s, 0.25)
        })
        .collect();
    let edge_pt: Vec<[f64; 3]> = (0..ne)
        .map(|e| {
            let [a, b] = edges[e];
            let [f0, f1] = edge_faces[e];
            if f1 == usize::MAX {
                scale(add(pos[a], pos[b]), 0.5)
            } else {
                scale(
                    add(add(pos[a], pos[b]), add(face_pt[f0], face_pt[f1])),
                    0.25,
                )
            }
        })
        .collect();
    let mut fsum = vec![[0.0; 3]; nv];
    let mut fcount = vec![0usize; nv];
    for (f, q) in quads.iter().enumerate() {
        for &v in q {
            fsum[v] = add(fsum[v], face_pt[f]);
            fcount[v] += 1;
        }
    }
    let mut esum = vec![[0.0; 3]; nv];
    let mut ecount = vec![0usize; nv];
    for &[a, b] in &edges {
        let m = scale(add(pos[a], pos[b]), 0.5);
        esum[a] = add(esum[a], m);
        esum[b] = add(esum[b], m);
        ecount[a] += 1;
        ecount[b] += 1;
    }
    let mut out = Vec::with_capacity(nv + ne + nf);
    for v in 0..nv {
        let n = ecount[v] as f64;
        if ecount[v] == 0 || fcount[v] == 0 {
            out.push(pos[v]);
            continue;
        }
        let f = scale(fsum[v], 1.0 / fcount[v] as f64);
        let r = scale(esum[v], 1.0 / n);
        let p = add(add(f, scale(r, 2.0)), scale(pos[v], n - 3.0));
        out.push(scale(p, 1.0 / n));
    }
    out.extend_from_slice(&edge_pt);
    out.extend_from_slice(&face_pt);
    let mut nq = Vec::with_capacity(4 * nf);
    for (f, q) in quads.iter().enumerate() {
        let fe = face_edges[f];
        for k in 0..4 {
            nq.push([q[k], nv + fe[k], nv + ne + f, nv + fe[(k + 3) % 4]]);
        }
    }
    (out, nq)
}

/// Moves every vertex of a closed quad mesh to its Catmull-Clark limit position
/// `(n^2 v + 4 sum(edge neighbours) + sum(diagonal neighbours)) / (n (n + 5))`.
fn limit_positions(pos: &[[f64; 3]], quads: &[[usize; 4]]) -> Vec<[f64; 3]> {
    let nv = pos.len();
    let mut acc = vec![[0.0; 3]; nv];
    let mut valence = vec![0usize; nv];
    for q in quads {
        for k in 0..4 {
            let v = q[k];
            // Each edge v -> next is seen from exactly one quad in this direction, so the
            // edge neighbour q[k+1] is counted once per edge; the diagonal once per quad.
            let e = q[(k + 1) % 4];
            let d = q[(k + 2) % 4];
            acc[v] = add(acc[v], add(scale(pos[e], 4.0), pos[d]));
            valence[v] += 1;
        }
    }
    (0..nv)
        .map(|v| {
            let n = valence[v] as f64;
            if valence[v] == 0 {
                return pos[v];
            }
            scale(add(scale(pos[v], n * n), acc[v]), 1.0 / (n * (n + 5.0)))
        })
        .collect()
}

/// Smooth closed surface of genus `g >= 1` after `res` Catmull-Clark steps.
/// Vertex count `chi + F0 * 4^res` with `chi = 2 - 2g` and `F0` the control quads.
pub(crate) fn pretzel(g: usize, res: u32) -> Arrays {
    let (mut pos, mut quads) = control_mesh(g);
    for _ in 0..res {
        let (p, q) = catmull_clark(&pos, &quads);
        pos = p;
        quads = q;
    }
    let pos = limit_positions(&pos, &quads);
    let mut tris = Vec::with_capacity(2 * quads.len());
    for q in &quads {
        let d02 = norm(sub(pos[q[2]], pos[q[0]]));
        let d13 = norm(sub(pos[q[3]], pos[q[1]]));
        if d02 <= d13 {
            tris.push([q[0], q[1], q[2]]);
            tris.push([q[0], q[2], q[3]]);
        } else {
            tris.push([q[0], q[1], q[3]]);
            tris.push([q[1], q[2], q[3]]);
        }
    }
    (pos, tris)
}
